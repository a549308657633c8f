"""Rotary-axis tests as studies: the five-axis ballbar test and measured R-test and ballbar data.

The references: the library called directly (bit for bit, the same seeded draws), the
exact kinematics of :mod:`mtmc.kinematics` (errors injected, recovered to a second-order
rest), and the geometry of what a bar cannot see (closed forms of the C-axis test).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.circular import (
    Ballbar,
    evaluate_uncertainty,
    follow_positions,
    loads_rotary_csv,
    rotary_ballbar,
    rotary_displacement,
    rotary_model,
    separable_terms,
)
from mtmc.demo import study_path
from mtmc.errors import IdentifiabilityError, InputError
from mtmc.kinematics import Machine
from mtmc.study import load_study, loads_study, write_result

FIVE = Machine.from_topology("wCBXfYZt")
BALL = np.array([150.0, 0.0, 80.0])
C = np.radians(np.linspace(0.0, 360.0, 72, endpoint=False))
TRIALS = 2000
SEED = 5

BALLBAR = """
kind = "circular"
title = "C-axis ballbar test"
[rotary]
machine = "wCBXfYZt"
axis = "C"
steps = 72
ball = [150.0, 0.0, 80.0]
[errors]
EX0C = "normal(0.010, 0.002)"
EY0C = "normal(-0.020, 0.002)"
EA0C = "normal(30e-6, 5e-6)"
EB0C = "normal(-20e-6, 5e-6)"
EXP = 0.005
EYP = 0.004
EZP = -0.003
[ballbar]
length = 100.0
direction = [1.0, 0.0, 0.0]
length_error = "normal(0, 0.0005)"
alpha = "normal(1.1e-5, 1e-6)"
temperature = "uniform(19.5, 20.5)"
resolution = 0.0001
noise = 0.0003
"""


def test_the_ballbar_study_is_the_library_called_directly():
    result = loads_study(BALLBAR, file="bb.toml").run(trials=TRIALS, seed=SEED)
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    names = ["EX0C", "EY0C", "EA0C", "EB0C", "EXP", "EYP", "EZP"]
    errors = {
        "EX0C": "normal(0.010, 0.002)",
        "EY0C": "normal(-0.020, 0.002)",
        "EA0C": "normal(30e-6, 5e-6)",
        "EB0C": "normal(-20e-6, 5e-6)",
        "EXP": 0.005,
        "EYP": 0.004,
        "EZP": -0.003,
    }
    bar = Ballbar(
        length_error="normal(0, 0.0005)",
        alpha="normal(1.1e-5, 1e-6)",
        temperature="uniform(19.5, 20.5)",
        resolution=0.0001,
        noise=0.0003,
    )
    model, inputs = rotary_model(
        FIVE.jacobian(q, None, names=names),
        errors,
        ballbar=bar,
        direction=[1.0, 0.0, 0.0],
        length=100.0,
    )
    res = evaluate_uncertainty(model, inputs, TRIALS, SEED)
    # a radial bar at one height separates the offsets of the axis and the bar's constant
    assert res.outputs == ("range", "EX0C", "EY0C", "length")
    assert [x.name for x in result.quantities] == list(res.outputs)
    for x in result.quantities:
        # bit for bit: the same seeded draws and reductions, times the exact unit factor
        assert x.unit == "µm"
        assert x.mc.estimate == 1e3 * res.monte_carlo(x.name).estimate
        assert x.mc.u == 1e3 * res.monte_carlo(x.name).u
    # what it cannot see is said, with the sphere's height as the factor of the tilts
    notes = result.extra["circular"]["notes"]
    assert "EA0C: not separable, its readings are those of -80·EY0C" in notes[0]
    assert "EB0C: not separable, its readings are those of 80·EX0C" in notes[1]
    assert "EXP: not separable, its readings are those of -1·length" in notes[2]
    assert notes[3] == "EYP: not seen by this test, it moves no reading"


def test_what_a_radial_bar_reads_of_the_c_axis_in_closed_form():
    """To first order a radial bar (x of the workpiece frame) on the C-axis test reads

    ``r(C) = (EX0C + z EB0C) (1 - cos C) + (EY0C - z EA0C) sin C - EXP``

    (z the sphere's height; the sphere is moved by ``(I - R(C)) d`` for an axis line off
    by ``d``, nothing at C = 0, where the set-up is taken): the tilts are the offsets at
    80 mm, EXP a constant, EYP and EZP across the bar. The design of the model is this,
    column by column."""
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    names = ("EX0C", "EY0C", "EA0C", "EB0C", "EXP", "EYP", "EZP")
    model, _ = rotary_model(
        FIVE.jacobian(q, None, names=list(names)),
        names=names,
        measured=np.zeros(C.size),
        ballbar=Ballbar(),
        direction=[2.0, 0.0, 0.0],  # normalised
        length=100.0,
    )
    z = BALL[2]
    want = np.stack(
        [1 - np.cos(C), np.sin(C), -z * np.sin(C), z * (1 - np.cos(C)), -(C**0), 0 * C, 0 * C],
        axis=1,
    )
    # 1e-12: the Jacobian's own rounding (terms of 150 mm and rotations of 2π)
    np.testing.assert_allclose(model.design, want, atol=1e-12)
    assert separable_terms(model.design, names) == ("EX0C", "EY0C", "EXP")


def test_the_ballbar_reads_the_exact_kinematics_to_second_order():
    """The study's first-order readings against :func:`rotary_ballbar` of the exact model."""
    names = ["EX0C", "EY0C", "EA0C", "EB0C"]
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    model, inputs = rotary_model(
        FIVE.jacobian(q, None, names=names),
        dict(zip(names, (0.01, -0.02, 3e-5, -2e-5), strict=True)),
        ballbar=Ballbar(),
        direction=[0.0, 1.0, 0.0],
        length=100.0,
    )
    rest = []
    for k in (1.0, 0.5):
        x = {n: np.array([k * float(np.mean(inputs[n].mean))]) for n in names}
        x |= {n: np.array([float(np.mean(inputs[n].mean))]) for n in inputs if n not in names}
        exact = rotary_ballbar(FIVE, q, BALL, [0.0, 1.0, 0.0], 100.0, {n: x[n][0] for n in names})
        rest.append(np.max(np.abs(model.readings(**x) - exact)))
    assert rest[0] < 1e-5  # mm: of order |e|² / L for errors of 0.02 mm
    assert rest[0] / rest[1] == pytest.approx(4.0, rel=0.1)  # second order: a quarter


