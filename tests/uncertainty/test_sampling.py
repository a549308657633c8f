"""Seeded sampling: chunk independence, spawned children, name-keyed streams, seed records."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from mtmc.errors import DistributionError, InputError
from mtmc.uncertainty.distributions import MultivariateNormal, Normal, Triangular, Uniform
from mtmc.uncertainty.sampling import (
    DEFAULT_BLOCK_SIZE,
    SEED_BLOCK_SIZE,
    input_generator,
    iter_blocks,
    resolve_seed,
    sample_inputs,
)

INPUTS = {
    "x": Normal(1.0, 0.5),
    "y": Uniform(-1.0, 1.0),
    "v": MultivariateNormal([0.0, 1.0], [[1.0, 0.3], [0.3, 2.0]]),
    "c": 4.0,
    "t": "triangular(0, 1)",
}
TRIALS = 123_457  # not a multiple of any block size used


def _concat(blocks):
    out = {}
    starts = []
    for a, b, s in blocks:
        starts.append((a, b))
        for k, v in s.items():
            assert v.shape[0] == b - a
            out.setdefault(k, []).append(np.array(v))
    return {k: np.concatenate(v) for k, v in out.items()}, starts


@pytest.mark.parametrize("block_size", [1000, 4096, 10**5, SEED_BLOCK_SIZE, DEFAULT_BLOCK_SIZE])
@pytest.mark.parametrize("method", ["default", "box-muller"])
def test_blocks_identical_to_draw(block_size, method):
    ref = sample_inputs(INPUTS, TRIALS, seed=99, normal_method=method)
    got, spans = _concat(iter_blocks(INPUTS, TRIALS, 99, block_size, normal_method=method))
    assert spans[0][0] == 0
    assert spans[-1][1] == TRIALS
    assert all(b - a == block_size for a, b in spans[:-1])
    for k in INPUTS:
        np.testing.assert_array_equal(got[k], ref[k])
    assert ref["v"].shape == (TRIALS, 2)
    assert ref["x"].shape == (TRIALS,)


def test_seed_block_k_is_kth_spawned_child_keyed_by_name():
    seed = 2024
    x = sample_inputs({"x": Normal(0, 1)}, 2 * SEED_BLOCK_SIZE + 10, seed)["x"]
    key = int.from_bytes(hashlib.sha256(b"x").digest()[:8], "little")
    for k in range(3):
        child = np.random.SeedSequence(seed).spawn(k + 1)[k]
        assert child.spawn_key == (k,)
        grandchild = np.random.SeedSequence(seed, spawn_key=(*child.spawn_key, key))
        expected = np.random.default_rng(grandchild).standard_normal(SEED_BLOCK_SIZE)
        got = x[k * SEED_BLOCK_SIZE : (k + 1) * SEED_BLOCK_SIZE]
        np.testing.assert_array_equal(got, expected[: got.size])
    assert input_generator(seed, 1, "x").random() == input_generator(seed, 1, "x").random()


def test_dict_order_and_other_inputs_do_not_matter():
    a = sample_inputs({"x": Normal(0, 1), "y": Uniform(0, 1)}, 5000, 1)
    b = sample_inputs({"y": Uniform(0, 1), "x": Normal(0, 1)}, 5000, 1)
    c = sample_inputs({"x": Normal(0, 1), "z": Triangular(0, 1)}, 5000, 1)
    np.testing.assert_array_equal(a["x"], b["x"])
    np.testing.assert_array_equal(a["y"], b["y"])
    np.testing.assert_array_equal(a["x"], c["x"])
    assert not np.array_equal(a["x"], a["y"])


def test_shorter_run_is_a_prefix_of_longer_run():
    short = sample_inputs(INPUTS, 1000, 5)
    long = sample_inputs(INPUTS, 3 * SEED_BLOCK_SIZE + 7, 5)
    for k in INPUTS:
        np.testing.assert_array_equal(short[k], long[k][:1000])


def test_start_offset():
    ref = sample_inputs(INPUTS, 50_000, 3)
    got, _ = _concat(iter_blocks(INPUTS, 50_000, 3, 7000, start=20_000))
    for k in INPUTS:
        np.testing.assert_array_equal(got[k], ref[k][20_000:])


def test_different_seeds_differ():
    assert not np.array_equal(
        sample_inputs(INPUTS, 100, 1)["x"], sample_inputs(INPUTS, 100, 2)["x"]
    )


def test_block_views_are_read_only():
    _, _, s = next(iter(iter_blocks({"x": Normal(0, 1)}, 100, 1, 50)))
    with pytest.raises(ValueError, match="read-only"):
        s["x"][0] = 1.0


def test_resolve_seed():
    assert resolve_seed(17) == 17
    assert resolve_seed(np.int64(17)) == 17
    assert resolve_seed(np.random.SeedSequence(17)) == 17
    s = resolve_seed(None)
    assert isinstance(s, int)
    assert s >= 0
    assert s.bit_length() > 32
    # the recorded entropy reproduces the draws
    np.testing.assert_array_equal(
        sample_inputs(INPUTS, 100, s)["x"], sample_inputs(INPUTS, 100, s)["x"]
    )
    assert resolve_seed(None) != s


@pytest.mark.parametrize(
    ("seed", "msg"),
    [
        (-1, "non-negative integer"),
        (1.5, "non-negative integer"),
        (True, "non-negative integer"),
        (np.random.SeedSequence(1).spawn(1)[0], "root SeedSequence"),
    ],
)
def test_resolve_seed_errors(seed, msg):
    with pytest.raises(InputError, match=msg) as exc:
        resolve_seed(seed)
    assert exc.value.field == "seed"


def test_argument_errors():
    with pytest.raises(InputError, match="field trials: expected an integer >= 1"):
        sample_inputs(INPUTS, 0, 1)
    with pytest.raises(InputError, match="field block_size"):
        list(iter_blocks(INPUTS, 10, 1, 0))
    with pytest.raises(InputError, match="field normal_method"):
        sample_inputs(INPUTS, 10, 1, normal_method="polar")  # type: ignore[arg-type]
    with pytest.raises(DistributionError, match=r"field q: .*unknown distribution 'foo'"):
        sample_inputs({"q": "foo(1)"}, 10, 1)
    with pytest.raises(InputError, match="field seed: expected the integer seed"):
        sample_inputs(INPUTS, 10, None)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="mapping"):
        sample_inputs([Normal(0, 1)], 10, 1)  # type: ignore[arg-type]
