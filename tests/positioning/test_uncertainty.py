"""The uncertainty of the parameters: GUM against closed forms, GUM against Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.positioning import (
    SYMBOLS,
    PositioningTest,
    UncertaintyModel,
    coverage,
    disagreement_notes,
    evaluate_uncertainty,
    positioning_model,
)
from mtmc.uncertainty import endpoint_std_error, validate

P = np.linspace(0.0, 1000.0, 6)


def _scale_test(noise: float = 0.3, seed: int = 3) -> PositioningTest:
    """A pure scale error of 12 µm/m with a little noise: extremes far apart."""
    rng = np.random.default_rng(seed)
    x = 0.012 * P[:, None, None] + noise * rng.standard_normal((P.size, 5, 2))
    return PositioningTest(P, x)


MATERIAL = {"material_temperature": "normal(21.0, 0.1)", "expansion": "normal(11.5, 0.5)"}


def test_gum_of_E_is_the_closed_form_of_the_material_term():
    # Only the material temperature uncertain, readings corrected to 20 °C by the laser:
    # E = max - min of the means, each shifted by -c α (t - t0) L_i: u(E) = c α u(t) ΔL,
    # ΔL = 1000 mm between the targets of the max and the min (the scale error puts them
    # at the ends). The reading's own x/c (at most 12 µm in 1000 mm) enters the scale
    # term only, which is absent here: the closed form is exact to rounding.
    test = _scale_test()
    model = UncertaintyModel(
        material_temperature="normal(21.0, 0.1)", expansion=11.5, type_a="none"
    )
    res = evaluate_uncertainty(test, model, 1000, seed=1)
    g = res.gum_result("E_up")
    assert g.u == pytest.approx(1e3 * 11.5e-6 * 0.1 * 1000.0, rel=1e-12)
    assert g.estimate == pytest.approx(float(res.readings.E_up), rel=1e-14)


def test_gum_validated_by_monte_carlo_on_a_near_linear_case():
    # JCGM 101 §8: the air, the material temperature and the wavelength (all nearly
    # linear; the expansion coefficient known, so no product α·Δt), no Type A inputs, and
    # extremes 12 µm apart against u ~ 1.2 µm: the GUM interval of every parameter that is
    # a range of the means lies within δ of the Monte Carlo one, or misses it by less than
    # three standard errors of a Monte Carlo endpoint (the verdict of the engine).
    test = _scale_test()
    model = UncertaintyModel(
        air_temperature="normal(20.5, 0.1)",
        air_pressure="normal(1010, 1)",
        humidity="normal(45, 5)",
        wavelength_error="normal(0, 0.05)",
        material_temperature="normal(21.0, 0.1)",
        expansion=11.5,
        type_a="none",
    )
    res = evaluate_uncertainty(test, model, 200_000, seed=11)
    for sym in ("A", "A_up", "A_down", "E", "E_up", "E_down", "M"):
        mc = res.monte_carlo(sym)
        v = validate(res.gum_result(sym), mc)
        assert v.verdict(endpoint_std_error(mc.u, mc.m, 0.95)) != "not validated", (sym, v)
    assert disagreement_notes(res, {s: True for s in SYMBOLS}) == []


def test_monte_carlo_of_A_differs_from_the_gum_at_a_near_tie():
    # A flat axis: every target has the same mean, so the maximum of x̄ + 2s is a near tie
    # of 2m uncertain values (Type A t inputs). The GUM linearises at one target; the
    # Monte Carlo mean of A lies well above the GUM estimate (the expectation of a maximum
    # of several exchangeable values exceeds their common expectation).
    rng = np.random.default_rng(4)
    x = 0.5 * rng.standard_normal((8, 5, 2))
    test = PositioningTest(np.linspace(0, 700, 8), x)
    res = evaluate_uncertainty(test, UncertaintyModel(), 50_000, seed=2)
    g, mc = res.gum_result("A"), res.monte_carlo("A")
    se = mc.u / math.sqrt(mc.trials)
    assert mc.estimate - g.estimate > 20 * se
    v = validate(g, mc)
    assert not v.passed
    notes = disagreement_notes(res, {"A": v.passed})
    assert len(notes) == 1
    assert notes[0].startswith("A: the GUM is not validated")
    assert "comes within" in notes[0]


def test_type_a_alone_is_the_t_interval_of_the_mean():
    # One target dominates E_up through its Type A input (scale s/√n, ν = n - 1): the GUM
    # gives u = s/√n for it, and the Monte Carlo the t PDF whose standard deviation is
    # s/√n · sqrt(ν/(ν - 2)).
    x = np.zeros((2, 5, 2))
    x[1, :, 0] = 10.0 + np.array([-2.0, -1.0, 0.0, 1.0, 2.0])  # s = sqrt(2.5), mean 10
    test = PositioningTest([0.0, 100.0], x)
    res = evaluate_uncertainty(test, UncertaintyModel(), 200_000, seed=5)
    g = res.gum_result("E_up")
    s = math.sqrt(2.5)
    assert g.u == pytest.approx(s / math.sqrt(5), rel=1e-12)
    assert g.dof == pytest.approx(4.0)
    mc = res.monte_carlo("E_up")
    # the standard error of a sample standard deviation of a t_4 is large (no fourth
    # moment); 3 % at M = 2e5 is several of them for this seed
    assert mc.u == pytest.approx(s / math.sqrt(5) * math.sqrt(2.0), rel=0.03)


def test_means_and_s_gives_u_of_s_by_the_gum():
    x = 0.1 * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])[None, :, None] * np.ones((2, 1, 2))
    x[0, :, 0] *= 10.0  # s = sqrt(2.5) there, s = sqrt(0.025) elsewhere
    test = PositioningTest([0.0, 100.0], x)
    res = evaluate_uncertainty(test, UncertaintyModel(type_a="means-and-s"), 2000, seed=5)
    # R_up = 4 s: σ = s/√g with ν g ~ χ²_ν, u(g) = sqrt(2/ν) → u(σ) = s / sqrt(2ν)
    assert res.gum_result("R_up").u == pytest.approx(4 * math.sqrt(2.5) / math.sqrt(8), rel=1e-12)


def test_one_seed_one_result_bit_for_bit():
    test = _scale_test()
    model = UncertaintyModel(drift="uniform(-1, 1)", resolution=0.01, **MATERIAL)
    a = evaluate_uncertainty(test, model, 3000, seed=9)
    b = evaluate_uncertainty(test, model, 3000, seed=9, block_size=700)
    np.testing.assert_array_equal(a.mc.samples, b.mc.samples)


def test_the_full_model_runs_and_notes_the_cosine_error():
    test = _scale_test()
    model = UncertaintyModel(
        air_temperature="normal(20.5, 0.1)",
        air_pressure="normal(1010, 1)",
        humidity="normal(45, 5)",
        equation_error="normal(0, 0.01)",
        misalignment="uniform(-100, 100)",
        dead_path_mm=100.0,
        air_temperature_change="uniform(-0.5, 0.5)",
        air_pressure_change="uniform(-1, 1)",
        drift="uniform(-1, 1)",
        resolution=0.001,
        material_compensated=False,
        datum_mm=0.0,
        **MATERIAL,
    )
    res = evaluate_uncertainty(test, model, 4000, seed=3)
    # not compensated: the material correction -c α (t - 20) L is applied at the estimate
    shift = -1e3 * 11.5e-6 * 1.0 * 1000.0
    assert res.gum_result("E_up").estimate == pytest.approx(
        float(res.readings.E_up) + shift, abs=1e-3
    )
    # the cosine error has a zero GUM sensitivity
    budget = {e.name: e for e in res.gum_result("E_up").budget}
    assert float(budget["misalignment"].sensitivity[0, 0]) == 0.0
    assert any(n.startswith("misalignment:") for n in disagreement_notes(res, {}))
    with pytest.raises(InputError, match="unknown parameter"):
        res.monte_carlo("Q")


def test_what_U_covers_and_what_is_not_evaluated():
    test = _scale_test()
    # readings alone, means only: R↑ and R↓ are functions of s alone, which nothing moves
    res = evaluate_uncertainty(test, UncertaintyModel(), 2000, seed=1)
    line, per = coverage(res)
    assert line.startswith("U covers: instrument and environment not evaluated")
    assert "+ scatter of the means (Type A, t with ν = 4)" in line
    assert "scatter of s not evaluated (type_a = 'means')" in line
    for sym in ("R_up", "R_down"):
        assert per[sym].startswith("not evaluated: R")
        assert "type_a = 'means-and-s'" in per[sym]
        assert np.ptp(res.monte_carlo(sym).samples) == 0  # the reason is the numbers'
    assert per["E"] == per["M"] == "scatter of the means"
    assert per["A"] == "scatter of the means"
    # with the scatter of s and an instrument input, every parameter is evaluated
    model = UncertaintyModel(type_a="means-and-s", **MATERIAL)
    res = evaluate_uncertainty(test, model, 2000, seed=1)
    line, per = coverage(res)
    assert "instrument and environment (material_temperature, expansion)" in line
    assert "+ scatter of s (Type A, χ² with ν = 4)" in line
    assert per["R_up"] == "instrument and environment + scatter of s"
    assert per["A"] == "instrument and environment + scatter of the means + scatter of s"
    assert not any(v.startswith("not evaluated") for v in per.values())
    # no scatter at all: the means' parameters are not evaluated either
    res = evaluate_uncertainty(
        test, UncertaintyModel(type_a="none", drift="normal(0, 0.5)"), 500, seed=1
    )
    line, per = coverage(res)
    assert "scatter of the means not evaluated (type_a = 'none')" in line
    assert per["E"] == "instrument and environment"


def test_the_estimate_is_the_definition_applied_to_the_readings():
    test = _scale_test()
    res = evaluate_uncertainty(test, UncertaintyModel(**MATERIAL), 2000, seed=1)
    from mtmc.positioning import evaluate

    readings = evaluate(test)
    for sym in SYMBOLS:
        # the model corrects nothing on average (material compensated at its
        # expectations): the estimate is the readings' value to rounding of the
        # corrections (a few 1e-15 of values of size 10)
        assert res.estimate(sym) == pytest.approx(float(getattr(readings, sym)), abs=1e-12)
    # the Monte Carlo mean of a maximum lies above it
    assert res.monte_carlo("E").estimate != res.estimate("E")


def test_model_errors():
    with pytest.raises(InputError, match="together"):
        UncertaintyModel(air_temperature=20.0)
    with pytest.raises(InputError, match="together"):
        UncertaintyModel(expansion=11.5)
    with pytest.raises(InputError, match="equation"):
        UncertaintyModel(equation="edlen-1953")
    with pytest.raises(InputError, match="type_a"):
        UncertaintyModel(type_a="all")
    with pytest.raises(InputError, match=">= 0"):
        UncertaintyModel(resolution=-1.0)
    with pytest.raises(InputError, match="dead path needs the air"):
        UncertaintyModel(dead_path_mm=10.0)
    with pytest.raises(InputError, match="scalar"):
        UncertaintyModel(drift="mvnormal([0, 0], [[1, 0], [0, 1]])")
    two_runs = PositioningTest([0.0, 1.0], np.zeros((2, 2, 2)))
    with pytest.raises(InputError, match="at least 3 runs"):
        positioning_model(two_runs, UncertaintyModel())
    with pytest.raises(InputError, match="no uncertain input"):
        positioning_model(two_runs, UncertaintyModel(type_a="none"))


def test_rotary_axis():
    x = np.random.default_rng(1).normal(0.0, 1.0, (4, 5, 2))
    test = PositioningTest([0.0, 90.0, 180.0, 270.0], x, unit="arcsec", target_unit="deg")
    with pytest.raises(InputError, match="rotary axis") as exc:
        positioning_model(test, UncertaintyModel(**MATERIAL))
    assert exc.value.field == "material_temperature"
    res = evaluate_uncertainty(test, UncertaintyModel(drift="uniform(-0.5, 0.5)"), 2000, seed=1)
    assert res.mc.samples.shape == (2000, 12)


def test_a_large_test_runs_in_smaller_blocks_with_the_same_numbers():
    from mtmc.positioning.uncertainty import BLOCK_READINGS, block_trials

    x = np.random.default_rng(2).normal(0.0, 1.0, (64, 40, 2))
    test = PositioningTest(np.arange(64.0), x)
    assert block_trials(test) == 512  # 2**22 // 5120 = 819 readings → 512
    assert 512 * 2 * 64 * 40 <= BLOCK_READINGS
    small = evaluate_uncertainty(test, UncertaintyModel(), 1200, seed=3)
    big = evaluate_uncertainty(test, UncertaintyModel(), 1200, seed=3, block_size=8192)
    # the engine's draws do not depend on the evaluation blocks: bit for bit
    np.testing.assert_array_equal(small.mc.samples, big.mc.samples)
