"""Every study kind gives the same result folder, byte for byte, on every executor.

Each kind runs once in this process (the reference), then on two threads, two worker
processes and a real Dask ``LocalCluster`` of two worker processes (loopback), with its
blocks cut small so that several blocks go to the workers. The result folders are
compared file by file: ``result.json``, the CSV tables and the samples; of
``provenance.json`` all but the clock times. ``report.html`` is drawn from these files
alone (``mtmc report``), so it is left out to keep the test short.
"""

from __future__ import annotations

import json
import pickle
from pathlib import Path

import pytest

from conftest import absent
from mtmc.study import load_study, write_result
from mtmc.study.spec import loads_study
from mtmc.uncertainty import montecarlo

try:
    import distributed
except ImportError:
    absent("dask.distributed", 'pip install "mtmc[dask]"')

from mtmc.parallel import local_cluster

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
TRIALS = 300
BLOCK = 100  # trials per evaluation block: three blocks, two of them on the workers

#: a ``sweep`` study: the bcs_origin graph on a small grid
SWEEP = """\
kind = "sweep"
title = "sweep on every executor"
graph = "../graphs/bcs_origin.toml"
outputs = ["d_ac"]

[run]
trials = 300
seed = 5

[sweep]
output = "d_ac"
trials = 200
intercept = true

[sweep.vary]
"probe.u_probe" = "0.001:0.005:3"
"probe.u_axis" = "0.001:0.003:2"
"""

KINDS = {
    "propagate": "mass_calibration.toml",
    "graph": "axis_c.toml",
    "sweep": None,
    "kinematics": "five_axis.toml",
    "verification": "aguado2017.toml",
    "artefact": "wang2022.toml",
    "positioning": "positioning_x.toml",
}


def _study(kind: str):
    name = KINDS[kind]
    if name is None:
        return loads_study(SWEEP, file=str(STUDIES / "sweep.toml"), folder=STUDIES)
    return load_study(STUDIES / name)


@pytest.fixture(scope="module")
def client():
    cluster = local_cluster(2, scheduler_port=0)
    try:
        with distributed.Client(cluster) as c:
            yield c
    finally:
        cluster.close()


@pytest.fixture
def small_blocks(monkeypatch):
    original = montecarlo.evaluation_block_size
    monkeypatch.setattr(
        montecarlo,
        "evaluation_block_size",
        lambda dists, size: min(BLOCK, original(dists, size)),
    )


def _folder(study, out: Path, **parallel) -> dict[str, bytes]:
    result = study.run(trials=TRIALS, seed=11, samples=True, **parallel)
    write_result(result, out, study_text=study.source.text, argv=["mtmc"], report=False)
    files = {}
    for path in sorted(out.rglob("*")):
        if path.is_file():
            data = path.read_bytes()
            if path.name == "provenance.json":
                prov = json.loads(data)
                del prov["started"], prov["finished"]
                data = json.dumps(prov, sort_keys=True).encode()
            files[str(path.relative_to(out))] = data
    return files


@pytest.mark.usefixtures("small_blocks")
@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_executor_writes_the_same_folder(kind, tmp_path, client):
    study = _study(kind)
    assert study.kind == kind
    ref = _folder(study, tmp_path / "one")
    assert "result.json" in ref
    runs = {
        "thread": {"workers": 2, "executor": "thread"},
        "process": {"workers": 2, "executor": "process"},
        "dask": {"executor": "dask", "scheduler": client},
    }
    differ = []
    for name, parallel in runs.items():
        got = _folder(study, tmp_path / name, **parallel)
        assert sorted(got) == sorted(ref), name
        differ += [f"{name}: {f}" for f, data in ref.items() if got[f] != data]
    assert differ == [], kind


@pytest.mark.parametrize("name", ["five_axis.toml", "wang2022.toml", "axis_c.toml"])
def test_library_models_are_picklable(name):
    """The models the library builds are module-level callables holding their data."""
    from mtmc.artefact.simulation import study_model
    from mtmc.graph.run import graph_model
    from mtmc.study.kinematics import tool_positions_model

    study = load_study(STUDIES / name)
    if study.kind == "kinematics":
        model = tool_positions_model(study.machine, study.poses)
    elif study.kind == "artefact":
        model = study_model(study.study)[0]
    else:
        from mtmc.graph.model import check_graph

        model = graph_model(check_graph(study.graph), study.outputs[0])[0]
    again = pickle.loads(pickle.dumps(model))
    assert type(again) is type(model)
