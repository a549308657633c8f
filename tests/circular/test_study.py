"""The ``circular`` study kind: the library's numbers, by ``mtmc run`` and ``circle simulate``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.circular import Ballbar, circular_model, design, evaluate_uncertainty
from mtmc.circular.model import TERMS, default_terms
from mtmc.cli.main import main
from mtmc.demo import study_path
from mtmc.errors import InputError
from mtmc.study import load_result, load_study, loads_study, write_result
from mtmc.uncertainty import as_distribution

SHIPPED = study_path("circle_xy.toml")
TRIALS = 2000
SEED = 11


def _study(errors: str, extra: str = "", path: str = "") -> str:
    return f"""
kind = "circular"
[path]
radius = 150.0
points = 720
{path}
[errors]
{errors}
{extra}
"""


def test_the_study_gives_the_numbers_of_the_library_called_directly():
    result = load_study(SHIPPED).run(trials=TRIALS, seed=SEED)
    # the library in its own units, the file's values written out once more
    theta = 2.0 * np.pi * np.arange(720) / 720
    common = dict(radius=150.0, theta_ccw=theta, theta_cw=-theta, plane="XY", feed=1000.0 / 60.0)
    truth = design(terms=tuple(t for t in TERMS if "cyclic" not in t), **common)
    ident = design(terms=default_terms(2), **common)
    errors = {
        "centre_x": "normal(0.002, 0.001)",
        "centre_y": "normal(-0.001, 0.001)",
        "squareness": "normal(30e-6, 3e-6)",
        "scale_mismatch": "normal(20e-6, 2e-6)",
        "backlash_x": "uniform(0.003, 0.005)",
        "backlash_y": "uniform(0.001, 0.003)",
        "servo_mismatch": "normal(1e-3, 1e-4)",
    }
    bar = Ballbar(
        as_distribution("normal(0, 0.0005)"),
        as_distribution("normal(1.1e-5, 1e-6)"),
        as_distribution("uniform(19.5, 20.5)"),
        resolution=0.0001,
        noise=0.0003,
    )
    model, inputs = circular_model(ident, bar, errors=errors, simulate_with=truth)
    res = evaluate_uncertainty(model, inputs, TRIALS, SEED)
    assert [q.name for q in result.quantities] == list(res.outputs)
    for q in result.quantities:
        f = {"µm": 1e3, "µrad": 1e6, "µm/m": 1e6, "ms": 1e3}[q.unit]
        mc, g = res.monte_carlo(q.name), res.gum_result(q.name)
        # bit for bit: the same seeded draws and reductions, times the exact unit factor
        assert q.mc.estimate == f * mc.estimate
        assert q.mc.u == f * mc.u
        assert q.gum is not None
        assert q.gum.u == f * g.u


def test_a_pure_squareness_gives_g_equal_to_r_times_s_and_is_identified():
    # closed form: ΔR = -(R S / 2) sin 2θ, so F = ±R S/2, G(LSC) = G(MZ) = G(b) = R S and
    # H = 0; the points at 45° and 135° reach the extremes exactly
    s = 2.5e-5
    study = loads_study(_study(f"squareness = {s}"), file="c.toml")
    r = study.run(trials=100, seed=1)
    q = {x.name: x for x in r.quantities}
    rs = 150.0 * s * 1e3  # µm
    # 1e-9 µm: a sum of a few products of order 1 µm, rounded in the last digits
    for name, want in (("G_lsc", rs), ("G_mz", rs), ("G_b", rs), ("F_max", rs / 2)):
        assert q[name].mc.estimate == pytest.approx(want, abs=1e-9)
        # every trial the same test: u is the rounding of the mean of equal values only
        assert q[name].mc.u < 1e-12
    assert q["F_min"].mc.estimate == pytest.approx(-rs / 2, abs=1e-9)
    assert q["H"].mc.estimate == pytest.approx(0.0, abs=1e-9)
    assert q["squareness"].mc.estimate == pytest.approx(1e6 * s, rel=1e-9)
    for name in ("servo_mismatch", "backlash_x", "scale_mismatch"):
        assert q[name].mc.estimate == pytest.approx(0.0, abs=1e-9)


def test_mtmc_run_circle_simulate_and_the_folder_agree(tmp_path):
    study = load_study(SHIPPED)
    result = study.run(trials=TRIALS, seed=SEED)
    folder = write_result(result, tmp_path / "r", study_text=study.source.text, report=False)
    back = load_result(folder)
    assert back.kind == "circular"
    out = tmp_path / "cli"
    argv = ["circle", "simulate", str(SHIPPED), "-n", str(TRIALS), "--seed", str(SEED), "--json"]
    from typer.testing import CliRunner

    from mtmc.cli.main import app

    # the numbers of the two routes; the report's plots are tested below
    run = CliRunner().invoke(app, [*argv, "-o", str(out), "--plots", "0"])
    assert run.exit_code == 0, run.output
    doc = json.loads(run.stdout)
    for q in result.quantities:
        # bit for bit: JSON writes floats as their shortest repr, read back exactly
        assert doc["quantities"][q.name]["estimate"] == q.mc.estimate
        assert doc["quantities"][q.name]["U"] == q.mc.U
        assert back.quantity(q.name).mc.U == q.mc.U
    a = json.loads((folder / "result.json").read_text())
    b = json.loads((out / "result.json").read_text())
    assert a["quantities"] == b["quantities"]
    assert doc["quantities"]["H"]["conformity"]["decision"] == "does not conform"
    assert main  # the console entry is the app the test invoked


@pytest.mark.parametrize(
    ("text", "field", "message"),
    [
        (_study("squarenes = 1e-5"), "errors.squarenes", "unknown error 'squarenes'"),
        (
            _study("squareness = 1e-5", path='directions = ["up"]'),
            "path.directions",
            "expected 'ccw' and/or 'cw'",
        ),
        (
            _study("squareness = 1e-5", "[conformity.H]\nupper = 3", 'directions = ["ccw"]'),
            "conformity.H",
            "unknown output 'H'",
        ),
        (_study("squareness = 1e-5", path="centre = [1]"), "path.centre", "two finite numbers"),
        (
            _study("squareness = 1e-5", '[identify]\nterms = ["spin"]'),
            "identify.terms",
            "unknown term 'spin'",
        ),
    ],
)
def test_bad_input_is_named_at_its_line(text, field, message):
    with pytest.raises(InputError) as err:
        loads_study(text, file="c.toml")
    assert err.value.field == field
    assert err.value.line is not None
    assert message in str(err.value)


def test_the_shipped_example_identifies_what_it_injects():
    # the shipped XY example separates what it injects: the means of the identified
    # errors are the PDFs' means within 4 standard errors of the Monte Carlo mean
    r = load_study(SHIPPED).run(trials=TRIALS, seed=SEED)
    q = {x.name: x for x in r.quantities}
    for name, mean in (("squareness", 30.0), ("scale_mismatch", 20.0), ("backlash_x", 4.0)):
        assert abs(q[name].mc.estimate - mean) < 4 * q[name].mc.u / np.sqrt(TRIALS)


def test_the_report_draws_the_polar_plot_and_prints_the_numbers_of_result_json(tmp_path):
    study = load_study(SHIPPED)
    result = study.run(trials=500, seed=SEED)
    folder = write_result(result, tmp_path / "r", study_text=study.source.text)
    html = (folder / "report.html").read_text(encoding="utf-8")
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    section = html[html.index('<section id="circular">') :]
    section = section[: section.index("</section>")]
    assert 'data-plot="circular"><svg' in section
    assert "LSC" in section
    assert "MZ circles" in section
    assert "tolerance G ≤ 25 µm about the LSC" in section
    for q in doc["quantities"]:
        mc = q["monte_carlo"]
        row = f"<tr><td>{q['name']}</td><td>{mc['estimate']:.4g}</td><td>{mc['U']:.2g}</td>"
        assert row in section
    # the circles drawn are those of the trace: the LSC of the CCW trace by its own
    # definition, a least-squares fit of c + a cos θ + b sin θ by lstsq
    c = doc["circular"]
    idx = np.asarray(c["direction"]) > 0
    t = np.radians(np.asarray(c["theta_deg"]))[idx]
    basis = np.stack([np.ones_like(t), np.cos(t), np.sin(t)], axis=1)
    coef = np.linalg.lstsq(basis, np.asarray(c["trace_um"])[idx], rcond=None)[0]
    # 1e-9 µm: a well-conditioned 3-column fit of values of order 10 µm (cond ≈ 1.4)
    np.testing.assert_allclose(c["circles"]["ccw"]["lsc"], coef, atol=1e-9)
    # the MZ zone is no wider than the LSC's own zone and encloses the trace
    mid = np.asarray(c["circles"]["ccw"]["mz"]) @ basis.T
    w = c["circles"]["ccw"]["mz_width"]
    resid = np.asarray(c["trace_um"])[idx] - mid
    assert np.all(np.abs(resid) <= w / 2 + 1e-9)
    lsc_resid = np.asarray(c["trace_um"])[idx] - coef @ basis.T
    assert w <= np.ptp(lsc_resid) + 1e-9


C_AXIS = study_path("circle_c_axis.toml")


def test_the_c_axis_study_gives_the_numbers_of_the_library_called_directly():
    from mtmc.circular import follow_positions, rotary_model
    from mtmc.kinematics import Machine

    result = load_study(C_AXIS).run(trials=TRIALS, seed=SEED)
    m = Machine.from_topology("wCBXfYZt")
    c = np.radians(np.linspace(0.0, 360.0, 36, endpoint=False))
    q = follow_positions(m, {"B": 0.0, "C": c}, [150.0, 0.0, 80.0])
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
    model, inputs = rotary_model(
        m.jacobian(q, None, names=names), errors, gain="normal(0, 5e-4)", noise=0.0002
    )
    res = evaluate_uncertainty(model, inputs, TRIALS, SEED)
    assert [x.name for x in result.quantities] == list(res.outputs)
    for x in result.quantities:
        f = {"µm": 1e3, "µrad": 1e6}[x.unit]
        # bit for bit: the same seeded draws and reductions, times the exact unit factor
        assert x.mc.estimate == f * res.monte_carlo(x.name).estimate
        assert x.mc.u == f * res.monte_carlo(x.name).u
    # the R-test separates every location error: the identified means are the PDFs'
    # means within 4 standard errors
    qs = {x.name: x for x in result.quantities}
    for name, mean in (("EX0C", 10.0), ("EY0C", -20.0), ("EA0C", 30.0), ("EB0C", -20.0)):
        assert abs(qs[name].mc.estimate - mean) < 4 * qs[name].mc.u / np.sqrt(TRIALS)


def test_the_c_axis_report_plots_the_trace_against_the_rotary_angle(tmp_path):
    study = load_study(C_AXIS)
    folder = write_result(
        study.run(trials=300, seed=SEED), tmp_path / "r", study_text=study.source.text
    )
    html = (folder / "report.html").read_text(encoding="utf-8")
    assert 'data-plot="circular"><svg' in html
    assert "C-axis test of wCBXfYZt" in html
    doc = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    disp = np.asarray(doc["circular"]["displacement_um"])
    assert disp.shape == (36, 3)


@pytest.mark.parametrize(
    ("text", "field", "message"),
    [
        (
            '[rotary]\nmachine = "wCBXfYZt"\naxis = "D"\nball = [1, 2, 3]',
            "rotary.axis",
            "expected one of",
        ),
        ('[rotary]\nmachine = "wCBXfYZt"\naxis = "C"\nball = [1, 2]', "rotary.ball", "[x, y, z]"),
    ],
)
def test_bad_rotary_input_is_named_at_its_line(text, field, message):
    with pytest.raises(InputError) as err:
        loads_study(f'kind = "circular"\n{text}\n[errors]\nEX0C = 0.01\n', file="c.toml")
    assert err.value.field == field
    assert message in str(err.value)


def test_the_b_axis_study_identifies_the_location_errors_of_b() -> None:
    """The shipped B-axis R-test: its GUM estimates of EX0B, EZ0B, EA0B, EC0B are the
    means of their PDFs (the model is linear in them), in µm and µrad; each U covers the
    Monte Carlo spread of a parameter known to ±2 µm or ±5 µrad (u = 2, 5)."""
    result = load_study(study_path("circle_b_axis.toml")).run(trials=TRIALS, seed=SEED)
    q = {x.name: x for x in result.quantities}
    means = {"EX0B": 10.0, "EZ0B": -8.0, "EA0B": 20.0, "EC0B": -15.0}
    for name, mean in means.items():
        assert q[name].gum is not None
        assert q[name].gum.estimate == pytest.approx(mean, rel=1e-9), name
        u = 2.0 if name.startswith(("EX", "EZ")) else 5.0
        assert q[name].gum.u == pytest.approx(u, rel=0.05), name  # the PDF, plus the noise
    assert q["EA0B"].unit == "µrad"
    assert q["range_x"].conformity is not None


@pytest.mark.parametrize(
    ("body", "where", "words"),
    [
        ('data = "absent.csv"', ":2: field data", "expected an existing file"),
        ('data = "t.csv"\nunits = "deg,inch"', ":3: field units", "expected units ANGLE,DEVIATION"),
        ('data = "t.csv"\ncolumns = {theta = "x"}', ":3: field columns", "unknown column 'theta'"),
        ('data = "t.csv"\ndirections = {left = "up"}', ":3: field directions.left", "cw or ccw"),
        ('data = "t.csv"\n[errors]\nsquareness = 1e-5', ":5: field errors", "identifies"),
        ('data = "short.csv"', ":2: field data", "4 readings in"),
    ],
)
def test_a_measured_trace_study_names_the_line_of_what_is_wrong(
    tmp_path: Path, body: str, where: str, words: str
) -> None:
    rows = "".join(f"{a},ccw,{np.sin(np.radians(a)):.4f}\n" for a in range(0, 360, 10))
    (tmp_path / "t.csv").write_text("angle,direction,deviation\n" + rows, encoding="utf-8")
    short = "angle,direction,deviation\n0,ccw,1\n90,ccw,2\n180,ccw,3\n270,ccw,4\n"
    (tmp_path / "short.csv").write_text(short, encoding="utf-8")
    head, _, tables = body.partition("\n[")
    text = f'kind = "circular"\n{head}\n[path]\nradius = 100\n' + (f"[{tables}\n" if tables else "")
    study = tmp_path / "s.toml"
    study.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as info:
        load_study(study)
    assert f"s.toml{where}" in str(info.value)
    assert words in str(info.value)
