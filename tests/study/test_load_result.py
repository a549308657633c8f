"""Result folders read back, plain Monte Carlo results written, and ``[conformity]`` in studies.

The references: the :class:`StudyResult` that was written (every field, bit for bit),
the engine's :func:`mtmc.uncertainty.decision.conformity` on a Monte Carlo run of the
same seed, and :func:`mtmc.study.result.quantity` of the same values.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np
import pytest

import mtmc
from mtmc.errors import InputError
from mtmc.study import load_result, loads_study, study_result, write_result
from mtmc.study.result import Quantity, StudyResult, quantity
from mtmc.study.settings import RunSettings

STUDY = """\
kind = "propagate"
title = "Positioning deviation of an axis at 500 mm"
model = "L * e_scale + e_temp + e_probe"
output = "dx"
unit = "mm"

[inputs]
L = 500
e_scale = "normal(2e-6, 1e-6)"
e_temp = "uniform(-0.002, 0.002)"
e_probe = "normal(0, 0.0005)"

[conformity]
lower = -0.004
upper = 0.004
rule = "guarded"
guard = 0.5
prior = {mean = 0.0, sd = 0.002}

[run]
trials = 20000
seed = 7
samples = true
"""


def same(a: Any, b: Any, where: str = "") -> None:
    """Recursive equality: same types, arrays of the same dtype and bits, floats exactly."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        assert isinstance(a, np.ndarray), where
        assert isinstance(b, np.ndarray), where
        assert a.dtype == b.dtype, where
        np.testing.assert_array_equal(a, b, err_msg=where)
        return
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
        return
    if isinstance(a, dict) or hasattr(a, "keys"):
        assert set(a) == set(b), where
        for k in a:
            same(a[k], b[k], f"{where}[{k!r}]")
        return
    if isinstance(a, list | tuple):
        assert type(a) is type(b), where
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            same(x, y, f"{where}[{i}]")
        return
    if isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float), where
        assert math.isnan(b), where
        return
    assert type(a) is type(b) or {type(a), type(b)} <= {int, float}, where
    assert a == b, where


def test_a_written_study_result_loads_back_equal(tmp_path):
    study = loads_study(STUDY, file="positioning.toml")
    written = study.run()
    folder = write_result(written, tmp_path / "out", study_text=STUDY)
    loaded = load_result(folder)
    assert isinstance(loaded, StudyResult)
    # every field, bit for bit: floats through JSON with repr, arrays with their dtype
    same(written, loaded, "result")
    assert loaded.to_dict() == written.to_dict()
    # the samples come back from samples/dx.npy
    np.testing.assert_array_equal(loaded.samples["dx"], written.samples["dx"])
    # and the report drawn from the loaded result is the one drawn from the written one
    assert mtmc.render_report(loaded) == mtmc.render_report(written)


def test_load_result_refuses_what_is_not_a_result(tmp_path):
    with pytest.raises(InputError, match=r"no result\.json"):
        load_result(tmp_path)
    (tmp_path / "result.json").write_text('{"format": "other/1"}', encoding="utf-8")
    with pytest.raises(InputError, match="mtmc result") as info:
        load_result(tmp_path)
    assert info.value.file == str(tmp_path / "result.json")
    (tmp_path / "result.json").write_text('{"format": "mtmc-result/1"}', encoding="utf-8")
    with pytest.raises(InputError, match="no 'kind'"):
        load_result(tmp_path)


# --------------------------------------------------------------- plain Monte Carlo results
def test_write_result_and_render_report_take_a_plain_monte_carlo_result(tmp_path):
    model = mtmc.expression("a * b")
    inputs = {"a": "normal(2, 0.1)", "b": "uniform(2.8, 3.2)"}
    mc = mtmc.monte_carlo(model, inputs, trials=20_000, seed=4)
    folder = mtmc.write_result(mc, tmp_path / "mc")
    loaded = mtmc.load_result(folder)
    assert loaded.kind == "monte_carlo"
    assert (loaded.seed, loaded.trials) == (4, 20_000)
    # the quantity is the study layer's summary of the same values, default settings
    expected = quantity("y", "1", mc, None, RunSettings(trials=20_000, seed=4))
    same(expected.to_dict(), loaded.quantities[0].to_dict(), "y")
    page = mtmc.render_report(mc)
    assert page == mtmc.render_report(study_result(mc))
    assert "monte_carlo" in page
    prov = json.loads((folder / "provenance.json").read_text(encoding="utf-8"))
    assert prov["seed_entropy"] == str(np.random.SeedSequence(4).entropy)


def test_named_and_vector_outputs_become_quantities_and_a_region():
    def model(x, y):
        return {"s": x + y, "p": np.stack([x, y], axis=1)}

    r = mtmc.monte_carlo(model, {"x": "normal(0, 1)", "y": "normal(1, 2)"}, trials=5000, seed=2)
    g = mtmc.gum(lambda x, y: x + y, {"x": "normal(0, 1)", "y": "normal(1, 2)"})
    res = study_result(r, {"s": g}, unit="mm")
    assert [q.name for q in res.quantities] == ["s", "p[0]", "p[1]"]
    assert res.quantities[0].gum is not None  # the GUM beside the Monte Carlo
    assert res.quantities[0].gum.u == pytest.approx(math.sqrt(5.0), rel=1e-12)
    assert res.quantities[1].mc.u == r["p"].component(0).u  # the same reduction
    assert [reg.name for reg in res.regions] == ["p"]
    with pytest.raises(InputError, match="names output 'q'"):
        study_result(r, {"q": g})
    sketched = mtmc.monte_carlo(lambda x: x, {"x": "normal(0, 1)"}, trials=100, seed=1, keep=False)
    with pytest.raises(InputError, match="were not kept"):
        study_result(sketched)


