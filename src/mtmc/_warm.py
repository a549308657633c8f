"""Imported by each worker process of :func:`mtmc.parallel.local_cluster` as it starts.

A task reaches a Dask worker pickled, and unpickling its model imports the modules the
model was built from: a graph's take 0.2 s, a verification's 0.3 s, a worker. A fresh
cluster's first run would pay that while its workers wait for their first task (the
Stryczek sweep of 25 grid points: 1.29 s on a fresh cluster against 1.06–1.14 s after).
The workers import them here instead, once per cluster, as they start (0.38 s, the
workers side by side).

A cluster started by :mod:`mtmc.parallel` for one call also sets Dask's log level in its
workers here (the setting ``mtmc.worker-log-level``, passed down with the cluster's Dask
configuration).
"""

from __future__ import annotations

import importlib
import logging

#: What the models of the study kinds are made of, and the engine's blocks.
MODULES = (
    "mtmc.uncertainty.montecarlo",
    "mtmc.study",
    "mtmc.graph.run",
    "mtmc.verification.simulate",
    "mtmc.artefact.simulation",
    "mtmc.kinematics.machine",
    "mtmc.positioning.uncertainty",
)

for _name in MODULES:
    try:
        importlib.import_module(_name)
    except ImportError:  # a warm-up never stops a worker: its tasks import what they need
        pass

try:
    import dask
except ImportError:  # pragma: no cover - imported by Dask workers, where dask is
    pass
else:
    _level = dask.config.get("mtmc.worker-log-level", None)
    if _level is not None:
        logging.getLogger("distributed").setLevel(_level)
