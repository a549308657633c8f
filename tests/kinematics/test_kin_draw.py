"""The drawing of a kinematic chain: every body in chain order, labelled, the same each time."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from mtmc.errors import TopologyError
from mtmc.kinematics import draw_chain, library_machine, parse_topology

SVG = "{http://www.w3.org/2000/svg}"


def _ids_and_texts(svg: str) -> tuple[list[str], list[str]]:
    root = ET.fromstring(svg)
    ids = [g.get("id", "") for g in root.iter(f"{SVG}g")]
    return ids, [t.text or "" for t in root.iter(f"{SVG}text")]


def test_bodies_in_chain_order_with_their_labels() -> None:
    ids, texts = _ids_and_texts(draw_chain("XFYZ"))
    bodies = [i for i in ids if i.startswith("axis-") or i in ("workpiece", "frame", "tool")]
    assert bodies[:5] == [
        "workpiece",
        "axis-X-linear-part",
        "axis-Y-linear-tool",
        "axis-Z-linear-tool",
        "tool",
    ]
    assert "frame" in bodies
    assert texts[0] == "wXfYZt  (XFYZ)"
    assert texts[1:] == [
        "workpiece",
        "X",
        "along x, part",
        "frame",
        "Y",
        "along y, tool",
        "Z",
        "along z, tool",
        "tool",
    ]


def test_rotary_axes_title_and_inputs() -> None:
    machine = library_machine("xfyz")
    svg = draw_chain(machine, title="a <title> & more")
    assert svg == draw_chain(machine.topology, title="a <title> & more")  # same bytes
    ids, texts = _ids_and_texts(svg)
    assert texts[0] == "a <title> & more"  # escaped in the file, read back whole
    ids, texts = _ids_and_texts(draw_chain(parse_topology("wCBXfYZt")))
    assert [i for i in ids if i.startswith("axis-")] == [
        "axis-C-rotary-part",
        "axis-B-rotary-part",
        "axis-X-linear-part",
        "axis-Y-linear-tool",
        "axis-Z-linear-tool",
    ]
    assert {"about z, part", "about y, part"} <= set(texts)


def test_a_bad_topology_string_is_refused() -> None:
    with pytest.raises(TopologyError):
        draw_chain("XYZ")


@pytest.mark.parametrize(
    "poses",
    [
        "[[150.0, 0.0, -100.0, -30.0, 3600.0]]",  # C at the documented limit of 3600°
        "[[0.0, 0.0, 0.0, 3600.0, -3600.0], [0.0, 0.0, 0.0, 3600.0, -3600.0]]",
        "[[0.0, 0.0, 0.0, 0.0, 0.0]]",  # every axis at zero: the plots' ranges from the errors
    ],
)
def test_a_kinematics_report_at_the_angle_limit_warns_nothing(poses, tmp_path):
    """A pose at 3600° (ten turns, the largest angle a study takes) printed a Matplotlib
    UserWarning (identical xlims) while its report was drawn: every warning is an error here."""
    import warnings

    from mtmc.study import loads_study, write_result

    text = (
        'kind = "kinematics"\nmachine = "table-table"\nangles = "deg"\n'
        f"poses = {poses}\n"
        '[errors]\nEX0C = "normal(0, 0.003)"\nEA0C = "uniform(-10e-6, 10e-6)"\n'
        'EC0Y = "normal(0, 4e-6)"\n'
    )
    study = loads_study(text, file="k.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_result(study.run(trials=300, seed=1), tmp_path / "r", study_text=text)
    assert (tmp_path / "r" / "report.html").is_file()