# ------------------------------------------------------------------- [conformity] table
def test_the_study_decision_is_the_engines_on_the_same_run():
    study = loads_study(STUDY, file="positioning.toml")
    res = study.run()
    q: Quantity = res.quantity("dx")
    assert q.conformity is not None
    mc = mtmc.monte_carlo(study.model, study.inputs, trials=20_000, seed=7)
    g = mtmc.gum(study.model, study.inputs)
    c = mc.conformity(-0.004, 0.004, rule="guarded", guard=0.5, prior=(0.0, 0.002))
    # the same seed: the same values, the same fraction, bit for bit
    assert q.conformity["p_c"] == c.p_c
    assert q.conformity["text"] == c.text
    assert q.conformity["acceptance"] == [c.acceptance_lower, c.acceptance_upper]
    assert q.conformity["gum_p_c"] == g.conformity(-0.004, 0.004).p_c
    assert q.conformity["global_risks"] == c.global_risks.to_dict()
    # the report states it in one line near the top of the quantity
    page = mtmc.render_report(res)
    assert f"Conformity (JCGM 106): {c.text}." in page
    assert page.index("Conformity (JCGM 106)") < page.index("Uncertainty budget")


@pytest.mark.parametrize(
    ("old", "new", "field", "words"),
    [
        ('rule = "guarded"', 'rule = "strict"', "conformity.rule", "expected one of"),
        (
            "guard = 0.5",
            "guard = 0.5\nmax_consumer_risk = 0.05",
            "conformity.max_consumer_risk",
            "not both",
        ),
        ("guard = 0.5", "", "conformity.rule", "needs guard"),
        ('rule = "guarded"', 'rule = "simple"', "conformity.guard", "simple acceptance"),
        ("upper = 0.004", "upper = -0.004", "conformity.upper", "upper > lower"),
        ("guard = 0.5", "guard = 0.5\ntolerance = 1", "conformity.tolerance", "unknown key"),
        ("guard = 0.5", "max_consumer_risk = 0.6", "conformity.max_consumer_risk", "0.5"),
        ("sd = 0.002", "sd = 0", "conformity.prior.sd", "> 0"),
        ("guard = 0.5", 'guard = "half"', "conformity.guard", "number"),
    ],
)
def test_a_bad_conformity_table_names_file_line_and_field(old, new, field, words):
    text = STUDY.replace(old, new)
    with pytest.raises(InputError, match=words) as info:
        loads_study(text, file="positioning.toml")
    err = info.value
    assert err.file == "positioning.toml"
    assert err.field == field
    key = field.split(".")[-1]
    lines = text.splitlines()
    assert err.line is not None
    assert key in lines[err.line - 1] or "prior" in lines[err.line - 1]


def test_a_guard_band_wider_than_the_tolerance_is_named_at_run_time():
    text = STUDY.replace("guard = 0.5", "guard = 3")
    study = loads_study(text, file="positioning.toml")  # u is known only after the run
    with pytest.raises(InputError, match="no acceptance interval") as info:
        study.run()
    err = info.value
    assert (err.file, err.field) == ("positioning.toml", "conformity.guard")
    assert err.line == text.splitlines().index("guard = 3") + 1


def test_conformity_with_several_outputs_is_given_per_output():
    text = STUDY.replace('model = "L * e_scale + e_temp + e_probe"\noutput = "dx"\n', "").replace(
        "[conformity]", '[outputs]\ndx = "L * e_scale + e_temp + e_probe"\n\n[conformity]'
    )
    # the limits of one output at the top of [conformity]: refused, naming the first key
    with pytest.raises(
        InputError, match=r"a table of limits per output: \[conformity.dx\]"
    ) as info:
        loads_study(text, file="positioning.toml")
    assert info.value.field == "conformity.lower"
    # as a table of the output, the same decision as the study of one output, bit for bit
    per_output = loads_study(text.replace("[conformity]", "[conformity.dx]")).run()
    alone = loads_study(STUDY).run()
    assert per_output.quantity("dx").conformity == alone.quantity("dx").conformity


def test_mtmc_run_prints_the_decision_and_writes_a_folder_that_loads(tmp_path, capsys):
    from mtmc.cli.main import main

    study = tmp_path / "positioning.toml"
    study.write_text(STUDY, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(study), "-o", str(out), "--trials", "4000", "-q"]) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    lib = loads_study(STUDY, file=str(study)).run(trials=4000)
    q = lib.quantity("dx")
    assert q.conformity is not None
    # the library's decision, same seed, with the estimate and the limits it was held to
    assert printed[-2] == (
        f"conformity of dx (JCGM 106): {q.conformity['text']}; dx = "
        f"{q.conformity['estimate']:.6g} mm against T_L = -0.004 mm, T_U = 0.004 mm, "
        f"acceptance limits A_L = {q.conformity['acceptance'][0]:.6g} mm, "
        f"A_U = {q.conformity['acceptance'][1]:.6g} mm"
    )
    assert printed[-1] == f"report: {out / 'report.html'}"
    assert load_result(out).quantity("dx").conformity == q.conformity
