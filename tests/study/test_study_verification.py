"""The verification kind runs the verification of mtmc.verification and reports it unchanged."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.study import load_study

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "aguado2017.toml"


def test_verification_study_reports_what_simulate_computes():
    from mtmc.verification.simulate import VE_NAMES, simulate

    r = load_study(STUDY).run(trials=60, seed=3)
    s = load_study(STUDY).study
    mc = simulate(
        s.verification(),
        60,
        3,
        repeatability=s.repeatability,
        pose_u=s.pose_u,
        reflector_u=s.reflector_u,
    )
    for i, name in enumerate(VE_NAMES):
        q = r.quantity(f"volumetric_error.{name}")
        assert q.unit == "µm"  # the study's unit; the simulation's mm times 1000
        assert q.mc.estimate == pytest.approx(1e3 * mc.ve_estimate[i], rel=1e-12)
        assert q.mc.u == pytest.approx(1e3 * mc.ve_u[i], rel=1e-12)
    rows = r.tables[0].rows
    assert [row[0] for row in rows] == list(mc.names)
    # each parameter with its unit (ISO 230-1), in the study file's units: displacements
    # and the pose shift in µm, rotations and the pose rotation vector in µrad
    assert r.tables[0].columns[1] == "unit"
    units = {row[0]: row[1] for row in rows}
    assert units["EXX[1]"] == units["EZY[3]"] == units["LT.x"] == "µm"
    assert units["EAX[1]"] == units["ECX[2]"] == units["EC0Y"] == units["LT.rx"] == "µrad"
    assert set(units.values()) == {"µm", "µrad"}
    factor = np.array([1e3 if units[n] == "µm" else 1e6 for n in mc.names])
    np.testing.assert_allclose([row[4] for row in rows], factor * mc.coef_u, rtol=1e-12)
    np.testing.assert_allclose([row[5] for row in rows], factor * mc.gum.u, rtol=1e-12)
    field = r.fields[0]
    assert field.unit == "µm"
    np.testing.assert_allclose(field.values, 1e3 * mc.point_u, rtol=1e-12)
    assert field.points.shape == (len(mc.point_u), 3)
