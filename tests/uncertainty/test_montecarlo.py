"""monte_carlo: reproducibility, shape/NaN checks, Box–Muller, and JCGM 101 clause 9 examples."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from mtmc.errors import DistributionError, InputError
from mtmc.uncertainty.distributions import MultivariateNormal, Normal, Uniform
from mtmc.uncertainty.montecarlo import monte_carlo
from mtmc.uncertainty.tolerance import numerical_tolerance

M = 200_000


def additive(x1, x2, x3, x4):
    return x1 + x2 + x3 + x4


def mass_calibration(m_w, dm_r, rho_a, rho_w, rho_r):
    """JCGM 101 §9.3: δm = (m_W + δm_R)(1 + (ρ_a - ρ_a0)(1/ρ_W - 1/ρ_R)) - m_nom, in mg."""
    return (m_w + dm_r) * (1.0 + (rho_a - 1.2) * (1.0 / rho_w - 1.0 / rho_r)) - 100_000.0


MASS_INPUTS = {
    "m_w": Normal(100_000.000, 0.050),
    "dm_r": Normal(1.234, 0.020),
    "rho_a": Uniform(1.10, 1.30),
    "rho_w": Uniform(7000.0, 9000.0),
    "rho_r": Uniform(7950.0, 8050.0),
}

ADD_INPUTS = {
    "x1": "normal(0, 1)",
    "x2": "uniform(-1, 1)",
    "x3": Normal(0.5, 0.2),
    "x4": "triangular(0, 2)",
}


def _same(a, b):
    np.testing.assert_array_equal(a.samples, b.samples)
    assert a.seed == b.seed
    assert a.trials == b.trials


@pytest.mark.parametrize("trials", [123_457, 100_000])
def test_bit_identical_across_block_sizes(trials):
    runs = [
        monte_carlo(additive, ADD_INPUTS, trials=trials, seed=42, block_size=bs)
        for bs in (1000, 4096, 10**5)
    ]
    _same(runs[0], runs[1])
    _same(runs[0], runs[2])
    assert runs[0].u == runs[2].u
    assert runs[0].coverage_interval() == runs[2].coverage_interval()


def test_workers_threads_and_processes_identical():
    ref = monte_carlo(additive, ADD_INPUTS, trials=100_003, seed=7, block_size=10_000)
    _same(ref, monte_carlo(additive, ADD_INPUTS, 100_003, 7, block_size=10_000, workers=2))
    proc = monte_carlo(
        additive, ADD_INPUTS, 100_003, 7, block_size=30_000, workers=2, executor="process"
    )
    _same(ref, proc)


def test_process_pool_refuses_lambda():
    with pytest.raises(InputError, match="picklable"):
        monte_carlo(lambda x: x, {"x": "normal(0, 1)"}, 1000, 1, workers=2, executor="process")


def test_dict_order_irrelevant():
    rev = dict(reversed(list(ADD_INPUTS.items())))
    _same(
        monte_carlo(additive, ADD_INPUTS, 20_000, seed=3),
        monte_carlo(additive, rev, 20_000, seed=3),
    )


def test_seed_none_is_recorded_and_reproduces():
    a = monte_carlo(additive, ADD_INPUTS, 10_000)
    assert isinstance(a.seed, int)
    assert a.seed.bit_length() > 32
    _same(a, monte_carlo(additive, ADD_INPUTS, 10_000, seed=a.seed))
    b = monte_carlo(additive, ADD_INPUTS, 10_000, seed=np.random.SeedSequence(a.seed))
    _same(a, b)


def test_model_wrong_shape_is_named():
    with pytest.raises(InputError) as exc:
        monte_carlo(lambda x: x[:-1], {"x": "normal(0, 1)"}, trials=1000, seed=1, block_size=400)
    msg = str(exc.value)
    assert "field model" in msg
    assert "returned shape (399,) for a block of 400 trials" in msg
    assert "expected (400,) or (400, d)" in msg
    with pytest.raises(InputError, match=r"returned shape \(\)"):
        monte_carlo(lambda x: 3.0, {"x": "normal(0, 1)"}, trials=100, seed=1)  # noqa: ARG005
    with pytest.raises(InputError, match="could not be called with the inputs x"):
        monte_carlo(lambda y: y, {"x": "normal(0, 1)"}, trials=100, seed=1)
    with pytest.raises(InputError, match="callable"):
        monte_carlo(3, {"x": "normal(0, 1)"}, trials=100, seed=1)  # type: ignore[arg-type]


def test_nan_policy():
    def model(x):
        with np.errstate(invalid="ignore"):
            return np.sqrt(x)

    inputs = {"x": Normal(3.0, 1.0)}
    ref = monte_carlo(lambda x: x, inputs, 50_000, seed=5)
    nneg = int(np.count_nonzero(ref.samples < 0))
    assert nneg > 0
    first = int(np.argmax(ref.samples < 0))
    with pytest.raises(InputError) as exc:
        monte_carlo(model, inputs, 50_000, seed=5)
    assert f"not finite (NaN or inf) in {nneg} of 50000 trials (first at trial {first})" in str(
        exc.value
    )
    r = monte_carlo(model, inputs, 50_000, seed=5, nan_policy="omit")
    assert r.omitted == nneg
    assert r.samples.shape == (50_000 - nneg,)
    assert r.trials == 50_000
    np.testing.assert_array_equal(r.samples, np.sqrt(ref.samples[ref.samples >= 0]))
    with pytest.raises(InputError, match="nan_policy"):
        monte_carlo(model, inputs, 100, seed=5, nan_policy="ignore")  # type: ignore[arg-type]


def test_model_inputs_are_read_only():
    def model(x):
        x *= 2
        return x

    with pytest.raises(ValueError, match="read-only"):
        monte_carlo(model, {"x": "normal(0, 1)"}, 100, seed=1)


def test_vector_output_and_vector_input():
    cov = [[1.0, 0.5], [0.5, 2.0]]

    def model(p, s):
        return np.column_stack([p[:, 0] + s, p[:, 1] - s, p[:, 0] * 0 + 1.0])

    r = monte_carlo(model, {"p": MultivariateNormal([1, 2], cov), "s": "normal(0, 0.5)"}, M, 3)
    assert r.samples.shape == (M, 3)
    assert r.dim == 3
    exact = np.array([[1.25, 0.25], [0.25, 2.25]])
    se = np.sqrt((np.outer(np.diag(exact), np.diag(exact)) + exact**2) / M)
    assert np.all(np.abs(r.cov[:2, :2] - exact) <= 5 * se)
    np.testing.assert_allclose(r.estimate_vector[:2], [1, 2], atol=5 * math.sqrt(2.25 / M))


def test_bad_arguments():
    with pytest.raises(InputError, match="field trials"):
        monte_carlo(additive, ADD_INPUTS, trials=1, seed=1)
    with pytest.raises(InputError, match="field workers"):
        monte_carlo(additive, ADD_INPUTS, 100, seed=1, workers=0)
    with pytest.raises(DistributionError, match="field x1"):
        monte_carlo(additive, {**ADD_INPUTS, "x1": "normal(1)"}, 100, seed=1)


def test_box_muller_histogram_matches_standard_normal():
    r = monte_carlo(
        lambda z: z, {"z": "normal(0, 1)"}, 100_000, seed=11, normal_method="box-muller"
    )
    assert abs(r.estimate) <= 5 / math.sqrt(1e5)
    assert abs(r.u - 1) <= 5 / math.sqrt(2e5)
    # chi-square test of the histogram on 40 equiprobable bins
    edges = stats.norm.ppf(np.linspace(0, 1, 41))
    counts, _ = np.histogram(r.samples, edges)
    chi2 = stats.chisquare(counts)
    assert chi2.pvalue > 1e-3
    assert stats.kstest(r.samples, "norm").pvalue > 1e-3
    # and it is a different stream from the default method
    d = monte_carlo(lambda z: z, {"z": "normal(0, 1)"}, 1000, seed=11)
    assert not np.array_equal(d.samples, r.samples[:1000])


def test_jcgm101_9_2_additive_normal():
    # JCGM 101 §9.2.2 Table 2: four N(0, 1) inputs, u(y) = 2.00, 95 % interval [-3.92, 3.92]
    inputs = {f"x{i}": "normal(0, 1)" for i in range(1, 5)}
    r = monte_carlo(additive, inputs, M, seed=92)
    assert abs(r.estimate) <= 5 * 2 / math.sqrt(M)
    assert abs(r.u - 2.0) <= 5 * 2 / math.sqrt(2 * M)
    lo, hi = r.coverage_interval(0.95, "symmetric")
    se = math.sqrt(0.025 * 0.975 / M) / (stats.norm.pdf(1.96) / 2)
    assert abs(lo + 3.92) <= 5 * se + 0.005
    assert abs(hi - 3.92) <= 5 * se + 0.005


def irwin_hall(n=4):
    """CDF and PDF of the sum of n R(0, 1) variables (Irwin–Hall, closed form)."""

    def cdf(x):
        return sum(
            (-1) ** k * math.comb(n, k) * max(x - k, 0.0) ** n for k in range(n + 1)
        ) / math.factorial(n)

    def pdf(x):
        return sum(
            (-1) ** k * math.comb(n, k) * max(x - k, 0.0) ** (n - 1) for k in range(n + 1)
        ) / math.factorial(n - 1)

    return cdf, pdf


def test_jcgm101_9_2_additive_rectangular():
    # JCGM 101 §9.2.3 Table 3: four R(-√3, √3) inputs; u = 2.00, MCM and exact [-3.88, 3.88]
    a = math.sqrt(3)
    inputs = {f"x{i}": Uniform(-a, a) for i in range(1, 5)}
    r = monte_carlo(additive, inputs, M, seed=93)
    assert abs(r.u - 2.0) <= 5 * 2 / math.sqrt(2 * M)
    # Y = -4a + 2a S with S the Irwin–Hall sum of four R(0, 1)
    cdf, pdf = irwin_hall()
    s975 = optimize.brentq(lambda x: cdf(x) - 0.975, 0.0, 4.0, xtol=1e-14)
    exact_hi = 2 * a * s975 - 4 * a
    assert exact_hi == pytest.approx(3.88, abs=0.005)  # the published value
    se = math.sqrt(0.025 * 0.975 / M) / (pdf(s975) / (2 * a))
    lo, hi = r.coverage_interval(0.95, "symmetric")
    assert abs(hi - exact_hi) <= 5 * se
    assert abs(lo + exact_hi) <= 5 * se


def test_jcgm101_9_3_mass_calibration():
    """JCGM 101 §9.3 against its exact output moments and interval length.

    δm = M (1 + AB) - 10⁵ with M ~ N(100 001.234, 0.050² + 0.020²), A = ρ_a - 1.2,
    B = 1/ρ_W - 1/ρ_R: E = 1.234 mg exactly (E[A] = 0) and
    Var = σ² (1 + E[A²]E[B²]) + μ² E[A²]E[B²] (u = 0.075480 mg; published MCM:
    1.2341 mg, 0.0754 mg from 10⁶ trials). The exact shortest 95 % interval,
    [1.084433, 1.383567] mg (length 0.299133 mg, PDF g = 0.73915 mg⁻¹ at both ends), is
    computed by quadrature in ``test_jcgm101_clause9._mass_exact``. The length of a
    shortest interval varies like the difference of the quantiles at 0.025 and 0.975:
    standard error √(2 × 0.025 × 0.95 / M) / g. Its location is checked there."""
    r = monte_carlo(mass_calibration, MASS_INPUTS, M, seed=930)
    mu, var_m = 100_001.234, 0.050**2 + 0.020**2
    e_w, e_w2 = math.log(9 / 7) / 2000, (1 / 7000 - 1 / 9000) / 2000
    e_r, e_r2 = math.log(8050 / 7950) / 100, (1 / 7950 - 1 / 8050) / 100
    e_ab2 = 0.1**2 / 3 * (e_w2 - 2 * e_w * e_r + e_r2)
    u = math.sqrt(var_m * (1 + e_ab2) + mu**2 * e_ab2)
    assert u == pytest.approx(0.075480, abs=5e-7)
    assert abs(r.estimate - 1.234) <= 5 * u / math.sqrt(M)
    assert abs(r.u - u) <= 5 * u / math.sqrt(2 * M)
    lo, hi = r.coverage_interval(0.95, "shortest")
    se_len = math.sqrt(2 * 0.025 * 0.95 / M) / 0.73915
    assert abs((hi - lo) - 0.299133) <= 5 * se_len
    # two significant digits of u agree with the published value: the §7.9.2 tolerance
    assert abs(r.u - 0.0754) <= numerical_tolerance(0.0754)


def test_given_executor_gives_identical_numbers():
    import concurrent.futures as cf

    from mtmc.parallel import map_blocks

    ref = monte_carlo(additive, ADD_INPUTS, 50_001, seed=8, block_size=7_000)
    with cf.ThreadPoolExecutor(max_workers=3) as pool:
        got = monte_carlo(additive, ADD_INPUTS, 50_001, seed=8, block_size=7_000, executor=pool)
        assert list(map_blocks(abs, [-3, 2, -1], executor=pool)) == [3, 2, 1]
    _same(ref, got)
    with pytest.raises(InputError, match="field executor"):
        list(map_blocks(abs, [1], workers=2, executor="cluster"))  # type: ignore[arg-type]