TRUTH = {"EX0C": 0.010, "EY0C": -0.020, "EA0C": 30e-6, "EB0C": -20e-6, "EXP": 0.005}


def _rtest_csv(rng: np.random.Generator, sigma: float) -> str:
    """An R-test export from the exact kinematics, in µm, with noise of ``sigma`` mm."""
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    e = rotary_displacement(FIVE, q, BALL, TRUTH)[0] + rng.normal(0.0, sigma, (C.size, 3))
    rows = [
        f"{a:.6f},{1e3 * d[0]:.6f},{1e3 * d[1]:.6f},{1e3 * d[2]:.6f}"
        for a, d in zip(np.degrees(C), e, strict=True)
    ]
    return "# R-test export\nangle,dx,dy,dz\n" + "\n".join(rows) + "\n"


MEASURED = """
kind = "circular"
title = "C-axis R-test, measured"
data = "{data}"
[rotary]
machine = "wCBXfYZt"
axis = "C"
ball = [150.0, 0.0, 80.0]
{instrument}
"""


def test_a_measured_rtest_identifies_the_location_errors(tmp_path: Path):
    sigma = 2e-4
    (tmp_path / "rtest.csv").write_text(_rtest_csv(np.random.default_rng(3), sigma), "utf-8")
    text = MEASURED.format(data="rtest.csv", instrument='[rtest]\ngain = "normal(0, 5e-4)"')
    (tmp_path / "s.toml").write_text(text, encoding="utf-8")
    study = load_study(tmp_path / "s.toml")
    result = study.run(trials=TRIALS, seed=SEED)
    q = {x.name: x for x in result.quantities}
    # the axis' location errors and the set-up, by default: what one R-test separates
    assert list(q) == [
        "range_x",
        "range_y",
        "range_z",
        "EX0C",
        "EY0C",
        "EA0C",
        "EB0C",
        "EXP",
        "EYP",
        "EZP",
    ]
    circ = result.extra["circular"]
    # the noise of each reading: the residual scatter (Type A), σ within its own
    # sampling spread (216 readings, 7 terms: a relative sd of 5 %)
    assert circ["rms_um"] == pytest.approx(1e3 * sigma, rel=0.2)
    for name, want in (*TRUTH.items(), ("EYP", 0.0), ("EZP", 0.0)):
        f = 1e6 if name.startswith(("EA", "EB")) else 1e3
        # the injected errors within U (noise and gain) and the second-order rest
        assert abs(q[name].mc.estimate - f * want) < q[name].mc.U, name
        # the GUM and the Monte Carlo agree on a linear identification (JCGM 101 §8)
        assert q[name].gum is not None
        assert q[name].mc.u == pytest.approx(q[name].gum.u, rel=0.1), name
    # the folder reruns from itself: the CSV is copied into inputs/
    folder = write_result(result, tmp_path / "r", study_text=study.source.text)
    again = load_study(folder / "study.toml").run(trials=TRIALS, seed=SEED)
    assert [x.mc.estimate for x in again.quantities] == [x.mc.estimate for x in result.quantities]
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    assert np.asarray(doc["circular"]["displacement_um"]).shape == (C.size, 3)
    html = (folder / "report.html").read_text(encoding="utf-8")
    assert "Rotary-axis test" in html
    assert "as measured" in html


