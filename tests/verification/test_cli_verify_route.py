"""``verify simulate`` runs its study as ``mtmc run`` does; ``verify place`` reports progress."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from mtmc.cli.main import main
from mtmc.study import load_study
from mtmc.uncertainty.tolerance import round_to_uncertainty

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
STUDY = STUDIES / "aguado2016.toml"


def test_simulate_o_writes_the_result_of_mtmc_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    a, b = tmp_path / "verify", tmp_path / "run"
    # the routes agree on the numbers; the report's plots are tested with the report
    args = ["-n", "20", "-s", "4", "--no-progress", "--plots", "0"]
    assert main(["verify", "simulate", str(STUDY), "-o", str(a), *args]) == 0
    text = capsys.readouterr().out
    assert main(["run", str(STUDY), "-o", str(b), *args]) == 0
    capsys.readouterr()
    ja = json.loads((a / "result.json").read_text(encoding="utf-8"))
    jb = json.loads((b / "result.json").read_text(encoding="utf-8"))
    # one route, seeded draws: the quantities agree to the bit
    assert ja["quantities"] == jb["quantities"]
    assert (a / "report.html").is_file()
    assert text.splitlines()[-1] == f"report: {a / 'report.html'}"
    # the printed numbers are the result's: y and U as it rounds them, k, u to two digits
    result = load_study(STUDY).run(trials=20, seed=4)
    for q in result.quantities:
        stat = q.name.rsplit(".", 1)[1]
        mc = q.mc
        u = round_to_uncertainty(mc.u, mc.u)[1]
        line = f"{stat:<4}: {q.reported.estimate}  U = {q.reported.U} (k = {mc.k:.3f})  u = {u}"
        assert line in text, (line, text)
    assert "U (k, p = 95 %) and u" in text


def test_simulate_json_is_the_result_in_its_unit(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["verify", "simulate", str(STUDY), "-n", "20", "-s", "4", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    result = load_study(STUDY).run(trials=20, seed=4)
    assert d["unit"] == "µm"
    q = result.quantity("volumetric_error.compensated.mean")
    v = d["compensated_ve_um"]["mean"]
    assert (v["estimate"], v["U"], v["u"], v["k"], v["unit"]) == (
        q.mc.estimate,
        q.mc.U,
        q.mc.u,
        q.mc.k,
        "µm",
    )


def test_simulate_quiet_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["verify", "simulate", str(STUDY), "-n", "40", "-s", "1", "-q"]) == 0
    out, err = capsys.readouterr()
    assert out == "trials 40  seed 1\n"
    assert "trials" not in err
    argv = ["verify", "simulate", str(STUDY), "-n", "4", "-o", str(tmp_path / "r")]
    assert main([*argv, "--points", "mesh"]) == 2
    assert "not with --points or --tracker" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_placement_reports_its_progress() -> None:
    from mtmc.verification.placement import place

    st = load_study(STUDY).study
    calls: list[tuple[int, int | None]] = []
    place(
        st.verification(),
        st.limits,
        n_xy=3,
        heights=2,
        refine=5,
        trials=4,
        seed=1,
        progress=lambda d, t: calls.append((d, t)),
    )
    done = [d for d, _ in calls]
    # every step counted once: 3 × 3 × 2 grid nodes, 5 refinement evaluations, 4 trials
    assert {t for _, t in calls} == {3 * 3 * 2 + 5 + 4}
    assert done == sorted(done)
    assert done[-1] == 3 * 3 * 2 + 5 + 4


@pytest.mark.parametrize("flag", ["--progress", "--no-progress", "-q"])
def test_place_progress_and_quiet(flag: str, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["verify", "place", str(STUDY), "-n", "4", "-s", "2"]
    assert main([*argv, "--grid", "2", "--refine", "3", flag]) == 0
    out, err = capsys.readouterr()
    total = 2 * 2 * 3 + 3 + 4  # the grid at three heights, the refinement, the trials
    assert (f"{total}/{total} steps" in err) == (flag == "--progress")
    assert (out == "trials 4  seed 2\n") == (flag == "-q")
    assert re.search(r"mean point u [0-9.]+ µm", out) or flag == "-q"


def test_the_verify_commands_scale_by_the_studys_units_only() -> None:
    # mm → µm and rad → µrad have one home, the study's file_unit: no factor in the CLI
    from mtmc.study.verification import file_unit

    assert file_unit("mm") == ("µm", 1e3)
    assert file_unit("rad") == ("µrad", 1e6)
    text = (ROOT / "src" / "mtmc" / "cli" / "verify.py").read_text(encoding="utf-8")
    assert not re.search(r"\b1e[36]\b", text)
