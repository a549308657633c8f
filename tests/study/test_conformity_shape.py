"""Every study kind that decides conformity writes one ``conformity`` shape (JCGM 106).

A propagate study (``[conformity]``), a study of several outputs (``[conformity.NAME]``), a
circular test (``[conformity.G_lsc]``) and a positioning test (``[tolerances]``) each decide
through :func:`mtmc.uncertainty.conformity` and write :meth:`Conformity.to_dict` with the
GUM's ``p_c`` beside it: the same keys in every ``result.json``, read back by
:func:`mtmc.load_result` to the same dict, and the same ``p_c`` as the engine's rule on the
quantity's Monte Carlo values recomputed here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mtmc.study import load_result, load_study, loads_study, write_result

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"

PROPAGATE = """\
kind = "propagate"
title = "Length at 500 mm"
model = "L * e_scale + e_temp"
output = "dx"
unit = "mm"

[inputs]
L = 500
e_scale = "normal(2e-6, 1e-6)"
e_temp = "uniform(-0.002, 0.002)"

[conformity]
upper = 0.003

[run]
trials = 2000
seed = 7
samples = true
"""

OUTPUTS = """\
kind = "propagate"
title = "Two lengths"
unit = "mm"

[outputs]
a = "x + y"
b = "x - y"

[inputs]
x = "normal(0, 0.001)"
y = "uniform(-0.001, 0.001)"

[conformity.a]
lower = -0.002
upper = 0.002
rule = "guarded"
guard = 0.5

[run]
trials = 2000
seed = 7
samples = true
"""


def _kinds() -> dict[str, Any]:
    return {
        "propagate": loads_study(PROPAGATE),
        "outputs": loads_study(OUTPUTS),
        "circular": load_study(STUDIES / "circle_xy.toml"),
        "positioning": load_study(STUDIES / "positioning_x.toml"),
    }


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Any, Any]]:
    out = {}
    for kind, study in _kinds().items():
        result = study.run(trials=400, seed=11, samples=True)
        folder = tmp_path_factory.mktemp("conf") / kind
        write_result(result, folder, study_text=study.source.text, report=False)
        out[kind] = (result, load_result(folder))
    return out


def test_every_kind_writes_one_conformity_shape(written: dict[str, tuple[Any, Any]]) -> None:
    shapes = {}
    for kind, (result, back) in written.items():
        decided = [q for q in result.quantities if q.conformity]
        assert decided, kind
        for q in decided:
            shapes.setdefault(frozenset(q.conformity), []).append(f"{kind}:{q.name}")
        # read back: the same dict, quantity by quantity
        for q, r in zip(result.quantities, back.quantities, strict=True):
            assert r.conformity == q.conformity, (kind, q.name)
    assert len(shapes) == 1, {tuple(sorted(k)): v for k, v in shapes.items()}


def test_p_c_is_the_engine_rule_on_the_samples(written: dict[str, tuple[Any, Any]]) -> None:
    """p_c = the fraction of the Monte Carlo values within the limits, in every kind."""
    for kind, (result, _) in written.items():
        for q in result.quantities:
            c = q.conformity
            if not c:
                continue
            y = np.asarray(result.samples[q.name], dtype=np.float64)
            lo = -np.inf if c["lower"] is None else c["lower"]
            hi = np.inf if c["upper"] is None else c["upper"]
            inside = np.mean((y >= lo) & (y <= hi))
            assert c["p_c"] == pytest.approx(inside, abs=1e-12), (kind, q.name)
