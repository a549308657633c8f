"""A constant output: its estimate is the constant and its u exactly 0, whatever the blocks.

The sum of ``n`` copies of ``c`` divided by ``n`` can miss ``c`` by an ulp; the deviations
from it then gave a constant a ``u`` of about 1e-17 (30° as 0.5235987755982989 rad with
u = 1.1e-16 in ``graph run``). Reference: the constant itself, exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.uncertainty import Normal, monte_carlo
from mtmc.uncertainty.results import Moments

C = float(np.radians(30.0))


def test_the_sum_of_copies_is_not_the_constant() -> None:
    # the premise: a naive mean of many copies misses the constant
    x = np.full(1000, 0.1)
    assert np.add.reduce(x) / x.size != 0.1


@pytest.mark.parametrize("value", [0.1, C, -7.3e-9, 1e300])
def test_moments_of_a_constant_column_are_exact(value: float) -> None:
    x = np.empty((1000, 2))
    x[:, 0] = value
    x[:, 1] = np.linspace(0.0, 1.0, 1000)
    m = Moments.of(x[:300]).merge(Moments.of(x[300:]))
    assert m.mean[0] == value
    assert m.m2[0, 0] == 0.0
    assert m.m2[0, 1] == 0.0
    # the other column as before (0.5 to a few ulp)
    assert m.mean[1] == pytest.approx(0.5, abs=1e-15)
    # NaN is never a constant (NaN != NaN): its mean stays NaN
    assert np.isnan(Moments.of(np.full((5, 1), np.nan)).mean[0])


@pytest.mark.parametrize("keep", [True, False])
@pytest.mark.parametrize("block_size", [1000, 4096])
def test_a_constant_output_of_the_engine_is_exact(keep: bool, block_size: int) -> None:
    r = monte_carlo(
        lambda a: np.stack([a * 0.0 + C, a], axis=1),
        {"a": Normal(0.0, 1.0)},
        10_000,
        7,
        keep=keep,
        block_size=block_size,
    )
    assert r.estimate_vector[0] == C
    assert r.u_vector[0] == 0.0
    assert r.u_vector[1] == pytest.approx(1.0, rel=0.03)  # 10⁴ normal draws: sd 0.7 %
