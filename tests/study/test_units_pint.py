"""Units of a propagate study's inputs (pint): recorded, and the model checked against them.

The references are the rules of quantity calculus, worked by hand: a sum takes one unit,
``sin`` an angle in rad, a model's unit is the product and quotient of its inputs' units,
and the output's unit equals the model's to the factor 1 (the engine converts nothing).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from mtmc.errors import InputError
from mtmc.study import loads_study, write_result
from mtmc.study.units import model_unit, read_unit, unit_text
from mtmc.uncertainty.formula import expression

MASS = """\
kind = "propagate"
model = "(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000"
output = "dm"
unit = "mg"
[inputs]
m_rc = {dist = "normal(100000.000, 0.050)", unit = "mg"}
dm_rc = {dist = "normal(1.234, 0.020)", unit = "mg"}
rho_a = {dist = "uniform(1.10, 1.30)", unit = "kg/m^3"}
rho_w = {dist = "uniform(7000, 9000)", unit = "kg/m^3"}
rho_r = {dist = "uniform(7950, 8050)", unit = "kg/m^3"}
[run]
trials = 2000
seed = 1
"""


@pytest.mark.parametrize(
    ("model", "units", "expected"),
    [
        ("L * (1 + alpha * dT)", {"L": "mm", "alpha": "1/K", "dT": "K"}, "mm"),
        ("sqrt(x**2 + y**2)", {"x": "um", "y": "um"}, "µm"),
        ("F / (pi * d**2 / 4)", {"F": "N", "d": "mm"}, "N/mm²"),
        ("r * cos(theta)", {"r": "mm", "theta": "rad"}, "mm"),
        ("arctan2(y, x)", {"x": "mm", "y": "mm"}, "rad"),
        ("m * g", {"m": "kg", "g": "m/s^2"}, "kg·m/s²"),
        ("x - 1.5", {"x": "mm"}, "mm"),  # a bare number takes the unit it is added to
        ("2 * x", {"x": "1"}, "1"),
    ],
)
def test_the_unit_of_a_model_is_that_of_quantity_calculus(
    model: str, units: dict[str, str], expected: str
) -> None:
    got = model_unit(expression(model), units)
    assert got == read_unit(expected.replace("·", "*").replace("²", "^2"))
    assert unit_text(got) == expected


@pytest.mark.parametrize(
    ("model", "units", "words"),
    [
        ("x + y", {"x": "mm", "y": "kg"}, "+ of mm and kg"),
        ("x + y", {"x": "mm", "y": "m"}, "+ of mm and m"),  # same dimension, no conversion
        ("sin(x)", {"x": "mm"}, "sin takes an angle in rad or a pure number"),
        ("sin(x)", {"x": "deg"}, "sin takes an angle in rad (the engine converts nothing)"),
        ("exp(x)", {"x": "K"}, "exp takes a pure number"),
        ("x ** y", {"x": "mm", "y": "1"}, "to a power computed by the model"),
        ("arctan2(y, x)", {"x": "mm", "y": "s"}, "arctan2 takes two quantities of one unit"),
    ],
)
def test_a_model_its_units_refuse_is_named(model: str, units: dict[str, str], words: str) -> None:
    with pytest.raises(InputError, match=re.escape(words)):
        model_unit(expression(model), units)


def test_the_mass_calibration_with_units_records_them(tmp_path: Path) -> None:
    study = loads_study(MASS)
    result = study.run()
    units = {x["name"]: x["unit"] for x in result.inputs}
    assert units == {
        "m_rc": "mg",
        "dm_rc": "mg",
        "rho_a": "kg/m³",
        "rho_w": "kg/m³",
        "rho_r": "kg/m³",
    }
    # the numbers are those of the same study without units, bit for bit
    bare = MASS
    for text, unit in (("mg", "mg"), ("kg/m^3", "kg/m^3")):
        bare = bare.replace(f', unit = "{unit}"', "")
        del text
    plain = loads_study(bare).run()
    assert result.quantities[0].mc.estimate == plain.quantities[0].mc.estimate
    assert result.quantities[0].mc.U == plain.quantities[0].mc.U
    # the report's input table and budget have a unit column
    write_result(result, tmp_path / "r", study_text=MASS)
    page = (tmp_path / "r" / "report.html").read_text("utf-8")
    assert "<td>kg/m³</td>" in page
    doc = json.loads((tmp_path / "r" / "result.json").read_text("utf-8"))
    assert {x["name"]: x["unit"] for x in doc["inputs"]} == units


@pytest.mark.parametrize(
    ("old", "new", "where", "words"),
    [
        ('unit = "mg"\n[inputs]', 'unit = "g"\n[inputs]', ":4: field unit", "0.001 g"),
        (
            '"uniform(7950, 8050)", unit = "kg/m^3"',
            '"uniform(7950, 8050)", unit = "g/cm^3"',
            ":2: field model",
            "- of m³/kg and cm³/g",
        ),
        (
            '"normal(1.234, 0.020)", unit = "mg"',
            '"normal(1.234, 0.020)"',
            ":7: field inputs.dm_rc",
            "dm_rc has no unit",
        ),
        (
            'unit = "kg/m^3"}\nrho_w',
            'unit = "furlongs per fortnight!"}\nrho_w',
            ":8: field inputs.rho_a.unit",
            "expected a unit such as",
        ),
        ('unit = "mg"\n[inputs]', 'unit = "m"\n[inputs]', ":4: field unit", "another quantity"),
    ],
)
def test_a_study_whose_units_do_not_agree_names_the_line(
    old: str, new: str, where: str, words: str
) -> None:
    assert old in MASS
    with pytest.raises(InputError) as info:
        loads_study(MASS.replace(old, new))
    assert f"<study>{where}" in str(info.value)
    assert words in str(info.value)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("furlongs per fortnight!", "expected a unit such as"),
        ("parsec_xyz", "expected a unit such as"),
        ("__import__", "expected a unit such as"),
        ("2 mm", "expected a unit such as"),
        ("m^1e308", "powers of at most 12"),
        ("m" * 101, "at most 100 characters"),
    ],
)
def test_a_unit_text_is_a_unit_or_a_clear_error(text: str, words: str) -> None:
    with pytest.raises(InputError, match=re.escape(words)):
        read_unit(text)


def test_each_output_of_outputs_is_checked_against_its_unit() -> None:
    text = """\
kind = "propagate"
[outputs]
area = {model = "a * b", unit = "mm^2"}
sum = {model = "a + b", unit = "mm"}
[inputs]
a = {dist = "normal(10, 0.01)", unit = "mm"}
b = {dist = "normal(20, 0.01)", unit = "mm"}
[run]
trials = 200
seed = 1
"""
    result = loads_study(text).run()
    assert {x["name"]: x["unit"] for x in result.inputs} == {"a": "mm", "b": "mm"}
    with pytest.raises(InputError) as info:
        loads_study(text.replace('unit = "mm^2"', 'unit = "mm"'))
    assert "<study>:3: field outputs.area" in str(info.value)
    assert "the model gives mm²" in str(info.value)


def test_type_a_readings_take_a_unit_too() -> None:
    text = """\
kind = "propagate"
model = "d - d0"
unit = "mm"
[inputs]
d = {data = [10.0121, 10.0097, 10.0108, 10.0113], unit = "mm"}
d0 = {dist = "constant(10)", unit = "mm"}
[run]
trials = 200
seed = 1
"""
    result = loads_study(text).run()
    assert [x["unit"] for x in result.inputs] == ["mm", "mm"]
    assert "type_a" in result.inputs[0]
