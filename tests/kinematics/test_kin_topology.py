"""Topology strings and ISO 230 error names."""

from __future__ import annotations

import pytest

from mtmc.errors import InputError, TopologyError
from mtmc.kinematics import (
    list_error_terms,
    normalise_error_name,
    parse_error_name,
    parse_topology,
)


@pytest.mark.parametrize(
    ("spec", "part", "tool"),
    [
        ("wCBXfYZt", ("C", "B", "X"), ("Y", "Z")),
        ("wBZfXYCt", ("B", "Z"), ("X", "Y", "C")),
        ("XFYZ", ("X",), ("Y", "Z")),
        ("ZYXF", ("X", "Y", "Z"), ()),  # knee type: part on X, X on Y, Y on Z, Z on the frame
        ("FXYZ", (), ("X", "Y", "Z")),
        ("w CA X f Y Z t", ("C", "A", "X"), ("Y", "Z")),
        ("XUfYZW", ("U", "X"), ("Y", "Z", "W")),  # Aguado's reading: from the frame out
    ],
)
def test_parse_both_notations(spec: str, part: tuple[str, ...], tool: tuple[str, ...]) -> None:
    t = parse_topology(spec)
    assert t.part_axes == part
    assert t.tool_axes == tool
    # both printed forms parse back to the same topology
    assert parse_topology(str(t)) == t
    assert parse_topology(t.aguado) == t


def test_axes_canonical_order_and_sides() -> None:
    t = parse_topology("wCBXfYZt")
    assert t.axes == ("X", "Y", "Z", "B", "C")
    assert t.chain == ("C", "B", "X", "Y", "Z")
    assert t.side("C") == "part"
    assert t.side("Z") == "tool"
    assert t.linear_axes == ("X", "Y", "Z")
    assert t.rotary_axes == ("B", "C")
    with pytest.raises(TopologyError, match="'A' is not in wCBXfYZt"):
        t.side("A")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("", "empty topology"),
        ("XYZ", "no frame: expected exactly one 'f'"),
        ("XFYFZ", "two frames"),
        ("wXfYZ", "expected both 'w' .* and 't'"),
        ("XFYQ", r"unknown letter 'Q' at position 4: expected axis letters"),
        ("XFYX", "axis 'X' appears twice"),
        ("wft", "no axes"),
    ],
)
def test_bad_topologies(spec: str, message: str) -> None:
    with pytest.raises(TopologyError, match=message) as info:
        parse_topology(spec)
    assert info.value.field == "topology"
    assert isinstance(info.value, ValueError)


def test_error_names() -> None:
    assert normalise_error_name("x0c") == "EX0C"
    assert normalise_error_name("EXX") == "EXX"
    with pytest.raises(InputError, match="field name: expected an error name such as 'EXX'"):
        normalise_error_name(3)  # type: ignore[arg-type]
    t = parse_error_name("C0Y")
    assert (t.name, t.kind, t.axis, t.direction, t.angular) == ("EC0Y", "squareness", "Y", 2, True)
    t = parse_error_name("EX0C")
    assert (t.kind, t.axis, t.direction, t.angular) == ("location", "C", 0, False)
    t = parse_error_name("ebz")
    assert (t.kind, t.axis, t.direction, t.angular) == ("component", "Z", 1, True)
    assert parse_error_name("EZT").kind == "tool"
    assert parse_error_name("ECP").kind == "part"


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("EQX", "unknown error name 'EQX': expected an ISO 230 error name"),
        ("EXQ", "unknown error name"),
        ("EX0X", "'EX0X' is not a squareness error: for linear axis X expected a rotation"),
        ("EA0X", "not a squareness error"),
        ("EC0C", "not a location error of rotary axis C"),
        ("EX1C", "unknown error name"),
    ],
)
def test_bad_error_names(name: str, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        parse_error_name(name)
    assert info.value.field == name


def test_standard_error_set() -> None:
    names = [t.name for t in list_error_terms(parse_topology("XFYZ"))]
    # 18 component errors, 3 squareness (ISO 230-1 references), 6 tool, 6 part
    assert len(names) == 18 + 3 + 12
    assert [n for n in names if "0" in n] == ["EC0Y", "EB0Z", "EA0Z"]
    alln = [t.name for t in list_error_terms(parse_topology("XFYZ"), which="all")]
    assert {"EC0X", "EB0X", "EA0Y"} <= set(alln)
    five = [t.name for t in list_error_terms(parse_topology("wBZfXYCt"))]
    assert [n for n in five if "0" in n and n[-1] in "BC"] == [
        "EX0B",
        "EZ0B",
        "EA0B",
        "EC0B",
        "EX0C",
        "EY0C",
        "EA0C",
        "EB0C",
    ]
    with pytest.raises(InputError, match="expected 'standard' or 'all'"):
        list_error_terms(parse_topology("XFYZ"), which="some")
