"""The parameters of ISO 230-2 against hand computation from their definitions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.positioning import SYMBOLS, PositioningTest, axis_parameters, evaluate, statistics

P = np.array([0.0, 100.0, 250.0, 400.0, 500.0])


def _test(x: np.ndarray) -> PositioningTest:
    return PositioningTest(P[: x.shape[0]], x)


def test_pure_scale_error():
    # x = k P in every run and direction: no scatter, no reversal
    k = 0.012  # µm per mm
    x = np.repeat((k * P)[:, None, None], 5, axis=1).repeat(2, axis=2)
    p = evaluate(_test(x))
    span = k * (P[-1] - P[0])
    for sym in ("A", "A_up", "A_down", "E", "E_up", "E_down", "M"):
        assert float(getattr(p, sym)) == pytest.approx(span, rel=1e-15, abs=1e-15), sym
    for sym in ("R", "R_up", "R_down", "B", "B_mean"):
        assert float(getattr(p, sym)) == 0.0, sym


def test_pure_backlash():
    # x↑ = +b/2, x↓ = -b/2 at every target: B_i = b, and R_i = |B_i| with s = 0
    b = 3.0
    x = np.zeros((5, 4, 2))
    x[:, :, 0], x[:, :, 1] = b / 2, -b / 2
    p = evaluate(_test(x))
    assert float(p.B) == b
    assert float(p.B_mean) == b
    assert float(p.E) == b
    assert float(p.A) == b
    assert float(p.R) == b
    for sym in ("E_up", "E_down", "M", "A_up", "A_down", "R_up", "R_down"):
        assert float(getattr(p, sym)) == 0.0, sym


def test_pure_noise_with_known_s():
    # runs c·(-2, -1, 0, 1, 2): mean 0, s = c sqrt(10/4) exactly, at every target
    c = 0.4
    runs = c * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    x = np.broadcast_to(runs[None, :, None], (5, 5, 2)).copy()
    x[:, :, 1] = x[:, ::-1, 1]
    s = c * math.sqrt(2.5)
    p = evaluate(_test(x))
    np.testing.assert_allclose(p.s_up, s, rtol=1e-15)
    for sym in ("R_up", "R_down", "A_up", "A_down"):
        assert float(getattr(p, sym)) == pytest.approx(4 * s, rel=1e-15), sym
    # R_i = max(2s↑ + 2s↓ + |B_i|, 4s↑, 4s↓) = 4s; A = max(x̄ + 2s) - min(x̄ - 2s) = 4s
    assert float(p.R) == pytest.approx(4 * s, rel=1e-15)
    assert float(p.A) == pytest.approx(4 * s, rel=1e-15)
    for sym in ("E", "M", "B", "B_mean"):
        assert abs(float(getattr(p, sym))) < 1e-15, sym


def _by_hand(x: np.ndarray) -> dict[str, float]:
    """The definitions written out with loops over targets and runs, in plain floats."""
    m, n = x.shape[0], x.shape[1]
    mean = [[sum(float(x[i, j, d]) for j in range(n)) / n for d in (0, 1)] for i in range(m)]
    s = [
        [
            math.sqrt(sum((float(x[i, j, d]) - mean[i][d]) ** 2 for j in range(n)) / (n - 1))
            for d in (0, 1)
        ]
        for i in range(m)
    ]
    bi = [mean[i][0] - mean[i][1] for i in range(m)]
    xi = [(mean[i][0] + mean[i][1]) / 2 for i in range(m)]
    ri = [max(2 * s[i][0] + 2 * s[i][1] + abs(bi[i]), 4 * s[i][0], 4 * s[i][1]) for i in range(m)]
    every = [mean[i][d] for i in range(m) for d in (0, 1)]
    return {
        "A": max(mean[i][d] + 2 * s[i][d] for i in range(m) for d in (0, 1))
        - min(mean[i][d] - 2 * s[i][d] for i in range(m) for d in (0, 1)),
        "A_up": max(mean[i][0] + 2 * s[i][0] for i in range(m))
        - min(mean[i][0] - 2 * s[i][0] for i in range(m)),
        "A_down": max(mean[i][1] + 2 * s[i][1] for i in range(m))
        - min(mean[i][1] - 2 * s[i][1] for i in range(m)),
        "E": max(every) - min(every),
        "E_up": max(mean[i][0] for i in range(m)) - min(mean[i][0] for i in range(m)),
        "E_down": max(mean[i][1] for i in range(m)) - min(mean[i][1] for i in range(m)),
        "M": max(xi) - min(xi),
        "R": max(ri),
        "R_up": max(4 * s[i][0] for i in range(m)),
        "R_down": max(4 * s[i][1] for i in range(m)),
        "B": max(abs(b) for b in bi),
        "B_mean": sum(bi) / m,
    }


def test_random_tests_against_the_definitions_by_hand():
    rng = np.random.default_rng(7)
    for _ in range(20):
        m, n = int(rng.integers(2, 6)), int(rng.integers(2, 7))
        x = rng.normal(0.0, 3.0, (m, n, 2)) + rng.normal(0.0, 5.0, (m, 1, 1))
        p = evaluate(_test(x)).axis_values()
        ref = _by_hand(x)
        for sym in SYMBOLS:
            # sums of a few numbers of size ~10: a few ulps of 10
            assert float(p[sym]) == pytest.approx(ref[sym], rel=1e-13, abs=1e-13), sym


def test_batched_equals_one_at_a_time():
    rng = np.random.default_rng(8)
    x = rng.normal(size=(7, 4, 3, 2))
    mean, s = statistics(x)
    batch = axis_parameters(mean, s).stacked()
    assert batch.shape == (7, 12)
    for k in range(7):
        one = evaluate(_test(x[k])).stacked()
        np.testing.assert_array_equal(batch[k], one)


def test_complex_step_gives_the_derivative_at_the_extreme():
    # E_up = max x̄↑ - min x̄↑: its derivative is +1 at the max target, -1 at the min one
    mean = np.array([[0.0, 0.0], [5.0, 4.0], [2.0, 1.0]], dtype=complex)
    s = np.full((3, 2), 0.1, dtype=complex)
    h = 1e-20
    for i, want in ((1, 1.0), (0, -1.0), (2, 0.0)):
        m2 = mean.copy()
        m2[i, 0] += 1j * h
        assert axis_parameters(m2, s).E_up.imag / h == want


def test_bad_shapes_and_values_are_refused():
    with pytest.raises(InputError, match="shape"):
        statistics(np.zeros((3, 1, 2)))
    with pytest.raises(InputError, match="strictly increasing"):
        PositioningTest([0.0, 0.0], np.zeros((2, 2, 2)))
    with pytest.raises(InputError, match="at least two target"):
        PositioningTest([0.0], np.zeros((1, 2, 2)))
    with pytest.raises(InputError, match=r"shape \(m, n, 2\)"):
        PositioningTest([0.0, 1.0], np.zeros((2, 1, 2)))
    with pytest.raises(InputError, match="finite"):
        PositioningTest([0.0, 1.0], np.full((2, 2, 2), np.nan))
    with pytest.raises(InputError, match="run labels"):
        PositioningTest([0.0, 1.0], np.zeros((2, 2, 2)), runs=(1,))
    with pytest.raises(InputError, match="TARGET,DEVIATION"):
        PositioningTest([0.0, 1.0], np.zeros((2, 2, 2)), unit="arcsec")