def test_a_measured_ballbar_test_identifies_what_a_bar_can(tmp_path: Path):
    q = follow_positions(FIVE, {"B": 0.0, "C": C}, BALL)
    truth = {"EX0C": 0.010, "EY0C": -0.020}
    r = rotary_ballbar(FIVE, q, BALL, [1.0, 0.0, 0.0], 100.0, truth)[0]
    rows = "\n".join(f"{a:.6f},{1e3 * v:.6f}" for a, v in zip(np.degrees(C), r, strict=True))
    (tmp_path / "bar.csv").write_text(f"angle,deviation\n{rows}\n", encoding="utf-8")
    bar = '[ballbar]\nlength = 100.0\ndirection = [1, 0, 0]\nlength_error = "normal(0, 5e-4)"'
    text = MEASURED.format(data="bar.csv", instrument=bar)
    result = loads_study(text, file="m.toml", folder=tmp_path).run(trials=TRIALS, seed=SEED)
    qs = {x.name: x for x in result.quantities}
    assert list(qs) == ["range", "EX0C", "EY0C", "length"]
    # recovered to the second-order rest and the 5e-7 mm rounding of the file
    assert qs["EX0C"].mc.estimate == pytest.approx(10.0, abs=0.01)
    assert qs["EY0C"].mc.estimate == pytest.approx(-20.0, abs=0.01)
    # the bar's length error reaches only its own constant
    assert qs["length"].mc.u == pytest.approx(0.5, rel=0.05)
    notes = result.extra["circular"]["notes"]
    assert any(n.startswith("EA0C: not separable") for n in notes)


def test_an_unseparable_choice_and_bad_rows_are_refused(tmp_path: Path):
    (tmp_path / "rtest.csv").write_text(_rtest_csv(np.random.default_rng(4), 1e-4), "utf-8")
    bar = "[ballbar]\nlength = 100.0\ndirection = [1, 0, 0]"
    text = MEASURED.format(data="rtest.csv", instrument=bar).replace(
        "[ballbar]", '[identify]\nterms = ["EX0C", "EB0C"]\n[ballbar]'
    )
    (tmp_path / "bar.csv").write_text(
        "angle,deviation\n" + "\n".join(f"{a},{a / 100}" for a in range(0, 360, 10)), "utf-8"
    )
    with pytest.raises(InputError, match="cannot separate these errors") as err:
        loads_study(text.replace("rtest.csv", "bar.csv"), file="m.toml", folder=tmp_path)
    assert err.value.field == "identify.terms"
    assert "1·EX0C -0.0125·EB0C" in str(err.value)  # 1/80 mm: the sphere's height
    with pytest.raises(IdentifiabilityError):
        rotary_model(
            np.zeros((8, 3, 1)), names=("EX0C",), identify=("EX0C",), measured=np.zeros((8, 3))
        )
    # not asked for, a term the test does not see is left out and named
    model, _ = rotary_model(np.zeros((8, 3, 1)), names=("EX0C",), measured=np.zeros((8, 3)))
    assert model.outputs == ("range_x", "range_y", "range_z")
    assert model.notes == ("EX0C: not seen by this test, it moves no reading",)
    with pytest.raises(
        InputError,
        match=r"r.csv:4: field angle: a second reading at 10 deg \(the first is on line 3\)",
    ):
        loads_rotary_csv("angle,dx,dy,dz\n0,1,2,3\n10,1,2,3\n10,1,2,3\n20,1,2,3\n", "r.csv")
    with pytest.raises(InputError, match="at least 4 rotary positions, got 2"):
        loads_rotary_csv("angle,deviation\n0,1\n10,1\n", instrument="ballbar")
    with pytest.raises(InputError, match=r"r.csv:3: field dz"):
        loads_rotary_csv("angle,dx,dy,dz\n0,1,2,3\n10,1,2,x\n", "r.csv")


