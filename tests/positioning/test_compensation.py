"""The pitch-error compensation table: written, read back, applied; the residual it leaves."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.positioning import PositioningTest, apply_compensation, evaluate, pitch_compensation
from mtmc.verification import FORMATS, dump_compensation, load_compensation

P = np.array([0.0, 120.0, 260.0, 395.0, 500.0, 640.0])


def _synthetic() -> PositioningTest:
    """A pitch error (scale + periodic) with noise and no reversal of the machine."""
    rng = np.random.default_rng(12)
    pitch = 0.01 * P + 2.0 * np.sin(P / 80.0)
    return PositioningTest(P, pitch[:, None, None] + 0.4 * rng.standard_normal((P.size, 5, 2)))


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("sign", ["error", "correction"])
def test_round_trip_through_the_readers(tmp_path, fmt, sign):
    table = pitch_compensation(_synthetic(), "X", sign=sign)
    path = dump_compensation(table, tmp_path / f"pitch.{fmt}", fmt)
    back = load_compensation(path, fmt)
    assert back == table  # exact: the writers give shortest round-trip floats
    curve = back.curve("EXX")
    np.testing.assert_array_equal(curve.positions, P)
    want = np.asarray(evaluate(_synthetic()).mean) * 1e-3  # µm to mm
    np.testing.assert_array_equal(curve.values, want if sign == "error" else -want)


def test_residual_is_the_bidirectional_scatter_alone(tmp_path):
    test = _synthetic()
    path = dump_compensation(pitch_compensation(test), tmp_path / "pitch.isg", "isg")
    residual = apply_compensation(test, load_compensation(path, "isg"))
    xbar = np.asarray(evaluate(test).mean)
    # each reading less the mean bidirectional deviation at its target (µm of size ~10:
    # the µm -> mm -> µm trip costs a few ulps)
    np.testing.assert_allclose(
        residual.deviations, test.deviations - xbar[:, None, None], rtol=0, atol=1e-13
    )
    before, after = evaluate(test), evaluate(residual)
    assert abs(float(after.M)) < 1e-13  # no mean bidirectional deviation left
    np.testing.assert_allclose(after.s_up, before.s_up, rtol=1e-12)  # scatter unchanged
    assert float(after.R) == pytest.approx(float(before.R), rel=1e-12)
    assert float(after.B) == pytest.approx(float(before.B), rel=1e-12)
    # what is left of E is the reversal: x̄↑ - x̄ = B_i/2, x̄↓ - x̄ = -B_i/2
    half = 0.5 * np.asarray(before.reversal)
    both = np.concatenate([half, -half])
    assert float(after.E) == pytest.approx(float(both.max() - both.min()), rel=1e-12)


def test_rotary_table_units():
    x = np.zeros((3, 3, 2))
    x[1] = 3600.0  # 3600 arcsec = 1 deg, at 90 deg
    test = PositioningTest([0.0, 90.0, 180.0], x, unit="arcsec", target_unit="deg")
    table = pitch_compensation(test, "c")
    curve = table.curve("ECC")
    np.testing.assert_allclose(curve.positions, [0.0, math.pi / 2, math.pi], rtol=1e-15)
    np.testing.assert_allclose(curve.values, [0.0, math.pi / 180, 0.0], rtol=1e-15)
    back = apply_compensation(test, table, "C")
    np.testing.assert_allclose(back.deviations, 0.0, atol=1e-9)


def test_axis_errors():
    test = _synthetic()
    with pytest.raises(InputError, match="rotary, the test is of a linear axis"):
        pitch_compensation(test, "C")
    with pytest.raises(InputError, match="axis letter"):
        pitch_compensation(test, "Q")
    with pytest.raises(InputError, match="sign"):
        pitch_compensation(test, "X", sign="minus")
    with pytest.raises(InputError, match="has no EYY"):
        apply_compensation(test, pitch_compensation(test, "X"), "Y")
