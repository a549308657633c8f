"""A graph run is the engine's run of a compiled graph model: same seeds, same summaries."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.graph import load_graph, run_graph
from mtmc.graph.model import check_graph
from mtmc.graph.run import GraphModel, flatten, unflatten
from mtmc.uncertainty.montecarlo import monte_carlo

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "graphs"


@pytest.fixture(scope="module")
def axis_c():
    return check_graph(load_graph(EXAMPLES / "axis_c.toml"))


@pytest.mark.parametrize(
    ("block_size", "workers", "executor"),
    [(1000, 1, "thread"), (7777, 2, "thread"), (20_000, 2, "process")],
)
def test_summaries_do_not_depend_on_blocks_or_workers(axis_c, block_size, workers, executor):
    ref = run_graph(axis_c, trials=40_000, seed=3)
    got = run_graph(
        axis_c, trials=40_000, seed=3, block_size=block_size, workers=workers, executor=executor
    )
    for name, s in ref.places.items():
        np.testing.assert_array_equal(
            got.places[name].estimate_vector, s.estimate_vector, err_msg=name
        )
        np.testing.assert_array_equal(got.places[name].cov, s.cov, err_msg=name)


def test_graph_run_is_the_engine_run_of_the_compiled_model(axis_c):
    model = GraphModel(axis_c, ("p_c", "axis_c"))
    direct = monte_carlo(model, model.inputs, trials=5000, seed=8)
    run = run_graph(axis_c, trials=5000, seed=8, outputs=["p_c", "axis_c"], keep=["p_c"])
    np.testing.assert_array_equal(run.result("p_c").samples, direct["p_c"].samples)
    np.testing.assert_allclose(
        run.places["axis_c"].cov, direct["axis_c"].cov, rtol=1e-9, atol=1e-18
    )
    # a compiled model travels to worker processes whole
    again = pickle.loads(pickle.dumps(model))
    assert again.outputs == model.outputs
    assert list(again.inputs) == list(model.inputs)


def test_one_trial_is_refused_as_everywhere(axis_c):
    with pytest.raises(InputError, match="expected an integer >= 2, got 1"):
        run_graph(axis_c, trials=1, seed=1)
    with pytest.raises(InputError, match="expected an integer >= 2, got 1"):
        monte_carlo(lambda x: x, {"x": "normal(0, 1)"}, trials=1, seed=1)


def test_unflatten_inverts_flatten(axis_c):
    res = run_graph(axis_c, trials=50, seed=2, outputs=[], keep=list(axis_c.types))
    for name, value in res.samples.items():
        t = axis_c.types[name]
        flat = flatten(t, value, 50)
        np.testing.assert_array_equal(flatten(t, unflatten(t, flat), 50), flat)


def test_memory_of_a_graph_with_thousands_of_probings_is_bounded():
    """2 500 meas transitions at 10 trials: each input's seed block is drawn, sliced and
    dropped (one block of every input would take 328 MB); the file loads in linear time."""
    import time
    import tracemalloc

    from mtmc.graph.toml_format import loads_graph

    parts = ['units = "mm"', "[probe]", "u_axis = 0.002", "u_probe = 0.001"]
    for i in range(2500):
        parts += [
            "[[transition]]",
            f'name = "m{i}"',
            'op = "meas"',
            'coordinate = "x"',
            f"at = [{i}.0, 0.0, 0.0]",
            "direction = [1.0, 0.0, 0.0]",
            f'out = "x{i}"',
        ]
    t0 = time.perf_counter()
    graph = loads_graph("\n".join(parts))
    assert time.perf_counter() - t0 < 10.0  # was quadratic: 23 s for 2 000 transitions
    tracemalloc.start()
    res = run_graph(graph, trials=10, seed=1, outputs=["x7"])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 64 * 2**20
    assert res.places["x7"].u > 0


def test_per_coordinate_u_of_a_marked_point():
    from mtmc.graph.toml_format import loads_graph

    text = "\n".join(
        [
            'units = "um"',
            "[[place]]",
            'name = "a"',
            'type = "point"',
            "value = [1.0, 2.0, 3.0]",
            "u = [2.0, 0.0, 6.0]",
            "[[place]]",
            'name = "b"',
            'type = "point"',
            "value = [3.0, 2.0, 1.0]",
            "[[transition]]",
            'name = "t"',
            'op = "middle"',
            'in = ["a", "b"]',
            'out = "c"',
        ]
    )
    res = run_graph(loads_graph(text), trials=200_000, seed=4, outputs=["c"])
    u = res.places["c"].u_vector  # mm: half of (2, 0, 6) µm
    np.testing.assert_allclose(u[[0, 2]], [0.001, 0.003], rtol=0.01)  # se of u: 0.16 %
    assert u[1] < 1e-15  # a constant coordinate (to rounding of its mean)


def test_a_part_of_a_summarised_place_has_the_numbers_of_its_own_run(axis_c):
    """c_p0 and v_c are the point and direction of the line axis_c: summarised with it,
    they are read from its moments; summarised alone, they are reduced on their own."""
    both = run_graph(axis_c, trials=40_000, seed=11, outputs=["c_p0", "axis_c", "v_c"])
    alone = run_graph(axis_c, trials=40_000, seed=11, outputs=["v_c", "c_p0"])
    assert list(both.places) == ["c_p0", "axis_c", "v_c"]
    for name in ("c_p0", "v_c"):
        a, b = both.places[name], alone.places[name]
        assert a.type == b.type
        assert a.estimate_vector.tobytes() == b.estimate_vector.tobytes()
        assert a.cov.tobytes() == b.cov.tobytes()
        assert (a.result.trials, a.result.seed, a.result.kept) == (40_000, 11, False)
    kept = run_graph(axis_c, trials=40_000, seed=11, outputs=["axis_c", "v_c"], keep=["v_c"])
    assert kept.places["v_c"].result.kept


def test_part_variants_return_the_part_itself():
    from mtmc.geometry import Circle, Line, Plane, Sphere
    from mtmc.graph import ops

    values = {
        "line": Line([1.0, 2, 3], [0.0, 0, 2]),
        "plane": Plane([1.0, 2, 3], [0.0, 1, 1]),
        "circle": Circle([1.0, 2, 3], [0.0, 0, 1], 4.0),
        "sphere": Sphere([1.0, 2, 3], 4.0),
    }
    seen = set()
    for op in ops.op_names():
        for v in ops.variants(op):
            part = ops.PART_OF_INPUT.get(v.func)
            if part is not None:
                value = values[v.inputs[0]]
                assert v.func(value) is getattr(value, part)
                seen.add(v.func)
    assert seen == set(ops.PART_OF_INPUT)
