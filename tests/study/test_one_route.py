"""One route per computation: each file is parsed once, and a command that computes gives
the numbers of ``mtmc run`` on the same study (the same study object, the same run).

The parses are counted where every TOML file is parsed (``mtmc.document``); a command's
``--json`` output is compared with ``load_study(...).run(...)`` at the same trials and seed:
to the bit where both read the same result, to a few ulps where one sums the same draws in
another order.
"""

from __future__ import annotations

import collections
import json
import math
from pathlib import Path
from typing import Any

import pytest

import mtmc.document
from mtmc.cli.main import main as cli
from mtmc.study import load_study

STUDIES = Path(__file__).resolve().parents[2] / "examples" / "studies"

#: A shipped study of every kind that reads a file, with few trials.
KINDS = {
    "mass_calibration": 200,  # propagate
    "ball_centre": 200,  # graph (the study file and its graph file)
    "bcs_origin": 200,  # sweep
    "five_axis": 200,  # kinematics
    "aguado2017": 20,  # verification
    "wang2022": 50,  # artefact (the study file and its artefact file)
}


@pytest.mark.parametrize("name", sorted(KINDS))
def test_each_file_is_parsed_once_per_run(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    parsed: collections.Counter[str] = collections.Counter()
    real = mtmc.document.tomllib.loads

    def counting(text: str, **kw: Any) -> dict[str, Any]:
        parsed[text] += 1
        return real(text, **kw)

    monkeypatch.setattr(mtmc.document.tomllib, "loads", counting)
    study = load_study(STUDIES / f"{name}.toml")
    study.run(trials=KINDS[name], seed=1)
    assert parsed, "no file parsed through mtmc.document"
    assert max(parsed.values()) == 1, {t.splitlines()[0]: n for t, n in parsed.items()}
    assert (STUDIES / f"{name}.toml").read_text(encoding="utf-8") in parsed


def _json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> Any:
    capsys.readouterr()
    assert cli(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_verify_simulate_gives_the_numbers_of_mtmc_run(capsys: pytest.CaptureFixture[str]) -> None:
    path = STUDIES / "aguado2017.toml"
    j = _json(["verify", "simulate", str(path), "--trials", "30", "--seed", "5", "--json"], capsys)
    r = load_study(path).run(trials=30, seed=5)
    for which in ("initial", "residual", "compensated"):
        for stat in ("max", "mean", "min"):
            q = r.quantity(f"volumetric_error.{which}.{stat}")
            # one unit: the study's µm, in the command's JSON and in the run's quantities
            assert q.unit == "µm"
            assert j[f"{which}_ve_um"][stat]["estimate"] == q.mc.estimate
            assert j[f"{which}_ve_um"][stat]["u"] == q.mc.u


def test_verify_simulate_and_mtmc_run_draw_the_same_uncertainties(tmp_path: Path) -> None:
    # a study with a repeatability, a reflector u and a pose u (pose not identified): the
    # command and the run pass all three (they once differed on pose_u)
    text = (STUDIES / "aguado2017.toml").read_text(encoding="utf-8")
    text = text.replace("pose = true", "pose = false")
    text = text.replace(
        'tracker = "aguado2017"\n',
        'tracker = "aguado2017"\nrepeatability_um = 2.0\nreflector_um = 1.0\n'
        "pose_u = [1e-6, 1e-6, 1e-6, 0.002, 0.002, 0.002]\n",
    )
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    st = load_study(path)
    a = st.study.simulate(20, 8)
    b = st.run(trials=20, seed=8)
    mc = b.quantity("volumetric_error.compensated.mean").mc
    assert mc.estimate == 1e3 * a.ve("compensated.mean")[0]  # µm from mm
    plain = load_study(STUDIES / "aguado2017.toml").study.simulate(20, 8)
    assert a.ve("compensated.mean")[0] != plain.ve("compensated.mean")[0]


def test_a_pose_u_with_an_identified_pose_is_refused_at_its_line(tmp_path: Path) -> None:
    text = (STUDIES / "aguado2017.toml").read_text(encoding="utf-8")
    text = text.replace(
        'tracker = "aguado2017"\n', 'tracker = "aguado2017"\npose_u = [0, 0, 0, 0, 0, 1]\n'
    )
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    line = text.splitlines().index("pose_u = [0, 0, 0, 0, 0, 1]") + 1
    with pytest.raises(mtmc.document.InputError, match="pose is not identified") as err:
        load_study(path)
    assert err.value.line == line


def test_artefact_simulate_gives_the_numbers_of_mtmc_run(
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = STUDIES / "wang2022.toml"
    j = _json(
        ["artefact", "simulate", str(path), "--trials", "60", "--seed", "5", "--json"], capsys
    )
    r = load_study(path).run(trials=60, seed=5)
    for pose in j["poses"]:
        name = f"r_max.b{pose['b_deg']:g}_c{pose['c_deg']:g}"
        q = r.quantity(name)
        assert q.unit == "µm"  # the study's unit, as the command's
        assert pose["r_max_um"]["estimate"] == pytest.approx(q.mc.estimate, rel=1e-12)
        assert pose["r_max_um"]["u"] == pytest.approx(q.mc.u, rel=1e-12)


def test_graph_run_gives_the_numbers_of_mtmc_run(capsys: pytest.CaptureFixture[str]) -> None:
    graph = STUDIES.parent / "graphs" / "ball_centre.toml"
    j = _json(["graph", "run", str(graph), "--trials", "3000", "--seed", "5", "--json"], capsys)
    r = load_study(STUDIES / "ball_centre.toml").run(trials=3000, seed=5)
    for i, c in enumerate("xyz"):
        mc = r.quantity(f"p.{c}").mc
        # the same draws through the same graph; the command reports the place as a vector
        # (means over the trials of each column of an (M, 3) array), the study each
        # coordinate alone: the same sums in another order, so equal to a few ulps
        assert j["places"]["p"]["estimate"][i] == pytest.approx(mc.estimate, rel=1e-13)
        assert j["places"]["p"]["u"][i] == pytest.approx(mc.u, rel=1e-13)


def test_propagate_gives_the_numbers_of_mtmc_run(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    text = (
        'kind = "propagate"\nmodel = "X1 + X2"\noutput = "Y"\n'
        '[inputs]\nX1 = "normal(0, 1)"\nX2 = "normal(0.5, 0.5)"\n'
    )
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    argv = ["propagate", "X1 + X2", "-i", "X1=normal(0, 1)", "-i", "X2=normal(0.5, 0.5)"]
    j = _json([*argv, "--trials", "3000", "--seed", "5", "--json"], capsys)
    mc = load_study(path).run(trials=3000, seed=5).quantity("Y").mc
    assert j["estimate"] == mc.estimate
    assert j["u"] == mc.u
    assert math.isfinite(j["u"])


def test_graph_sweep_gives_the_numbers_of_the_sweep_study(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # the sweep of bcs_origin.toml ([sweep]: d_ac, 1000 trials a grid point, the two
    # standard deviations on 0.001:0.005:5) asked of the command with the same grid
    graph = STUDIES.parent / "graphs" / "bcs_origin.toml"
    argv = ["graph", "sweep", str(graph), "--quantity", "d_ac", "--trials", "1000"]
    vary = ["--vary", "probe.u_probe=0.001:0.005:5", "--vary", "probe.u_axis=0.001:0.005:5"]
    j = _json([*argv, *vary, "--seed", "5", "--json"], capsys)
    s = load_study(STUDIES / "bcs_origin.toml").run(trials=200, seed=5).extra["sweep"]
    assert j["names"] == list(s["names"])
    assert j["grid"] == [list(map(float, row)) for row in s["grid"]]
    # the same runs at every grid point: the same bits
    assert j["u"] == [float(u) for u in s["u"]]
    assert j["surrogate"]["c0"] == s["surrogate"]["c0"]
    assert [j["surrogate"]["coefficients"][n] for n in j["names"]] == [
        float(c) for c in s["surrogate"]["coefficients"]
    ]