def test_circle_evaluate_takes_a_rotary_study_and_the_overrun(tmp_path: Path, capsys):
    from mtmc.cli.main import main

    (tmp_path / "rtest.csv").write_text(_rtest_csv(np.random.default_rng(6), 2e-4), "utf-8")
    # the shipped C-axis study, simulated, now the template of the measured test: its
    # machine, sphere, R-test and limits; its [errors] and positions give way to the file's
    study = study_path("circle_c_axis.toml")
    argv = ["circle", "evaluate", str(tmp_path / "rtest.csv"), "--study", str(study), "--json"]
    argv += ["-n", "500"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert list(out["parameters"]) == ["range_x", "range_y", "range_z"]
    assert out["errors"]["EX0C"]["estimate"] == pytest.approx(10.0, abs=0.5)
    assert out["errors"]["EA0C"]["unit"] == "µrad"
    assert out["parameters"]["range_z"]["conformity"]["upper"] == 20.0
    assert main([*argv, "--radius", "100"]) == 2
    assert "a rotary-axis test ([rotary] in" in capsys.readouterr().err
    # an ISO 230-4 trace with 20° of overrun before its turn and none after
    deg = np.arange(-20.0, 360.0, 2.0)
    dev = 3 * np.cos(np.radians(deg))
    rows = "\n".join(f"{a:g},ccw,{d:.9f}" for a, d in zip(deg, dev, strict=True))
    (tmp_path / "t.csv").write_text(f"angle,direction,deviation\n{rows}\n", encoding="utf-8")
    base = ["circle", "evaluate", str(tmp_path / "t.csv"), "--radius", "150", "-n", "200"]
    assert main([*base, "--overrun", "20", "--json", "-o", str(tmp_path / "r")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "10 readings CCW outside the evaluated turn" in out["notes"][-1]
    # the centre offset of 3 µm along x, the first harmonic of the trace
    assert out["errors"]["centre_x"]["estimate"] == pytest.approx(3.0, abs=1e-6)
    assert "overrun = 20.0" in (tmp_path / "r" / "study.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("old", "new", "field", "words"),
    [
        # found by make fuzz: a sphere at 1e308 mm ended in LinAlgError (SVD did not converge)
        ("ball = [150.0, 0.0, 80.0]", "ball = [150.0, 1e308, 80.0]", "rotary.ball", "1e+06"),
        ("steps = 72", "steps = 72\nstart = 1e5", "rotary.start", "3600"),
        ("length = 100.0", "length = 1e9", "ballbar.length", "1e+06"),
        ("direction = [1.0, 0.0, 0.0]", "direction = [1e300, 1e300, 0]", "ballbar.direction", ""),
    ],
)
def test_sizes_past_the_limits_are_refused_at_their_line(old, new, field, words):
    assert old in BALLBAR
    with pytest.raises(InputError) as err:
        loads_study(BALLBAR.replace(old, new), file="bb.toml")
    assert err.value.field == field
    assert words in str(err.value)


@pytest.mark.parametrize(
    ("key", "value", "words"),
    [("radius", "1e9", "1e+06"), ("feed", "1e9", "600000"), ("start", "-1e5", "3600")],
)
def test_a_circle_path_past_the_limits_is_refused(key, value, words):
    path = "\n".join(f"{k} = {v}" for k, v in {"radius": "150.0", key: value}.items())
    text = f'kind = "circular"\n[path]\n{path}\n[errors]\nsquareness = 1e-5\n'
    with pytest.raises(InputError) as err:
        loads_study(text, file="c.toml")
    assert err.value.field == f"path.{key}"
    assert words in str(err.value)
