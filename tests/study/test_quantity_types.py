"""The typed parts of a :class:`~mtmc.study.result.Quantity`: frozen, read back, in another unit.

The references: the ``result.json`` that :func:`mtmc.write_result` wrote from the same run
(the entry of the quantity, byte for byte as JSON), and the values of the quantity in mm
times 1000 for :meth:`Quantity.in_unit`.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import mtmc.study as ms
from mtmc.study import Quantity

STUDY = """\
kind = "propagate"
title = "Thermal expansion of a 100 mm gauge block, with its calibration"
model = "l * alpha * dt + d_cal + d_probe"
output = "dl"
unit = "mm"

[inputs]
l = 100
alpha = "normal(11.5e-6, 1e-6)"
dt = "uniform(-0.5, 0.5)"
d_cal = "normal(0, 0.00003)"
d_probe = "triangular(-0.0001, 0.0001)"

[run]
trials = 4000
seed = 12
"""

PARTS = {
    "mc": ms.MonteCarloSummary,
    "gum": ms.GumSummary,
    "validation": ms.ValidationSummary,
    "histogram": ms.Histogram,
    "convergence": ms.Convergence,
    "reported": ms.Reported,
}


@pytest.fixture(scope="module")
def q() -> Quantity:
    return ms.loads_study(STUDY, file="dl.toml").run().quantity("dl")


def test_the_parts_are_typed_frozen_and_read_only(q):
    for name, cls in PARTS.items():
        assert type(getattr(q, name)) is cls, name
    assert len(q.budget) == 5
    assert all(type(b) is ms.BudgetLine for b in q.budget)
    assert q.conformity is None
    for part in (q, *(getattr(q, n) for n in PARTS), *q.budget):
        first = dataclasses.fields(part)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(part, first, None)
    arrays = (q.histogram.edges, q.histogram.density, q.convergence.estimate, q.convergence.u)
    for a in arrays:
        assert a.dtype == np.float64
        assert not a.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            a[0] = 0.0
    assert q.convergence.m.dtype == np.int64
    assert not q.convergence.m.flags.writeable
    assert isinstance(q.mc.shortest, tuple)
    assert isinstance(q.mc.symmetric, tuple)
    assert q.mc.interval == "symmetric"
    assert q.mc.coverage_interval == q.mc.symmetric


def test_to_dict_is_the_written_json_and_reads_back_equal(q, tmp_path):
    result = ms.loads_study(STUDY, file="dl.toml").run()
    folder = ms.write_result(result, tmp_path / "out", study_text=STUDY)
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    written = doc["quantities"][0]
    assert json.dumps(q.to_dict()) == json.dumps(written)
    assert list(written) == [
        "name",
        "unit",
        "monte_carlo",
        "gum",
        "validation",
        "budget",
        "reported",
        "histogram",
        "convergence",
    ]
    # each part from what it wrote, and from that through JSON text
    assert q.gum is not None
    assert q.validation is not None
    for part in (*(getattr(q, n) for n in PARTS), *q.budget):
        cls = type(part)
        assert cls.from_dict(part.to_dict()) == part, cls.__name__
        assert cls.from_dict(json.loads(json.dumps(part.to_dict()))) == part, cls.__name__
    # the exactly known inputs: ν = ∞ is null in JSON and ∞ again when read
    assert written["budget"][0]["dof"] is None
    assert ms.BudgetLine.from_dict(written["budget"][0]).dof == float("inf")
    assert ms.load_result(folder).quantity("dl") == q


def test_in_unit_scales_the_values_and_keeps_k_p_shares_and_verdict(q):
    um = q.in_unit("µm", 1e3)
    assert um.unit == "µm"

    def times(x: float) -> float:
        return pytest.approx(1e3 * x, rel=1e-15, abs=0.0)

    for key in ("estimate", "u", "U"):
        assert getattr(um.mc, key) == times(getattr(q.mc, key)), key
    for key in ("shortest", "symmetric"):
        assert getattr(um.mc, key) == tuple(times(x) for x in getattr(q.mc, key)), key
    assert (um.mc.k, um.mc.p, um.mc.interval) == (q.mc.k, q.mc.p, q.mc.interval)
    assert (um.mc.trials, um.mc.omitted) == (q.mc.trials, q.mc.omitted)
    assert q.gum is not None
    assert um.gum is not None
    for key in ("estimate", "u", "U"):
        assert getattr(um.gum, key) == times(getattr(q.gum, key)), key
    assert um.gum.interval == tuple(times(x) for x in q.gum.interval)
    assert (um.gum.k, um.gum.dof, um.gum.method) == (q.gum.k, q.gum.dof, q.gum.method)
    assert q.validation is not None
    assert um.validation is not None
    for key in ("d_low", "d_high", "delta", "endpoint_std_error"):
        assert getattr(um.validation, key) == times(getattr(q.validation, key)), key
    for key in ("passed", "kind", "ndig", "verdict"):
        assert getattr(um.validation, key) == getattr(q.validation, key), key
    for a, b in zip(um.budget, q.budget, strict=True):
        assert a.contribution == times(b.contribution)
        assert a.sensitivity == (None if b.sensitivity is None else times(b.sensitivity))
        kept = ("name", "share", "dof", "estimate", "u")
        assert [getattr(a, k) for k in kept] == [getattr(b, k) for k in kept]
    np.testing.assert_allclose(um.histogram.edges, 1e3 * q.histogram.edges, rtol=1e-15)
    np.testing.assert_allclose(um.histogram.density, q.histogram.density / 1e3, rtol=1e-15)
    np.testing.assert_array_equal(um.convergence.m, q.convergence.m)
    np.testing.assert_allclose(um.convergence.u, 1e3 * q.convergence.u, rtol=1e-15)
    assert um.convergence.last_half_u == times(q.convergence.last_half_u)
    assert not um.histogram.edges.flags.writeable
    # the text is rounded again in the new unit (JCGM 100 §7.2.6)
    assert float(um.reported.U) == pytest.approx(1e3 * float(q.reported.U), rel=1e-12)
