"""The demo prints the library's own numbers: run it with a small M and check them.

Each number of ``results.json`` is checked by a second route through the library (another
entry point, a one-at-a-time loop, finite differences, a closed form), never by calling
the demo's own code again.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console
from scipy.stats import chi2

from mtmc import (
    demo,
    graph_model,
    gum,
    library_machine,
    load_graph,
    monte_carlo,
    run_graph,
    validate,
)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "graphs"
SEED = 101
GRAPH_M = 10_000  # --quick
FILES = (
    "results.json",
    "ball_centre.svg",
    "bcs_origin.svg",
    "machine.svg",
    "d_ac_histogram.png",
    "sweep.png",
)


def _mc_tol(m: int, n_sigma: float = 4.0) -> float:
    """n_sigma relative standard errors of a Monte Carlo standard deviation."""
    return n_sigma / math.sqrt(2.0 * (m - 1))


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    buf = io.StringIO()
    console = Console(file=buf, width=200)
    assert demo.main(["--quick", "--out", str(out)], console=console) == 0
    record = json.loads((out / "results.json").read_text(encoding="utf-8"))
    return out, buf.getvalue(), record


def test_every_file_is_written_and_parses(quick):
    out, _, record = quick
    for name in FILES:
        assert (out / name).is_file(), name
        assert (out / name).stat().st_size > 0, name
    for name in ("d_ac_histogram.png", "sweep.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    for name in ("ball_centre.svg", "bcs_origin.svg", "machine.svg"):
        text = (out / name).read_text(encoding="utf-8")
        assert "<svg" in text and text.rstrip().endswith("</svg>"), name
    # no temporary files of the atomic writes are left behind
    assert sorted(p.name for p in out.iterdir()) == sorted(FILES)
    assert [name for name, _ in demo.SECTIONS] == list(record["sections"])


def test_results_json_records_the_run(quick):
    _, out_text, record = quick
    import mtmc

    assert record["mtmc_version"] == mtmc.__version__
    assert record["seed"] == SEED
    assert record["trials"] == {
        "mass-calibration": 20_000,
        "graphs": GRAPH_M,
        "sweep_per_point": 1000,
    }
    assert record["date"][:2] == "20" and "T" in record["date"]
    s = record["sections"]
    assert s["ball-centre"]["probe_um"]["u_axis"] == pytest.approx(2.0)
    assert s["five-axis"]["errors"]["EX0C"] == {"pdf": "normal(0, 0.003)", "u": 0.003, "unit": "mm"}
    assert s["mass-calibration"]["inputs"]["rho_w"] == "uniform(7000, 9000)"
    assert "Results written to" in out_text


def test_ball_centre_against_library_and_closed_form(quick):
    _, out_text, record = quick
    r = record["sections"]["ball-centre"]
    g = load_graph(EXAMPLES / "ball_centre.toml")
    # second route: the graph as a plain model through monte_carlo (same seed, same draws)
    model, inputs = graph_model(g, "p")
    mc = monte_carlo(model, inputs, trials=GRAPH_M, seed=SEED)
    np.testing.assert_allclose(r["u_mc_um"], np.asarray(mc.u) * 1e3, rtol=1e-9)
    # closed form from the file's numbers: u_dir = sqrt(2² + 1² + 0.5²) µm, u(r1) = 0.5 µm
    u_dir = math.sqrt(2.0**2 + 1.0**2 + 0.5**2)
    closed = [u_dir / math.sqrt(2.0), u_dir / math.sqrt(2.0), math.hypot(u_dir, 0.5)]
    np.testing.assert_allclose(r["u_closed_form_um"], closed, rtol=1e-12)
    np.testing.assert_allclose(r["u_mc_um"], closed, rtol=_mc_tol(GRAPH_M))
    for u in r["u_mc_um"]:
        assert f"{u:.4g}" in out_text


def test_rotary_axes_against_gum_and_gaussian_ellipse(quick):
    _, out_text, record = quick
    for label, file, place in (("C", "axis_c.toml", "axis_c"), ("A", "axis_a.toml", "axis_a")):
        r = record["sections"]["rotary-axes"][label]
        g = load_graph(EXAMPLES / file)
        res = run_graph(g, GRAPH_M, SEED, outputs=[place])
        _, u_point, cov_point = res.places[place].part("point")
        np.testing.assert_allclose(r["u_point_mc_um"], u_point * 1e3, rtol=1e-9)
        # MC against the first-order GUM, within the MC tolerance of u
        np.testing.assert_allclose(r["u_point_mc_um"], r["u_point_gum_um"], rtol=_mc_tol(GRAPH_M))
        # the Gaussian ellipse from the library's covariance, projected on the plane
        basis = np.asarray(r["plane_basis"]).T
        assert np.allclose(basis.T @ basis, np.eye(2))
        assert np.allclose(basis.T @ np.asarray(r["direction"]), 0.0, atol=1e-9)
        lam = np.linalg.eigvalsh(basis.T @ cov_point @ basis)
        semi = math.sqrt(chi2.ppf(0.95, 2)) * np.sqrt(lam) * 1e3
        np.testing.assert_allclose(r["ellipse_semi_axes_chi2_um"], semi, rtol=1e-6)
        # the MC ellipse (k from the trials) agrees with the Gaussian one for this output
        np.testing.assert_allclose(r["ellipse_semi_axes_um"], semi, rtol=0.03)
        assert r["ellipse_k"] == pytest.approx(math.sqrt(chi2.ppf(0.95, 2)), rel=0.03)
    assert "95 % coverage ellipse" in out_text


def test_bcs_origin_against_run_graph_gum_and_sweep(quick):
    _, out_text, record = quick
    r = record["sections"]["bcs-origin"]
    g = load_graph(EXAMPLES / "bcs_origin.toml")
    res = run_graph(g, GRAPH_M, SEED, outputs=["d_ac", "p_o"], keep=["d_ac"])
    d = r["d_ac"]
    lo, hi = res.result("d_ac").coverage_interval(0.95, kind="symmetric")
    np.testing.assert_allclose(d["monte_carlo"]["symmetric_95_mm"], [lo, hi], rtol=1e-12)
    assert f"[{demo._mm(lo)}, {demo._mm(hi)}]" in out_text
    assert d["monte_carlo"]["u_um"] == pytest.approx(res.places["d_ac"].u * 1e3, rel=1e-9)
    assert d["monte_carlo"]["estimate_mm"] == pytest.approx(res.places["d_ac"].estimate, rel=1e-12)
    np.testing.assert_allclose(r["points"]["p_o"]["u_um"], res.places["p_o"].u * 1e3, rtol=1e-9)
    # nominal A-C distance of the example: the C balls at z = -10 with r2 = 40 mm
    assert d["gum"]["estimate_mm"] == pytest.approx(50.0, abs=1e-6)
    assert d["monte_carlo"]["u_um"] == pytest.approx(d["gum"]["u_um"], rel=_mc_tol(GRAPH_M))
    val = d["validation_um"]
    assert val["passed"] == (val["d_low"] <= val["delta"] and val["d_high"] <= val["delta"])
    # one grid point of the sweep run directly with the probe changed
    sw = r["sweep"]
    grid = np.asarray(sw["grid_mm"])
    i = 7  # u_probe = 0.002, u_axis = 0.003
    probe = dataclasses.replace(g.probe, u_probe=grid[i, 0], u_axis=grid[i, 1])
    direct = run_graph(dataclasses.replace(g, probe=probe), 1000, SEED, outputs=["d_ac"])
    assert sw["u_um"][i] == pytest.approx(direct.places["d_ac"].u * 1e3, rel=1e-9)
    assert len(sw["u_um"]) == 25
    assert sw["surrogate"]["max_rel_error"] <= 0.05  # seed 000: at most 5 %
    u = np.asarray(sw["u_um"])
    pred = np.asarray(sw["u_surrogate_um"])
    assert np.max(np.abs(pred / u - 1)) == pytest.approx(sw["surrogate"]["max_rel_error"])
    assert f"{d['monte_carlo']['u_um']:.4g}" in out_text
    assert "GUM validated" in out_text


def _fd_jacobian(machine, q, names, h=1e-7):
    cols = []
    for n in names:
        plus = machine.tool_position(q, {n: h})
        minus = machine.tool_position(q, {n: -h})
        cols.append((plus - minus)[0] / (2 * h))
    return np.stack(cols, axis=1)  # (3, N)


def test_five_axis_against_finite_differences_and_own_sampling(quick):
    _, out_text, record = quick
    r = record["sections"]["five-axis"]
    machine = library_machine(r["machine"])
    names = list(r["errors"])
    u_e = np.array([r["errors"][n]["u"] for n in names])
    rows = r["rows"]
    poses = np.asarray(r["poses_mm_rad"])
    assert len(rows) == 3 * len(poses)
    # GUM from finite differences of the forward kinematics, one pose at a time
    for i, q in enumerate(poses):
        J = _fd_jacobian(machine, q, names)
        u_fd = np.sqrt((J**2) @ (u_e**2)) * 1e3
        got = [row["u_gum_jacobian_um"] for row in rows[3 * i : 3 * i + 3]]
        np.testing.assert_allclose(got, u_fd, rtol=1e-5)
        diff = [row["u_gum_differentiated_um"] for row in rows[3 * i : 3 * i + 3]]
        np.testing.assert_allclose(diff, u_fd, rtol=1e-5)
        nominal = [row["nominal_mm"] for row in rows[3 * i : 3 * i + 3]]
        np.testing.assert_allclose(nominal, machine.tool_position(q)[0], atol=1e-9)
    # Monte Carlo with draws made here (another generator): u agrees within MC tolerance
    rng = np.random.default_rng(np.random.SeedSequence(2024))
    m = 20_000
    errors = {}
    for n in names:
        d = r["errors"][n]["pdf"]
        if d.startswith("normal"):
            errors[n] = rng.normal(0.0, r["errors"][n]["u"], m)
        else:
            half = r["errors"][n]["u"] * math.sqrt(3.0)
            errors[n] = rng.uniform(-half, half, m)
    for i, q in enumerate(poses):
        p = machine.tool_position(q, errors)
        u_own = p.std(axis=0, ddof=1) * 1e3
        got = [row["u_mc_um"] for row in rows[3 * i : 3 * i + 3]]
        np.testing.assert_allclose(got, u_own, rtol=_mc_tol(GRAPH_M) + _mc_tol(m))
    for row in rows:
        assert row["ratio_mc_gum"] == pytest.approx(1.0, abs=_mc_tol(GRAPH_M))
        expected = row["d_low_um"] <= row["delta_um"] and row["d_high_um"] <= row["delta_um"]
        assert row["validated"] == expected
        assert f"{row['u_mc_um']:.4g}" in out_text


def test_package_graphs_are_the_examples():
    for name in demo.GRAPH_FILES:
        packaged = Path(demo.__file__).parent / "data" / "graphs" / name
        assert packaged.read_bytes() == (EXAMPLES / name).read_bytes(), name
        assert demo.demo_graph(name).file == name


def test_mass_calibration_section_prints_library_results(capsys, tmp_path):
    assert (
        demo.main(
            [
                "--trials",
                "20000",
                "--seed",
                "3",
                "--out",
                str(tmp_path),
                "--section",
                "mass-calibration",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    model = demo.mass_calibration_model()
    inputs = demo.mass_calibration_inputs()
    mc = monte_carlo(model, inputs, trials=20_000, seed=3)
    g = gum(model, inputs)
    v = validate(g, mc, kind="shortest")
    lo, hi = mc.coverage_interval(0.95, kind="shortest")
    f = demo.fmt
    for text in (
        "JCGM 101 §9.3",
        f(mc.estimate),
        f(mc.u),
        f"[{f(lo)}, {f(hi)}]",
        "20000",
        f(g.u),
        f"[{f(g.interval[0])}, {f(g.interval[1])}]",
        f(v.d_low),
        f(v.d_high),
        f(v.delta),
        "GUM validated",
    ):
        assert text in out, text
    for entry in g.budget:
        assert entry.name in out
        assert f"{100 * entry.share:.1f} %" in out
    # the inputs of JCGM 101 Table 6
    assert "normal(100000, 0.05)" in out and "uniform(7000, 9000)" in out
    record = json.loads((tmp_path / "results.json").read_text(encoding="utf-8"))
    assert list(record["sections"]) == ["mass-calibration"]
    assert record["sections"]["mass-calibration"]["monte_carlo"]["u"] == pytest.approx(mc.u)


def test_same_seed_same_numbers(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    quiet = Console(file=io.StringIO())
    for d in (a, b):
        demo.main(["--quick", "--section", "five-axis", "--out", str(d)], console=quiet)
    ra = json.loads((a / "results.json").read_text(encoding="utf-8"))["sections"]
    rb = json.loads((b / "results.json").read_text(encoding="utf-8"))["sections"]
    for key in ("rows",):
        for x, y in zip(ra["five-axis"][key], rb["five-axis"][key], strict=True):
            assert x["u_mc_um"] == y["u_mc_um"]


def test_bad_trials_is_refused_with_a_message(capsys, tmp_path):
    with pytest.raises(SystemExit) as exc:
        demo.main(["--trials", "1", "--out", str(tmp_path)])
    assert exc.value.code == 2
    assert "--trials: expected an integer >= 2, got 1" in capsys.readouterr().err


def test_endpoint_standard_error_against_replicated_runs():
    # the sampling error of a 2.5 % quantile, from 400 replicated runs of M = 2000 draws
    rng = np.random.default_rng(np.random.SeedSequence(77))
    m, reps, u = 2000, 400, 3.0
    ends = np.quantile(rng.normal(0.0, u, (reps, m)), 0.025, axis=1)
    predicted = demo._endpoint_std_error(u, m)
    # the standard deviation of 400 values is known to about 1/sqrt(2 * 399) = 3.5 %
    assert ends.std(ddof=1) == pytest.approx(predicted, rel=0.15)


def test_out_that_is_a_file_is_refused_with_a_message(capsys, tmp_path):
    f = tmp_path / "results"
    f.write_text("not a folder")
    with pytest.raises(SystemExit) as exc:
        demo.main(["--quick", "--out", str(f)])
    assert exc.value.code == 2
    assert f"--out: expected a folder, but {f} is a file" in capsys.readouterr().err


def test_five_axis_names_exactly_the_rows_failing_beyond_noise(capsys, tmp_path):
    """The verdict line lists the rows whose d exceeds δ by more than 3 endpoint errors."""
    argv = ["--seed", "101", "--out", str(tmp_path), "--section", "five-axis"]
    assert demo.main(argv) == 0
    out = " ".join(capsys.readouterr().out.split())
    rows = json.loads((tmp_path / "results.json").read_text(encoding="utf-8"))["sections"][
        "five-axis"
    ]["rows"]
    firm = [
        f"pose {r['pose']} {r['coordinate']}"
        for r in rows
        if max(r["d_low_um"], r["d_high_um"]) > r["delta_um"] + 3 * r["endpoint_std_error_um"]
    ]
    # With rectangular errors dominating its x coordinate, pose 1 has k_MC well below 1.96.
    assert "pose 1 x" in firm
    assert all(not r["validated"] for r in rows if f"pose {r['pose']} {r['coordinate']}" in firm)
    assert f"(d > δ + 3 σ(end)): {', '.join(firm)}:" in out
