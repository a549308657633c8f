"""The physical range of lengths, angles and uncertainties, checked where a file is read.

A coordinate of 10³⁰ mm or a u of 1e308 is no machine's: each is refused with the file, the
line and the field (``mtmc.document.MAX_MM``, ``MAX_DEG``, ``MAX_RAD``), while the same
numbers within the limits are read as before.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mtmc.document import MAX_DEG, MAX_MM, MAX_RAD
from mtmc.errors import InputError, MtmcError
from mtmc.graph import toml_format
from mtmc.positioning.data import loads_positioning_csv
from mtmc.study.spec import loads_study

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

_GRAPH = """units = "{units}"
[probe]
u_axis = {probe}
[[place]]
name = "a"
type = "real"
{unit}value = {value}
u = {u}
pos = [0, {pos}]
"""


def _graph(**kw: object) -> str:
    values = {"units": "mm", "probe": 0.001, "value": 1.0, "u": 0.1, "pos": 0}
    values.update(kw)
    values["unit"] = f"unit = {kw['unit']}\n" if "unit" in kw else ""
    return _GRAPH.format(**values)


def test_limits() -> None:
    assert MAX_MM == 1e6
    assert MAX_DEG == 3600.0
    assert MAX_RAD == pytest.approx(20 * 3.141592653589793)


@pytest.mark.parametrize(
    ("kw", "field", "line"),
    [
        ({"value": 1e9}, "value", 7),
        ({"value": -2e6}, "value", 7),
        ({"u": 1e10}, "u", 8),
        ({"pos": 1e9}, "pos", 9),
        ({"probe": 1e9}, "u_axis", 3),
        ({"unit": '"deg"', "value": 1e5}, "value", 8),
        ({"unit": '"rad"', "value": 100.0}, "value", 8),
        ({"units": "um", "value": 2e9}, "value", 7),
    ],
)
def test_graph_numbers_beyond_a_machine(kw: dict[str, object], field: str, line: int) -> None:
    text = _graph(**kw)
    with pytest.raises(MtmcError) as info:
        toml_format.loads_graph(text, file="g.toml", validate=False)
    err = info.value
    assert (err.file, err.field) == ("g.toml", field)
    if field != "u_axis":
        assert err.line == line
    assert "at most" in err.message


@pytest.mark.parametrize(
    "kw",
    [
        {"value": 9e5, "u": 1e5},
        {"unit": '"deg"', "value": 3600.0},
        {"unit": '"rad"', "value": 60.0},
        {"units": "um", "value": 1e9},
        {"unit": '"1"', "value": 1e11},
    ],
)
def test_graph_numbers_within_the_limits(kw: dict[str, object]) -> None:
    toml_format.loads_graph(_graph(**kw), file="g.toml", validate=False)


def _study(name: str, old: str, new: str) -> str:
    text = (EXAMPLES / "studies" / name).read_text()
    assert old in text
    return text.replace(old, new, 1)


def _refused(name: str, old: str, new: str, field: str) -> InputError:
    text = _study(name, old, new)
    with pytest.raises(InputError) as info:
        loads_study(text, file=name, folder=EXAMPLES / "studies")
    err = info.value
    assert err.file == name
    assert err.field == field
    assert err.line is not None
    assert text.splitlines()[err.line - 1].lstrip().startswith(field.split(".")[-1])
    return err


def test_kinematics_pose_beyond_a_machine() -> None:
    _refused("five_axis.toml", "[150.0, 0.0, -100.0, -30.0, 0.0]", "[1e30, 0, 0, 0, 0]", "poses")
    err = _refused(
        "five_axis.toml", "[150.0, 0.0, -100.0, -30.0, 0.0]", "[0, 0, 0, 1e5, 0]", "poses"
    )
    assert "3600" in err.message


def test_kinematics_error_beyond_a_machine() -> None:
    _refused("five_axis.toml", '"normal(0, 0.003)"', '"normal(0, 1e308)"', "errors.EX0C")
    _refused("five_axis.toml", '"uniform(-10e-6, 10e-6)"', "1e30", "errors.EA0C")


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("start = [0.0, 0.0, 0.0]", "start = [1e30, 0.0, 0.0]", "points.mesh.start"),
        (
            "position = [-863.527, 194.373, 677.782]",
            "position = [-1e30, 194.373, 677.782]",
            "tracker.positions.aguado2017.position",
        ),
        (
            "euler_deg = [0.0339, 0.0343, 59.4652]",
            "euler_deg = [0.0339, 0.0343, 1e30]",
            "tracker.positions.aguado2017.euler_deg",
        ),
        ("EXX = [54.0, 18.0, 3.0]", "EXX = [54.0, 1e30, 3.0]", "truth.EXX"),
        ("EC0Y = 40.0", "EC0Y = 1e300", "truth.EC0Y"),
    ],
)
def test_verification_numbers_beyond_a_machine(old: str, new: str, field: str) -> None:
    _refused("aguado2017.toml", old, new, field)


def test_positioning_beyond_a_machine() -> None:
    head = "target,run,direction,deviation\n"
    with pytest.raises(InputError) as info:
        loads_positioning_csv(head + "0,1,+,1e30\n", "p.csv")
    assert (info.value.line, info.value.field) == (2, "deviation")
    with pytest.raises(InputError) as info:
        loads_positioning_csv(head + "2e6,1,+,0\n", "p.csv")
    assert (info.value.line, info.value.field) == (2, "target")
    with pytest.raises(InputError) as info:
        loads_positioning_csv(head + "4000,1,+,0\n", "p.csv", units="deg,arcsec")
    assert info.value.field == "target"
    rows = [f"{t},{r},{d},{x}" for t in (0, 9e5) for r in (1, 2) for d, x in (("+", 9e8), ("-", 4))]
    ok = loads_positioning_csv(head + "\n".join(rows), "p.csv")
    assert ok.deviations.tolist() == [[[9e8, 4.0]] * 2] * 2


def test_gravity_coordinates_beyond_a_machine(tmp_path: Path) -> None:
    from mtmc.artefact.gravity import load_gravity

    f = tmp_path / "g.csv"
    rows = "H,1,0,0,0\nH,2,100,0,0\nV,1,0,0,0\nV,2,100,0,0\nO,1,0,0,0\nO,2,100,1e308,0\n"
    f.write_text("orientation,ball,x,y,z\n" + rows)
    with pytest.raises(InputError) as info:
        load_gravity(f)
    assert (info.value.line, info.value.field) == (7, "y")


def test_an_overflowing_model_stops_with_one_line_and_no_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import warnings

    from mtmc.cli.main import main

    study = tmp_path / "s.toml"
    study.write_text(
        'kind = "propagate"\nmodel = "exp(x)"\noutput = "y"\n[inputs]\nx = "normal(700, 10)"\n'
        "[run]\ntrials = 1000\nseed = 1\n"
    )
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        rc = main(["run", str(study), "-q", "-o", str(tmp_path / "out")])
    assert [str(w.message) for w in seen if issubclass(w.category, RuntimeWarning)] == []
    err = capsys.readouterr().err.splitlines()
    assert rc == 2
    assert len(err) == 1
    assert "not finite" in err[0]


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        # the artefact study's errors (µm, µrad), setup errors and poses, held to the limits
        # of the verification's: 1e300 µrad ran to "points coplanar", 1e300 µm at dpx to an
        # error naming EXY with RuntimeWarnings, and a pose at 1e300° ran
        ("EC0Y = 4.0", "EC0Y = 1e300", "machine.errors.EC0Y"),
        ("EXX = [0.0, -0.0026]", "EXX = [0.0, 1e300]", "machine.errors.EXX"),
        ("dpx = 1.0", "dpx = 1e300", "setup_errors.dpx"),
        ("poses_deg = [[0, 0],", "poses_deg = [[1e300, 0],", "plan.poses_deg"),
        ("poses_deg = [[0, 0],", "poses_deg = [[3601, 0],", "plan.poses_deg"),
        ("position = [0.0, -30.0, 0.0]", "position = [1e30, -30.0, 0.0]", "artefact.position"),
    ],
)
def test_artefact_numbers_beyond_a_machine(old: str, new: str, field: str) -> None:
    err = _refused("wang2022.toml", old, new, field)
    assert "at most" in err.message or " in [" in err.message


def test_artefact_numbers_at_the_limits_are_read() -> None:
    text = _study("wang2022.toml", "poses_deg = [[0, 0],", "poses_deg = [[3600, -3600],")
    text = text.replace("EC0Y = 4.0", "EC0Y = 6.2e7", 1).replace("dpx = 1.0", "dpx = -1e9", 1)
    loads_study(text, file="wang2022.toml", folder=EXAMPLES / "studies")
