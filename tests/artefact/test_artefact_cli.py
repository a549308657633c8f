"""``mtmc artefact simulate`` and ``mtmc artefact fit``: the JSON contracts and the errors."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from mtmc.artefact import patch_points
from mtmc.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "wang2022.toml"


def test_simulate_json_contract(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    fig = tmp_path / "fig7.svg"
    rc = main(
        [
            "artefact",
            "simulate",
            str(STUDY),
            "--trials",
            "300",
            "--seed",
            "3",
            "--json",
            "--no-gum",
            "--figure",
            str(fig),
        ]
    )
    out = capsys.readouterr().out
    assert rc == 0
    j = json.loads(out)
    assert len(j["poses"]) == 9
    for p in j["poses"]:
        assert {"b_deg", "c_deg", "r_max_um", "r_avg_um"} <= set(p)
        for k in ("r_max_um", "r_avg_um"):
            assert {"estimate", "u"} <= set(p[k])
            assert p[k]["u"] > 0
    assert len(j["setup_errors"]) == 18
    assert all({"estimate", "u"} <= set(v) for v in j["setup_errors"].values())
    assert (j["trials"], j["seed"]) == (300, 3)
    assert fig.read_text().lstrip().startswith("<?xml")
    assert "magnified" in fig.read_text()
    # the same seed gives the same numbers
    main(
        ["artefact", "simulate", str(STUDY), "--trials", "300", "--seed", "3", "--json", "--no-gum"]
    )
    assert json.loads(capsys.readouterr().out)["poses"] == j["poses"]


def test_simulate_table_and_errors(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["artefact", "simulate", str(STUDY), "--trials", "200", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "r_max" in out
    assert "dpx" in out
    # u is named and rounded to two significant digits (JCGM 100 §7.2.2, §7.2.6), no ±
    assert "±" not in out
    assert re.search(r"-?\d+\.?\d* \(u = 0\.0*[1-9]\d\)", out)
    # leading zeros are not significant: 0.099 has two significant digits, 0.0991 three
    assert not re.search(r"\(u = 0\.0*[1-9]\d{2,}\)", out)
    bad = tmp_path / "bad.toml"
    bad.write_text(STUDY.read_text().replace("repetitions = 3", "repetitions = -1"))
    assert main(["artefact", "simulate", str(bad), "--trials", "10"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("mtmc: error: ")
    assert "bad.toml:" in err
    assert "plan.repetitions" in err


def test_simulate_workers_give_the_same_numbers(capsys: pytest.CaptureFixture[str]) -> None:
    # 1500 trials: three evaluation blocks of 689, spread over two threads
    base = ["artefact", "simulate", str(STUDY), "--trials", "1500", "--seed", "8", "--json"]
    assert main([*base, "--no-gum", "--workers", "1"]) == 0
    one = json.loads(capsys.readouterr().out)
    assert main([*base, "--no-gum", "--workers", "2", "--executor", "thread"]) == 0
    two = json.loads(capsys.readouterr().out)
    assert two == one  # bit for bit: the engine's seed blocks do not depend on the workers
    assert one["poses"][0]["r_max_um"]["u"] > 0
    assert main([*base, "--workers", "2", "--executor", "nope"]) == 2
    assert "executor" in capsys.readouterr().err


def test_fit_json_contract(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    c = np.array([12.0, -3.0, 40.0])
    pts = patch_points(c, 4.9985)
    f = tmp_path / "pts.csv"
    f.write_text("x,y,z\n" + "\n".join(",".join(repr(v / 1e3) for v in p) for p in pts.tolist()))
    assert main(["artefact", "fit", str(f), "--units", "m", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert set(j) >= {"centre", "radius", "u_centre", "u_radius", "rms", "n"}
    np.testing.assert_allclose(j["centre"], c, atol=1e-9)  # mm whatever the input unit
    assert j["radius"] == pytest.approx(4.9985, abs=1e-9)
    assert j["n"] == 30
    assert main(["artefact", "fit", str(f), "--units", "m", "--radius", "0.0049985", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["u_radius"] == 0.0
    assert j["radius"] == pytest.approx(4.9985)
    assert main(["artefact", "fit", str(f), "--units", "m"]) == 0
    assert "centre" in capsys.readouterr().out
    g = tmp_path / "g.csv"
    g.write_text("1,2,3\n4,5\n")
    assert main(["artefact", "fit", str(g)]) == 2
    assert "g.csv:2" in capsys.readouterr().err
    assert main(["artefact", "fit", str(f), "--units", "inch"]) == 2


def test_fit_of_four_points_has_no_uncertainty(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    f = tmp_path / "p4.csv"
    f.write_text("5,0,0\n-5,0,0\n0,5,0\n0,0,5\n")
    for extra in ([], ["--json"]):
        assert main(["artefact", "fit", str(f), *extra]) == 2
        out, err = capsys.readouterr()
        assert out == ""
        assert err == (
            f"mtmc: error: {f}: 4 points leave no residual to give the fit's uncertainty "
            "(4 parameters): probe at least 5 points, or give the calibrated radius (--radius)\n"
        )
    assert main(["artefact", "fit", str(f), "--radius", "5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["u_centre"] == [0.0, 0.0, 0.0]


def test_gravity_cli(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "g.csv"
    f.write_text(
        "orientation,ball,x,y,z\nH,1,0,0,0\nH,2,1,0,0\nV,1,0.003,0,0.004\nV,2,1,-0.001,0\n"
    )
    assert main(["artefact", "gravity", str(f), "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["V-H"]["balls"]["1"]["dd_um"] == pytest.approx(5.0)
    assert j["V-H"]["mean_dd_um"] == pytest.approx(3.0)
    assert j["V-H"]["mean_abs_dx_um"] == pytest.approx(1.5)
    assert main(["artefact", "gravity", str(f)]) == 0
    assert "V-H" in capsys.readouterr().out
