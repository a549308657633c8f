"""The visibility warnings of ``verify simulate``, ``verify place`` and ``mtmc run``, and
the reading of the tracker angles of Aguado et al. 2016 Table I in the shipped study."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main as cli
from mtmc.instruments import LaserTracker
from mtmc.study import load_study
from mtmc.verification.visibility import study_visibility, visibility_warnings

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "aguado2016.toml"

#: Aguado et al. 2016 Table I: position (mm) and angles alpha, beta, phi (deg).
TABLE_I = {
    "pos1": ((3500.0, -1500.0, 500.0), (15.0, 37.0, 26.0)),
    "pos2": ((4500.0, -800.0, 500.0), (32.0, 17.0, 12.0)),
    "pos3": ((1250.0, 2000.0, 600.0), (5.0, 65.0, 32.0)),
    "pos4": ((1100.0, -1000.0, 600.0), (63.0, 14.0, 35.0)),
}


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_table_i_angles_are_zyz_euler_angles_and_pos4_sees_the_workspace() -> None:
    st = load_study(STUDY).study
    assert st.euler == "ZYZ"
    for name, (pos, ang) in TABLE_I.items():
        a, b, c = np.radians(ang)
        lt = st.trackers[name]
        # R = Rz(alpha) Ry(beta) Rz(phi): beta is the tilt from upright
        assert np.allclose(lt.rotation, _rz(a) @ _ry(b) @ _rz(c), atol=1e-12)
        assert np.allclose(lt.position, pos)
        assert math.isclose(math.degrees(math.acos(lt.rotation[2, 2])), ang[1], abs_tol=1e-9)
    limits = st.limits
    assert limits is not None
    for points in ("mesh96", "cloud96", "mesh5408"):
        vis = study_visibility(st, points)
        # the paper's placement tool gave pos4 (§5) and checks the elevation limits (§4.4)
        assert {n: v.ok for n, v in vis.items()} == {
            "pos1": True,
            "pos2": True,
            "pos3": False,
            "pos4": True,
        }
        # every point of the set, not only the limit points, by direct NumPy
        p = st.machine.tool_position(st.points[points].q)
        for name, (pos, ang) in TABLE_I.items():
            a, b, c = np.radians(ang)
            x = (p - np.asarray(pos)) @ (_rz(a) @ _ry(b) @ _rz(c))
            el = np.arctan2(x[:, 2], np.hypot(x[:, 0], x[:, 1]))
            inside = bool(np.all((el >= limits.elevation[0]) & (el <= limits.elevation[1])))
            assert inside == (name != "pos3"), (points, name)
    # the reading the study used before (extrinsic x, y, z) leaves pos4 blind to two corners
    pos, ang = TABLE_I["pos4"]
    old = dataclasses.replace(
        st, trackers={"pos4": LaserTracker.from_euler(pos, ang, seq="xyz", degrees=True)}
    )
    assert not study_visibility(old, "mesh96")["pos4"].ok


def test_warnings_name_the_position_the_point_and_the_limit() -> None:
    st = load_study(STUDY).study
    lines = visibility_warnings(study_visibility(st, "mesh96"), st.machine.axes)
    assert len(lines) == 1
    assert lines[0].startswith("tracker position pos3 cannot see")
    assert "P3 (X 0, Y 1500, Z 0): elevation -74.69 deg outside [-60, 77] deg" in lines[0]
    assert visibility_warnings(study_visibility(st, "mesh96", ["pos4"]), st.machine.axes) == []


def test_verify_simulate_warns(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["verify", "simulate", str(STUDY), "--trials", "20", "--json"]
    assert cli([*args, "--tracker", "pos3"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    assert len(d["warnings"]) == 1
    assert "pos3" in d["warnings"][0]
    assert cap.err.strip() == f"mtmc: warning: {d['warnings'][0]}"
    assert set(d["point_mean_ve_um"]) == {"initial", "compensated"}
    assert cli([*args, "--tracker", "pos4"]) == 0
    cap = capsys.readouterr()
    assert json.loads(cap.out)["warnings"] == []
    assert "warning" not in cap.err


def test_verify_place_warns(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["verify", "place", str(STUDY), "--grid", "2", "--refine", "0", "--trials", "0"]
    assert cli([*args, "--json"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)
    assert [w.split(" cannot")[0] for w in d["warnings"]] == ["tracker position pos3"]
    assert "mtmc: warning: tracker position pos3" in cap.err
    assert d["best"]["euler"] == "ZYZ"


def test_mtmc_run_warns_and_the_result_carries_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = STUDY.read_text(encoding="utf-8").replace('tracker = "pos4"', 'tracker = "pos3"')
    study = tmp_path / "pos3.toml"
    study.write_text(text, encoding="utf-8")
    out = tmp_path / "r"
    assert cli(["run", str(study), "-o", str(out), "--trials", "20", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "mtmc: warning: tracker position pos3 cannot see" in err
    result = json.loads((out / "result.json").read_text(encoding="utf-8"))
    assert len(result["warnings"]) == 1
    pm = result["verification"]["point_mean_ve_um"]
    assert set(pm["initial"]) == {"max", "mean", "min"}
    assert "tracker position pos3 cannot see" in (out / "report.html").read_text("utf-8")
    table = next(t for t in result["tables"] if t["name"] == "point_mean_volumetric_error")
    assert table["rows"][0][:2] == ["initial", "max"]
    assert table["rows"][0][3] == pytest.approx(pm["initial"]["max"]["estimate"])


def test_an_unknown_point_set_or_tracker_is_refused_as_the_simulation_refuses_it() -> None:
    # one lookup of a point set and of a tracker position (VerificationStudy.point_set,
    # tracker_name) for the simulation and the visibility check: the same message in both
    from mtmc.errors import InputError

    st = load_study(STUDY).study
    for call in (lambda: study_visibility(st, "nope"), lambda: st.verification("nope")):
        with pytest.raises(InputError, match=r"^field points: no point set 'nope'; the study ha"):
            call()
    for call in (
        lambda: study_visibility(st, "mesh96", ["pos1", "posX"]),
        lambda: st.verification("mesh96", "posX"),
    ):
        with pytest.raises(InputError) as info:
            call()
        assert info.value.field == "tracker"
        assert info.value.message == "no tracker position 'posX'; the study has " + ", ".join(
            st.trackers
        )
