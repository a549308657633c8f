"""``mtmc verify plan``: visibility of the nine limit points from each tracker position."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from mtmc.cli.main import main
from mtmc.instruments import LaserTracker, TrackerLimits
from mtmc.kinematics import Machine
from mtmc.verification.visibility import limit_points, plan_visibility

STUDY = """\
[machine]
topology = "XFYZ"
reflector = [0.0, 0.0, 100.0]

[workspace]
distribution = "mesh"
[workspace.X]
start = 0
end = 2000
step = 1000
[workspace.Y]
start = 0
end = 1000
step = 500
[workspace.Z]
start = 0
end = 800
step = 400

[nc]
format = ["iso"]
feed = 2000
dwell = 1
output = "vis"

[tracker]
[tracker.positions.near]
position = [1000.0, -1500.0, 1500.0]
euler_deg = [0.0, 0.0, 90.0]
[tracker.positions.far]
position = [6000.0, 500.0, 400.0]
euler_deg = [0.0, 0.0, 180.0]
[tracker.limits]
elevation_deg = [-20.0, 77.0]
height_mm = [300.0, 1400.0]
acceptance_deg = [0.0, 30.0]
"""


def _angles(lt: LaserTracker, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Elevation and acceptance angle by hand: the beam in the tracker frame."""
    x = (p - lt.position) @ lt.rotation
    el = np.arctan2(x[:, 2], np.hypot(x[:, 0], x[:, 1]))
    u = x[0] / np.linalg.norm(x[0])
    v = x / np.linalg.norm(x, axis=1)[:, None]
    return np.arctan2(x[:, 1], x[:, 0]), el, np.degrees(np.arccos(np.clip(v @ u, -1, 1)))


def test_limit_points_are_the_middle_and_the_corners() -> None:
    q = np.array([[x, y, z] for x in (0, 1000, 2000) for y in (0, 500, 1000) for z in (0, 800)])
    names, lp = limit_points(q)
    assert names == tuple(f"P{i}" for i in range(9))
    assert lp[0].tolist() == [1000.0, 500.0, 400.0]
    corners = {tuple(c) for c in lp[1:].tolist()}
    assert corners == {(x, y, z) for x in (0, 2000) for y in (0, 1000) for z in (0, 800)}


def test_plan_reports_the_failing_points_and_limits(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    study = tmp_path / "study.toml"
    study.write_text(STUDY)
    assert main(["verify", "plan", str(study), "-o", str(tmp_path), "--json"]) == 0
    vis = json.loads(capsys.readouterr().out)["visibility"]
    assert list(vis) == ["near", "far"]
    # the reference by hand: the reflector 100 mm below the spindle nose, eqs. 19-21
    m = Machine.from_topology("XFYZ", tool=(0.0, 0.0, 100.0))
    names, lp = limit_points(np.array([[0, 0, 0], [2000, 1000, 800]], dtype=float))
    p = m.tool_position(lp)
    for name, pos, eul in (("near", [1000, -1500, 1500], 90.0), ("far", [6000, 500, 400], 180.0)):
        lt = LaserTracker.from_euler(pos, [0, 0, eul], degrees=True)
        _, el, acc = _angles(lt, p)
        want = {(names[i], "elevation") for i in np.nonzero(np.degrees(el) < -20.0)[0]}
        want |= {(names[i], "acceptance") for i in np.nonzero(acc > 30.0)[0]}
        if not 300.0 <= pos[2] <= 1400.0:
            want.add(("tracker", "height"))
        got = {(f["point"], f["limit"]) for f in vis[name]["failures"]}
        assert got == want, name
        assert vis[name]["ok"] is (not want)
        for f in vis[name]["failures"]:
            if f["limit"] == "acceptance":
                i = names.index(f["point"])
                assert math.isclose(f["value"], acc[i], rel_tol=1e-9)
                assert f["axes"] == dict(zip("XYZ", lp[i].tolist(), strict=True))
    # the near position is too high and sees the far corners at too wide an angle
    assert ("tracker", "height") in {(f["point"], f["limit"]) for f in vis["near"]["failures"]}
    assert vis["far"]["ok"] is False or vis["near"]["ok"] is False
    # the text names the same
    assert main(["verify", "plan", str(study), "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "near: 10 failures" in out
    assert "tracker: height 1500.00 mm outside [300, 1400] mm" in out
    assert "P2 (X 0, Y 0, Z 800): acceptance 32.08 deg outside [0, 30] deg" in out


def test_plan_without_trackers_says_so(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    study = tmp_path / "study.toml"
    study.write_text(STUDY.split("[tracker]")[0])
    assert main(["verify", "plan", str(study), "-o", str(tmp_path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["visibility"] is None


def test_plan_visibility_library_call_matches_limits() -> None:
    m = Machine.from_topology("XFYZ")
    q = np.array([[0.0, 0.0, 0.0], [1000.0, 1000.0, 500.0]])
    lt = LaserTracker.from_euler([500.0, -3000.0, 250.0], [0, 0, 90.0], degrees=True)
    r = plan_visibility(m, q, {"a": lt}, TrackerLimits(acceptance=(0.0, math.radians(90.0))))
    assert r["a"].ok
    assert r["a"].names[0] == "P0"
    r = plan_visibility(m, q, {"a": lt}, TrackerLimits(acceptance=(0.0, math.radians(5.0))))
    assert not r["a"].ok
    assert {f["limit"] for f in r["a"].failures(("X", "Y", "Z"))} == {"acceptance"}
