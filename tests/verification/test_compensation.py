"""Compensation tables: sampling, the ISG CSV / Etalon / plain CSV files, round trips, errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import InputError, ParseError
from mtmc.kinematics import ChebyshevSeries, LegendreSeries, Machine, PolynomialFunction
from mtmc.kinematics.parameters import ErrorModel
from mtmc.verification.compensation import (
    CompensationTable,
    compensation_table,
    dump_compensation,
    dumps_etalon,
    dumps_isg_csv,
    dumps_plain_csv,
    load_compensation,
    loads_etalon,
    loads_isg_csv,
    loads_plain_csv,
)

REF = Path(__file__).resolve().parents[1] / "reference" / "formats"
RNG = np.random.default_rng(np.random.SeedSequence(230))


def _model() -> tuple[ErrorModel, np.ndarray]:
    m = Machine.from_topology("CXFYZ")  # a rotary table C on X
    model = ErrorModel(
        m,
        {
            "EXX": LegendreSeries([0.0] * 4, low=0.0, high=2500.0),
            "EYX": ChebyshevSeries([0.0] * 3, low=0.0, high=2500.0),
            "EZY": PolynomialFunction([0.0] * 3),
            "ECZ": LegendreSeries([0.0] * 2, low=0.0, high=1200.0),
            "ECC": LegendreSeries([0.0] * 3, low=-np.pi, high=np.pi),
            "EC0Y": 0.0,
            "EB0Z": 0.0,
            "EX0C": 0.0,
            "EA0C": 0.0,
        },
    )
    theta = RNG.normal(size=model.n_parameters) * 1e-3
    theta[model.parameter_names.index("EZY[2]")] *= 1e-6
    return model, theta


GRID = {
    "X": np.linspace(0.0, 2500.0, 11),
    "Y": np.array([0.0, 375.0, 750.0, 1125.0, 1500.0]),
    "Z": np.linspace(0.0, 1200.0, 7),
    "C": np.deg2rad(np.arange(-180.0, 181.0, 30.0)),
}


def test_table_from_an_error_model_is_the_functions_on_the_grid() -> None:
    model, theta = _model()
    t = compensation_table(model, GRID, theta=theta)
    errs = model.errors(theta)
    assert set(t.constants) == {"EC0Y", "EB0Z", "EX0C", "EA0C"}
    assert {c.name for c in t.curves} == {"EXX", "EYX", "EZY", "ECZ", "ECC"}
    for c in t.curves:
        np.testing.assert_array_equal(c.positions, GRID[c.axis])
        np.testing.assert_array_equal(c.values, errs[c.name](GRID[c.axis]))
    for k, v in t.constants.items():
        assert v == float(errs[k])
    # the same from a plain mapping of functions, and the corrections are the negatives
    same = compensation_table(errs, GRID)
    assert same == t
    corr = compensation_table(errs, GRID, sign="correction")
    assert corr.sign == "correction"
    np.testing.assert_array_equal(corr.curve("EXX").values, -t.curve("EXX").values)
    assert corr.constants["EC0Y"] == -t.constants["EC0Y"]
    assert corr.with_sign("error") == t
    # back to functions: interpolating tables equal to the errors on the grid
    back = corr.errors()
    np.testing.assert_array_equal(back["EYX"](GRID["X"]), errs["EYX"](GRID["X"]))  # type: ignore[operator]


@pytest.mark.parametrize(
    ("writer", "reader"),
    [
        (dumps_isg_csv, loads_isg_csv),
        (dumps_etalon, loads_etalon),
        (dumps_plain_csv, loads_plain_csv),
    ],
)
@pytest.mark.parametrize("sign", ["error", "correction"])
def test_round_trip(writer, reader, sign: str) -> None:  # type: ignore[no-untyped-def]
    model, theta = _model()
    t = compensation_table(model, GRID, theta=theta, sign=sign)
    text = writer(t)
    assert f"sign = {sign}" in text
    back = reader(text, "t.txt")
    assert back.sign == sign
    assert back.constants == t.constants  # exact: shortest round-trip representation
    for c in t.curves:
        b = back.curve(c.name)
        np.testing.assert_array_equal(b.values, c.values)
        if c.axis == "C":  # written in degrees: rad -> deg -> rad to the last bits
            np.testing.assert_allclose(b.positions, c.positions, rtol=0, atol=1e-15)
        else:
            np.testing.assert_array_equal(b.positions, c.positions)
    # and the read-back table gives the identified functions on the grid
    errs = model.errors(theta)
    factor = 1.0 if sign == "error" else -1.0
    funcs = back.errors()
    for name in ("EXX", "EYX", "EZY", "ECZ"):
        axis = name[-1]
        np.testing.assert_array_equal(funcs[name](GRID[axis]), errs[name](GRID[axis]))  # type: ignore[operator]
        np.testing.assert_array_equal(back.curve(name).values, factor * errs[name](GRID[axis]))


def test_write_and_load_files(tmp_path: Path) -> None:
    model, theta = _model()
    t = compensation_table(model, GRID, theta=theta)
    for fmt in ("isg", "etalon", "csv"):
        p = dump_compensation(t, tmp_path / f"comp.{fmt}", fmt)
        back = load_compensation(p, fmt)
        np.testing.assert_array_equal(back.curve("ECZ").values, t.curve("ECZ").values)
    with pytest.raises(InputError, match="format"):
        dump_compensation(t, tmp_path / "x", "siemens")
    with pytest.raises(InputError, match="cannot read"):
        load_compensation(tmp_path / "missing.txt", "isg")


def _structure(text: str) -> list[list[object]]:
    """Non-comment lines as tokens, numbers as floats (layout and comments ignored)."""
    out: list[list[object]] = []
    for line in text.splitlines():
        s = line.split("//", 1)[0].strip()
        if not s:
            continue
        toks: list[object] = []
        for tok in s.split():
            try:
                toks.append(float(tok))
            except ValueError:
                toks.append(tok)
        out.append(toks)
    return out


def test_isg_reference_example() -> None:
    text = (REF / "isg_csv_example.txt").read_text()
    t = loads_isg_csv(text, "isg_csv_example.txt")
    # the values typed from the ISG documentation page
    assert t.sign == "error"
    assert t.constants == {"EY0A": 0.1, "EZ0A": 0.2, "EX0B": 0.11}
    expected = {
        "EXX": [0.02, 0.00],
        "EYX": [0.01, -0.1],
        "EZX": [0.07, 0.01],
        "EAX": [0.00, 0.00],
        "EBX": [0.0042, 0.0011],
        "ECX": [0.003, 0.002],
    }
    assert [c.name for c in t.curves] == list(expected)
    for name, vals in expected.items():
        np.testing.assert_array_equal(t.curve(name).positions, [0.0, 10.0])
        np.testing.assert_array_equal(t.curve(name).values, vals)
    written = dumps_isg_csv(t)
    assert _structure(written) == _structure(text)
    assert loads_isg_csv(written) == t


def test_etalon_reference_example() -> None:
    text = (REF / "etalon_exchange_example.txt").read_text()
    t = loads_etalon(text, "etalon_exchange_example.txt")
    assert t.constants == {"EC0B": 0.000022355737, "EA0B": 0.000047622950}
    c = t.curve("EXY")
    np.testing.assert_array_equal(c.positions, [-280.0, -270.0, -260.0, 260.0, 270.0])
    np.testing.assert_array_equal(
        c.values,
        [-0.001358635132, -0.000240680764, 0.000877273605, -0.001297146744, -0.000316265101],
    )
    written = dumps_etalon(t)
    assert _structure(written) == _structure(text)
    assert loads_etalon(written) == t


def test_tool_errors_only_in_plain_csv() -> None:
    t = CompensationTable({"EXT": 0.01, "EC0Y": 1e-5})
    with pytest.raises(InputError, match="plain CSV"):
        dumps_isg_csv(t)
    with pytest.raises(InputError, match="plain CSV"):
        dumps_etalon(t)
    assert loads_plain_csv(dumps_plain_csv(t)) == t


def test_table_input_errors() -> None:
    with pytest.raises(InputError, match="give a grid for Y"):
        compensation_table({"EXY": lambda q: q}, {"X": [0.0, 1.0]})
    with pytest.raises(InputError, match="expected a number, not a function"):
        compensation_table({"EC0Y": lambda q: q}, {})
    with pytest.raises(InputError, match="strictly increasing"):
        compensation_table({"EXX": 0.0}, {"X": [0.0, 0.0]})
    with pytest.raises(InputError, match="theta"):
        compensation_table(_model()[0], GRID)
    with pytest.raises(InputError, match="sign"):
        compensation_table({"EXX": 0.0}, {"X": [0.0]}, sign="minus")


ISG = """\
// sign = error
C0Y    X0C
0.1    0.2
#
X      EXX    EYX
0.0    0.02   0.01
10.0   0.00   -0.1
"""


@pytest.mark.parametrize(
    ("text", "line", "field", "message"),
    [
        (ISG.replace("   -0.1", ""), 7, "EYX", "expected 3 values"),
        (ISG.replace("0.01", "abc"), 6, "EYX", "expected a number"),
        (ISG.replace("C0Y", "Q0Y"), 2, "Q0Y", "unknown error name"),
        (ISG.replace("EYX", "EYZ"), 5, "EYZ", "not a component error of axis X"),
        (
            ISG.replace("X      EXX", "X Z    EXX")
            .replace("0.0    0.02", "0.0 0.0 0.02")
            .replace("10.0   0.00", "10.0 0.0 0.00"),
            5,
            "Z",
            "more than one axis",
        ),
        (ISG.replace("0.1    0.2\n", "0.1    0.2\n0.3    0.4\n"), 4, "C0Y", "exactly one row"),
        (ISG.replace("X      EXX", "Q      EXX"), 5, "Q", "unknown axis"),
    ],
)
def test_isg_errors_name_line_and_field(text: str, line: int, field: str, message: str) -> None:
    assert loads_isg_csv(ISG).constants == {"EC0Y": 0.1, "EX0C": 0.2}
    with pytest.raises(ParseError, match=message) as info:
        loads_isg_csv(text, "comp.csv")
    assert (info.value.file, info.value.line, info.value.field) == ("comp.csv", line, field)
    assert str(info.value).startswith(f"comp.csv:{line}: field {field}:")


ETALON = """\
[C0B]
VALUE = 0.00002
[EXY]
Gridpoints = {
-280.0 -0.0013
-270.0 -0.0002
}
"""


@pytest.mark.parametrize(
    ("text", "line", "field", "message"),
    [
        (ETALON.replace("}\n", ""), 4, "EXY", "not closed"),
        (ETALON.replace("-270.0 -0.0002", "-270.0"), 6, "EXY", "two numbers"),
        (ETALON.replace("-0.0013", "x1"), 5, "EXY", "expected a number"),
        (ETALON.replace("VALUE = 0.00002", "VALU = 0.00002"), 2, "VALU", "unknown key"),
        (ETALON.replace("[C0B]", "[EXX]"), 2, "EXX", "component error"),
        (ETALON.replace("[EXY]", "[B0C]"), 4, "EB0C", "expected VALUE"),
        (ETALON.replace("VALUE = 0.00002\n", ""), 1, "EC0B", "no VALUE"),
        (ETALON.replace("-270.0 -0.0002", "-290.0 -0.0002"), 3, "EXY", "increasing"),
    ],
)
def test_etalon_errors_name_line_and_field(text: str, line: int, field: str, message: str) -> None:
    assert loads_etalon(ETALON).curve("EXY").values.tolist() == [-0.0013, -0.0002]
    with pytest.raises(ParseError, match=message) as info:
        loads_etalon(text, "comp.txt")
    assert (info.value.file, info.value.line, info.value.field) == ("comp.txt", line, field)


CSV = """\
# sign = correction
error,axis,position,position_unit,value,value_unit
EC0Y,,,,1e-05,rad
EXX,X,0.0,mm,0.001,mm
EXX,X,100.0,mm,0.002,mm
"""


@pytest.mark.parametrize(
    ("edit", "line", "field", "message"),
    [
        (("0.002,mm", "0.002,um"), 5, "value_unit", "expected value_unit 'mm'"),
        (("100.0,mm", "100.0,deg"), 5, "position_unit", "position_unit 'mm'"),
        (("EXX,X,100.0", "EXX,Y,100.0"), 5, "axis", "function of axis X"),
        (("0.001,mm", "nan,mm"), 4, "value", "finite"),
        (("EC0Y,,,,", "EC0Y,X,,,"), 3, "axis", "must be empty"),
        (("error,axis", "name,axis"), 2, None, "expected the header"),
        (("EXX,X,100.0,mm,0.002,mm", "EXX,X,100.0,mm,0.002"), 5, None, "expected 6 fields"),
    ],
)
def test_plain_csv_errors(
    edit: tuple[str, str], line: int, field: str | None, message: str
) -> None:
    with pytest.raises(ParseError, match=message) as info:
        loads_plain_csv(CSV.replace(*edit), "comp.csv")
    assert (info.value.line, info.value.field) == (line, field)
    t = loads_plain_csv(CSV)
    assert t.sign == "correction"
    assert t.constants == {"EC0Y": 1e-05}
    assert math.isclose(t.curve("EXX").values[1], 0.002)


@pytest.mark.parametrize(
    ("writer", "reader"),
    [
        (dumps_isg_csv, loads_isg_csv),
        (dumps_etalon, loads_etalon),
        (dumps_plain_csv, loads_plain_csv),
    ],
)
def test_every_truncation_is_refused_or_the_whole_table(writer, reader) -> None:  # type: ignore[no-untyped-def]
    model, theta = _model()
    t = compensation_table(model, GRID, theta=theta)
    text = writer(t)
    assert reader(text) == t
    where: list[tuple[str | None, bool, bool]] = []
    for k in range(len(text) + 1):
        prefix = text[:k]
        try:
            back = reader(prefix, "cut.txt")
        except ParseError as exc:
            where.append((exc.file, exc.line is not None, "\n" in str(exc)))
            continue
        # read only when nothing but trailing whitespace is missing, and then the same table
        assert prefix.rstrip() == text.rstrip(), k
        assert back == t
    # every refusal is one line naming the file and the line
    assert set(where) == {("cut.txt", True, False)}


_CSV_HEAD = "error,axis,position,position_unit,value,value_unit\n"


@pytest.mark.parametrize(
    ("reader", "text", "line", "message"),
    [
        (loads_isg_csv, "", 1, "no table"),
        (loads_isg_csv, "// only a comment\n\n", 1, "no table"),
        (loads_etalon, "// only a comment\n", 1, "no table"),
        (loads_plain_csv, "# only a comment\n", 1, "no header"),
        (loads_plain_csv, "# sign = error\n" + _CSV_HEAD, 2, "no table"),
        (loads_isg_csv, ISG.replace("sign = error", "sign = foo"), 1, "'sign = foo'"),
        (loads_isg_csv, ISG.replace("sign = error", "sign = corrections"), 1, "corrections"),
        (loads_etalon, "// sign = errors\n" + ETALON, 1, "'sign = errors'"),
        (loads_plain_csv, CSV.replace("sign = correction", "sign = foo"), 1, "'sign = foo'"),
        (loads_plain_csv, CSV + "# sign = error\n", 6, "second sign line"),
        (
            loads_plain_csv,
            CSV + "EYX,X,0.0,mm,0.1,mm\n",
            6,
            "EYX has 1 positions of axis X, EXX 2",
        ),
    ],
)
def test_tables_that_are_not_whole_are_refused(  # type: ignore[no-untyped-def]
    reader, text: str, line: int, message: str
) -> None:
    with pytest.raises(ParseError, match=message) as info:
        reader(text, "comp.txt")
    assert (info.value.file, info.value.line) == ("comp.txt", line)


def test_a_value_cut_inside_its_exponent_is_refused(tmp_path: Path) -> None:
    t = CompensationTable({"EC0Y": 4.6017387716398277e-05})
    for fmt, cut in (("etalon", "e-05\n"), ("isg", "e-05\n"), ("csv", "e-05,rad\n")):
        whole = dump_compensation(t, tmp_path / f"comp.{fmt}", fmt).read_text()
        assert load_compensation(tmp_path / f"comp.{fmt}", fmt) == t
        short = tmp_path / f"short.{fmt}"
        short.write_text(whole[: whole.index(cut)])
        with pytest.raises(ParseError, match=r"not whole|cut short|expected 6 fields") as info:
            load_compensation(short, fmt)
        assert info.value.file == str(short)
