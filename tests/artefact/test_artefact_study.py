"""The shipped study, its loader, the Monte Carlo model against one-at-a-time, exact fits, GUM."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.artefact.study import (
    gum_outputs,
    load_artefact_study,
    loads_artefact_study,
    simulate,
    study_model,
)
from mtmc.errors import InputError
from mtmc.kinematics.functions import PolynomialFunction

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "wang2022.toml"


@pytest.fixture(scope="module")
def study():  # type: ignore[no-untyped-def]
    return load_artefact_study(STUDY)


def test_shipped_study(study) -> None:  # type: ignore[no-untyped-def]
    assert (ROOT / "src/mtmc/data/studies/wang2022.toml").read_text() == STUDY.read_text()
    assert study.poses.shape == (9, 2)
    assert study.repetitions == 3
    np.testing.assert_allclose(np.degrees(study.poses[7]), [10, 5])
    assert study.setup.machine.axes == ("X", "Y", "Z", "B", "C")
    assert isinstance(study.errors["EXX"], PolynomialFunction)
    assert study.errors["EXX"].coefficients.tolist() == [0.0, 4e-6]  # 4 um/m in mm/mm
    assert study.errors["EC0Y"] == pytest.approx(3e-6)  # urad -> rad
    assert study.setup_errors[0] == pytest.approx(1e-3)  # dpx 1 um
    np.testing.assert_allclose(study.repeatability, [0.36e-3, 0.41e-3, 0.25e-3])
    assert study.text_is_chosen if hasattr(study, "text_is_chosen") else True
    assert "CHOSEN, NOT MEASURED" in STUDY.read_text()


def test_magnitudes_resemble_table2(study) -> None:  # type: ignore[no-untyped-def]
    from mtmc.artefact.analysis import analyse
    from mtmc.artefact.study import _prepare

    pr = _prepare(study)
    a = analyse(pr.meas.centres[None, None].repeat(3, axis=1), pr.cal, pr.pinv, pr.Jp)
    r = a.r_max_measured[0] * 1e3  # um
    c = np.degrees(study.poses[:, 1])
    assert 0.5 < r[0] < 1.5  # linear axes only: ~1 um (Table 2: 0.9)
    assert np.all((r[c != 0] > 4.0) & (r[c != 0] < 7.0))  # with C: 5-6 um (Table 2: 5.4-6.8)
    assert np.all(r[c == 0] < 2.5)


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("repetitions = 3", "repetitions = 0", "plan.repetitions"),
        ("EB0Z = 4.0", "EQ0Z = 4.0", "machine.errors.EQ0Z"),
        ("EX0C = 3.0", "EX0C = [1.0, 2.0]", "machine.errors.EX0C"),
        ("dpz = 0.8", "dpq = 0.8", "setup_errors.dpq"),
        ("size_mm = 6.0", "size_mm = 9.0", "probing.size_mm"),
        ('radius = "calibrated"', 'radius = "fitted"', "probing.radius"),
        ("[0, 0], [0, 5]", "[0, 0, 1], [0, 5]", "plan.poses_deg"),
        ('library = "wbzfxyct"', 'library = "nope"', "machine.library"),
    ],
)
def test_study_errors_name_file_line_field(old: str, new: str, field: str) -> None:
    text = STUDY.read_text()
    assert old in text
    bad = text.replace(old, new)
    with pytest.raises(InputError) as e:
        loads_artefact_study(bad, "w.toml", STUDY.parent)
    want_line = next(
        i
        for i, t in enumerate(bad.splitlines(), 1)
        if new.split(" =")[0] in t and not t.lstrip().startswith("#")
    )
    assert e.value.file == "w.toml"
    assert e.value.field == field
    assert e.value.line == want_line


def _noise_free(study, **kw):  # type: ignore[no-untyped-def]
    from dataclasses import replace

    return replace(study, **kw)


def test_noise_free_study_recovers_injected_setup_errors(study) -> None:  # type: ignore[no-untyped-def]
    s = _noise_free(study, errors={})
    model, inputs, _pr = study_model(s)
    z = {k: np.zeros((1, d.dim)) for k, d in inputs.items()}
    out = model(**z)
    np.testing.assert_allclose(out["setup"][0], s.setup_errors, rtol=0, atol=1e-9)  # 1e-6 um
    assert np.abs(out["volumetric"]).max() < 1e-9


def test_batched_equals_one_trial_at_a_time(study) -> None:  # type: ignore[no-untyped-def]
    from dataclasses import replace

    s = replace(study, machine_repeatability=np.array([1e-4, 1e-4, 2e-4]), setup_u=3e-4)
    model, inputs, _ = study_model(s)
    rng = np.random.default_rng(np.random.SeedSequence(99))
    draws = {k: d.sample(rng, 4) for k, d in inputs.items()}
    batch = model(**draws)
    for i in range(4):
        one = model(**{k: v[i : i + 1] for k, v in draws.items()})
        for k in batch:
            np.testing.assert_allclose(batch[k][i], one[k][0], rtol=0, atol=1e-15)


def test_linear_fit_map_against_exact_fits(study) -> None:  # type: ignore[no-untyped-def]
    lin, inputs, _ = study_model(study)
    exact, _, _ = study_model(study, exact_fit=True)
    rng = np.random.default_rng(np.random.SeedSequence(12))
    draws = {k: d.sample(rng, 3) for k, d in inputs.items()}
    a, b = lin(**draws), exact(**draws)
    assert np.abs(a["centres"] - b["centres"]).max() < 1e-6  # mm: 1e-3 um
    assert np.abs(a["r_max_measured"] - b["r_max_measured"]).max() < 2e-6
    assert np.abs(a["setup"] - b["setup"]).max() < 1e-6


def test_monte_carlo_beside_gum(study) -> None:  # type: ignore[no-untyped-def]
    res = simulate(study, trials=1500, seed=5)
    # setup errors are linear in the centres: MC u = GUM u within MC tolerance
    np.testing.assert_allclose(res.mc_u["setup"], res.gum_u["setup"], rtol=0.12)
    np.testing.assert_allclose(res.mc_mean["setup"], res.nominal.setup[0], atol=0.2e-3)
    # r_avg is biased upwards by the noise where the errors are small: MC mean > noise-free
    i00 = 0
    assert res.mc_mean["r_avg_measured"][i00] > res.nominal.r_avg_measured[0, i00]
    j = res.to_json()
    assert [p["b_deg"] for p in j["poses"]] == [0, 0, 0, 5, 5, 5, 10, 10, 10]
    assert set(j["poses"][0]["r_max_um"]) >= {"estimate", "u"}
    assert set(j["setup_errors"]) >= {"dpx", "dw5z"}
    assert j["setup_errors"]["dpx"]["u"] > 0
    # identification covariance from the centres' covariance = GUM of the setup outputs
    np.testing.assert_allclose(res.identification.u, res.gum_u["setup"], rtol=1e-6)
    g = gum_outputs(study)
    np.testing.assert_allclose(g["setup"][1], res.gum_u["setup"], rtol=1e-12)


def test_centre_noise_has_the_law_of_the_point_noise(study) -> None:  # type: ignore[no-untyped-def]
    from mtmc.uncertainty import monte_carlo

    res = {}
    for noise in ("points", "centres"):
        model, inputs, _ = study_model(study, noise=noise)
        res[noise] = monte_carlo(model, inputs, trials=1500, seed=11, keep=False)
    assert study_model(study, noise="centres")[1]["probe"].dim == 3 * 135
    for out in ("setup", "r_max_measured", "centres"):
        np.testing.assert_allclose(
            res["centres"][out].u_vector, res["points"][out].u_vector, rtol=0.12
        )
    with pytest.raises(InputError):
        study_model(study, noise="centres", exact_fit=True)


def test_exact_fit_batch_equals_one_ball_and_one_trial_at_a_time(study) -> None:  # type: ignore[no-untyped-def]
    """Batched sphere fits over (trials, repetitions, poses, balls) and the identification
    by one factorised pseudo-inverse = a loop of single fits and per-trial least squares."""
    from mtmc.geometry.fits import fit_sphere

    model, inputs, pr = study_model(study, exact_fit=True)
    rng = np.random.default_rng(np.random.SeedSequence(31))
    m = 2
    draws = {k: d.sample(rng, m) for k, d in inputs.items()}
    batch = model(**draws)
    meas = pr.meas
    P, N, k = meas.points.shape[:3]
    R = study.repetitions
    AS = meas.axis_map * study.repeatability[None, None, :]
    z = draws["probe"].reshape(m, R, P, N, k, 3)
    radius = study.setup.artefact.radius
    J = np.tile(pr.J, (R, 1))
    rot = study.setup.artefact.rotation
    for i in range(m):
        centres = np.empty((R, P, N, 3))
        for r in range(R):
            for p in range(P):
                for n in range(N):
                    pts = meas.points[p, n] + z[i, r, p, n] @ AS[p].T
                    one = fit_sphere(pts, radius)
                    centres[r, p, n] = one.geometry.centre  # type: ignore[union-attr]
        got = batch["centres"][i].reshape(P, N, 3)
        np.testing.assert_allclose(got, centres.mean(axis=0), rtol=0, atol=1e-12)
        cal = pr.cal + draws["cmm"][i].reshape(N, 3) @ rot.T
        dF = (cal[None, None] - centres).reshape(-1)
        E, *_ = np.linalg.lstsq(J, dF, rcond=None)
        np.testing.assert_allclose(batch["setup"][i], E, rtol=0, atol=1e-12)
