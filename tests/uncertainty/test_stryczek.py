"""Stryczek: eq. 5, Box–Muller (eq. 6, Fig. 3) and the sum of N(0,1) and N(0.5,0.5)."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from mtmc.uncertainty.montecarlo import monte_carlo

INPUTS = {"x1": "normal(0, 1)", "x2": "normal(0.5, 0.5)"}


def add(x1, x2):
    return x1 + x2


def test_sum_of_two_normals_has_u_sqrt_1_25():
    # Stryczek, Fig. 4: theory u = sqrt(1^2 + 0.5^2) = sqrt(1.25) = 1.118, y = 0.5
    m = 200_000
    for method in ("default", "box-muller"):
        r = monte_carlo(add, INPUTS, trials=m, seed=0, normal_method=method)
        u = math.sqrt(1.25)
        assert abs(r.u - u) <= 5 * u / math.sqrt(2 * m)
        assert abs(r.estimate - 0.5) <= 5 * u / math.sqrt(m)


def test_paper_size_run_is_within_sampling_spread():
    # the paper used 3000 trials and got y = 0.502, u = 1.117
    u = math.sqrt(1.25)
    for seed in range(5):
        r = monte_carlo(add, INPUTS, trials=3000, seed=seed, normal_method="box-muller")
        assert abs(r.u - u) <= 4 * u / math.sqrt(2 * 3000)
        assert abs(r.estimate - 0.5) <= 4 * u / math.sqrt(3000)


def test_u_is_eq5_with_m_minus_1():
    r = monte_carlo(add, INPUTS, trials=3000, seed=1)
    y = r.samples.tolist()
    mu = math.fsum(y) / len(y)
    u5 = math.sqrt(math.fsum((v - mu) ** 2 for v in y) / (len(y) - 1))
    assert abs(r.u - u5) <= 1e-12 * u5


def test_box_muller_fig3_histogram():
    # Fig. 3: 3000 Box–Muller samples compared with N(0, 1): chi-square on 20 equiprobable bins
    r = monte_carlo(lambda z: z, {"z": "normal(0, 1)"}, 3000, seed=3, normal_method="box-muller")
    edges = stats.norm.ppf(np.linspace(0, 1, 21))
    counts, _ = np.histogram(r.samples, edges)
    assert stats.chisquare(counts).pvalue > 1e-3


def test_interval_width_is_what_stryczek_calls_u():
    # Stryczek, p. 4: "[-1.658, 2.663] ... U equals 4.321": the printed U is the interval
    # length; mtmc's expanded uncertainty is half of it (JCGM 100 §6)
    r = monte_carlo(add, INPUTS, trials=200_000, seed=4)
    lo, hi = r.coverage_interval(0.95, "symmetric")
    assert r.expanded_uncertainty(0.95, "symmetric") == 0.5 * (hi - lo)
    # for this Gaussian output the interval is 0.5 ± 1.96 sqrt(1.25) = [-1.691, 2.691]
    sd = math.sqrt(1.25)
    z = stats.norm.ppf(0.975) * sd
    # five standard errors of a sample 2.5 % quantile, √(p(1 - p)/M) / g(η_p)
    se = math.sqrt(0.025 * 0.975 / 200_000) / (stats.norm.pdf(stats.norm.ppf(0.975)) / sd)
    assert abs(lo - (0.5 - z)) <= 5 * se
    assert abs(hi - (0.5 + z)) <= 5 * se
