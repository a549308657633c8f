"""Tracker placement beats the manual positions 1-3 of Aguado et al. 2016 (GUM and MC)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mtmc.cli.main import main
from mtmc.study import load_study
from mtmc.verification.placement import place
from mtmc.verification.simulate import (
    Verification,
    VerificationModel,
    gum_verification,
    reference_identification,
    simulate,
)

STUDY = Path(__file__).resolve().parents[2] / "examples" / "studies" / "aguado2016.toml"


def test_placement_beats_positions_1_to_3() -> None:
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos4")
    assert st.limits is not None
    r = place(ver, st.limits, references=st.trackers)
    for name in ("pos1", "pos2", "pos3"):
        assert r.u_best < r.reference[name], (name, r.u_best, r.reference)
    lo, hi = st.limits.height
    assert lo <= r.best.position[2] <= hi
    # the GUM score against the Monte Carlo of whole verifications at the best position
    best = st.verification("mesh96", "pos4")
    mc = simulate(
        type(best)(best.model, best.q, r.best, best.true_errors, fixed=best.fixed), 400, 3
    )
    assert np.isclose(np.mean(mc.point_u), r.u_best, rtol=0.1)


def test_placement_score_is_the_gum_of_a_verification_of_the_nominal_machine() -> None:
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos1")
    assert st.limits is not None
    nominal = Verification(ver.model, ver.q, ver.tracker, {}, pose=ver.pose, fixed=ver.fixed)
    r = place(nominal, st.limits, references={"pos1": ver.tracker}, n_xy=2, heights=1, refine=0)
    gum = gum_verification(VerificationModel.build(nominal, reference_identification(nominal)))
    assert np.isclose(np.mean(gum.point_u), r.reference["pos1"], rtol=1e-12, atol=0.0)


def test_place_cli_json(capsys) -> None:  # type: ignore[no-untyped-def]
    text = STUDY.read_text()
    assert "[tracker.limits]" in text
    args = ["verify", "place", str(STUDY), "--trials", "0", "--grid", "3", "--refine", "5"]
    assert main([*args, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["best"]) >= {"x", "y", "z", "euler_deg", "u_um"}
    assert set(d["reference"]) == {"pos1", "pos2", "pos3", "pos4"}
    assert d["candidates"] > 0
    assert d["reference"]["pos1"]["u_um"] > d["reference"]["pos3"]["u_um"] > 0


def test_place_cli_confirms_by_monte_carlo_on_two_workers(capsys) -> None:  # type: ignore[no-untyped-def]
    args = ["verify", "place", str(STUDY), "--trials", "20", "--grid", "2", "--refine", "0"]
    args += ["--points", "mesh96", "--seed", "4", "--json"]
    assert main(args) == 0
    one = json.loads(capsys.readouterr().out)
    assert main([*args, "--workers", "2"]) == 0
    two = json.loads(capsys.readouterr().out)
    assert one == two
    assert one["best"]["u_mc_um"] > 0


def test_place_cli_text_says_u_in_micrometres(capsys) -> None:  # type: ignore[no-untyped-def]
    # the text names its unit as verify simulate does: µm, not "um"
    args = ["verify", "place", str(STUDY), "--trials", "0", "--grid", "2", "--refine", "0"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "µm (GUM)" in out
    assert " um" not in out
    assert out.count(" µm\n") == 4  # the four reference positions


def test_the_search_runs_blas_on_one_thread_and_the_setting_comes_back(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # each candidate's score is a pinv of a (3N, p) Jacobian and thin products: with two
    # BLAS threads on a loaded 2-core machine the default search took 26.4 s, with one 7.4 s
    from threadpoolctl import threadpool_info, threadpool_limits

    from mtmc.verification import placement

    def threads() -> int:
        return max(d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas")

    seen: list[int] = []
    score = placement._gum_score

    def spy(ver, lt):  # type: ignore[no-untyped-def]
        seen.append(threads())
        return score(ver, lt)

    monkeypatch.setattr(placement, "_gum_score", spy)
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos1")
    assert st.limits is not None
    with threadpool_limits(limits=2, user_api="blas"):
        before = threads()
        r = place(ver, st.limits, references=st.trackers, n_xy=3, heights=1, refine=3)
        after = threads()
    assert before == after == 2
    assert seen
    assert set(seen) == {1}
    assert r.candidates > 0
