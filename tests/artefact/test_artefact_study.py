"""The shipped study, its loader, the Monte Carlo model against one-at-a-time, exact fits, GUM."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.artefact.simulation import (
    ArtefactStudy,
    gum_outputs,
    simulate_artefact,
    study_model,
)
from mtmc.errors import InputError
from mtmc.kinematics.functions import PolynomialFunction
from mtmc.study import load_study, loads_study

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "wang2022.toml"


@pytest.fixture(scope="module")
def study():  # type: ignore[no-untyped-def]
    return load_study(STUDY).study


def test_shipped_study(study) -> None:  # type: ignore[no-untyped-def]
    assert (ROOT / "src/mtmc/data/studies/wang2022.toml").read_text() == STUDY.read_text()
    assert study.poses.shape == (9, 2)
    assert study.repetitions == 3
    np.testing.assert_allclose(np.degrees(study.poses[7]), [-10, 5])
    assert study.setup.machine.axes == ("X", "Y", "Z", "B", "C")
    assert isinstance(study.errors["EXX"], PolynomialFunction)
    np.testing.assert_allclose(study.errors["EXX"].coefficients, [0.0, -2.6e-6])  # um/m -> mm/mm
    assert study.errors["EC0Y"] == pytest.approx(4e-6)  # urad -> rad
    assert study.setup_errors[0] == pytest.approx(1e-3)  # dpx 1 um
    np.testing.assert_allclose(study.repeatability, [0.36e-3, 0.41e-3, 0.25e-3])
    assert study.text_is_chosen if hasattr(study, "text_is_chosen") else True
    assert "CHOSEN, NOT MEASURED" in STUDY.read_text()


#: Wang, Cheung and Kong 2022, Table 2 ① (measured), keyed by the printed (b, c) in degrees:
#: r_max, r_avg in um.
PAPER_T2 = {
    (0, 0): (0.9, 0.4),
    (0, 5): (5.5, 1.3),
    (0, -5): (5.4, 1.1),
    (5, 0): (1.1, 0.6),
    (5, 5): (5.6, 1.6),
    (5, -5): (5.7, 1.4),
    (10, 0): (1.6, 0.6),
    (10, 5): (6.8, 2.3),
    (10, -5): (6.4, 2.2),
}


def _table2_noise_free(study: ArtefactStudy) -> tuple[np.ndarray, np.ndarray]:
    from mtmc.artefact.analysis import analyse
    from mtmc.artefact.simulation import _prepare

    pr = _prepare(study)
    a = analyse(pr.meas.centres[None, None].repeat(3, axis=1), pr.cal, pr.pinv, pr.Jp)
    return a.r_max_measured[0] * 1e3, a.r_avg_measured[0] * 1e3  # um


def test_poses_are_table2_with_the_paper_sign_of_b(study) -> None:  # type: ignore[no-untyped-def]
    # ISO 841: the paper's (x, y, z, b, c) is mtmc's (x, y, -z, -b, c)
    paper = np.array(list(PAPER_T2), dtype=np.float64)
    np.testing.assert_allclose(np.degrees(study.poses), paper * [-1.0, 1.0], atol=1e-12)


def test_table2_pattern_and_magnitudes(study) -> None:  # type: ignore[no-untyped-def]
    """Every pair of poses that Table 2 ① orders by more than its printed 0.1 um, ours
    orders the same way (noise-free), for r_max and for r_avg; r_max within 1 um."""
    r_max, r_avg = _table2_noise_free(study)
    paper = np.array(list(PAPER_T2.values()))
    for ours, col in ((r_max, 0), (r_avg, 1)):
        p = paper[:, col]
        i, j = np.triu_indices(len(p), 1)
        apart = np.abs(p[i] - p[j]) > 0.15
        assert apart.sum() == 33
        assert np.all(np.sign(ours[i] - ours[j])[apart] == np.sign(p[i] - p[j])[apart])
    assert np.all(np.abs(r_max - paper[:, 0]) < 1.0)
    assert np.all(r_avg < 2.0 * paper[:, 1])


def test_mirrored_poses_lose_the_pattern(study) -> None:  # type: ignore[no-untyped-def]
    """The errors are chosen for the paper's b: at our +b (its -b) r_max no longer grows
    with b at c = 0 as the paper's does (0.9, 1.1, 1.6 um)."""
    from dataclasses import replace

    r_max, _ = _table2_noise_free(study)
    assert r_max[0] < r_max[3] < r_max[6]
    mirrored = replace(study, poses=study.poses * [-1.0, 1.0])
    r_mirror, _ = _table2_noise_free(mirrored)
    assert not r_mirror[0] < r_mirror[3] < r_mirror[6]


def test_what_drives_each_row(study) -> None:  # type: ignore[no-untyped-def]
    """EXY alone gives the c = +-5 deg rows their ~5 um and nothing at b = c = 0 beyond a
    few tenths; EB0Z alone grows with b; the C axis location errors change no distance."""
    from dataclasses import replace

    zero = np.zeros_like(study.setup_errors)

    def alone(name: str) -> np.ndarray:
        return _table2_noise_free(
            replace(study, errors={name: study.errors[name]}, setup_errors=zero)
        )[0]

    c = np.degrees(study.poses[:, 1])
    exy = alone("EXY")
    assert np.all(exy[c != 0] > 4.0)
    assert np.all(exy[c == 0] < 0.5)
    eb0z = alone("EB0Z")
    assert eb0z[0] < eb0z[3] < eb0z[6]
    for name in ("EX0C", "EY0C"):
        assert np.abs(alone(name)).max() < 1e-6


def test_probing_repeatability_read_per_point_and_per_centre(study) -> None:  # type: ignore[no-untyped-def]
    """Section 2.3's per-axis 0.36, 0.41, 0.25 um read as the s.d. of each point give, through
    the 30-point calibrated-radius fit, x and y centre s.d. within a quarter of the printed
    0.18, 0.21 um and a z centre s.d. 4 times smaller than the printed 0.24 um."""
    from mtmc.artefact.probing import fit_sensitivity, patch_points

    art = study.setup.artefact
    pts = patch_points(np.zeros(3), art.radius, (0.0, 0.0, 1.0), study.setup.offsets)
    K = fit_sensitivity(pts, np.zeros(3))[0]
    sd = np.sqrt((K * K) @ np.tile(np.square([0.36, 0.41, 0.25]), len(pts)))
    printed = np.array([0.18, 0.21, 0.24])
    assert np.all(np.abs(sd[:2] / printed[:2] - 1.0) < 0.25)
    assert 3.5 < printed[2] / sd[2] < 4.5


def test_a_per_probing_repeatability_alone_runs(study) -> None:  # type: ignore[no-untyped-def]
    """No per-point noise, one shift per probing of a ball: the centres scatter by it."""
    from dataclasses import replace

    sd = np.array([0.18, 0.21, 0.24]) * 1e-3
    s = replace(study, repeatability=np.zeros(3), machine_repeatability=sd, cmm=False)
    model, inputs, _ = study_model(s)
    rng = np.random.default_rng(np.random.SeedSequence(3))
    out = model(**{k: d.sample(rng, 4000) for k, d in inputs.items()})
    # the mean of the three repetitions at b = c = 0, where W is along the linear axes
    centres = out["centres"].reshape(4000, 9, 5, 3)[:, 0]
    got = centres.std(axis=0).mean(axis=0) * np.sqrt(3.0)
    np.testing.assert_allclose(got, sd, rtol=0.05)


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("repetitions = 3", "repetitions = 0", "plan.repetitions"),
        ("EB0Z = 45.0", "EQ0Z = 45.0", "machine.errors.EQ0Z"),
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
        loads_study(bad, file="w.toml", folder=STUDY.parent)
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
        # to rounding of the centres (about 60 mm, one ulp 7e-15 mm): one trial's products
        # may take another BLAS path (a matrix-vector product) than a block's
        for k in batch:
            np.testing.assert_allclose(batch[k][i], one[k][0], rtol=0, atol=2e-14)


@pytest.mark.parametrize(("rows", "k", "n"), [(1, 90, 3), (2067, 90, 3), (333, 18, 135)])
def test_thin_products_in_slices_against_exact_sums(rows: int, k: int, n: int) -> None:
    """The row slices of the thin products against correctly rounded sums (math.fsum)."""
    import math

    from mtmc.artefact.simulation import _thin_matmul

    rng = np.random.default_rng(np.random.SeedSequence(rows))
    a = rng.normal(size=(rows, 2, k))[:, 1]  # a strided view, as the model's slices are
    b = rng.normal(size=(k, n))
    got = _thin_matmul(a, b, np.empty((rows, n)))
    ref = np.array([[math.fsum(a[i] * b[:, j]) for j in range(n)] for i in range(rows)])
    # a sum of k products rounded in any order is within k·eps·Σ|a_i b_i| of the exact
    # one (Higham, Accuracy and Stability, §3.1); exact products are within eps of theirs
    bound = (k + 1) * np.finfo(float).eps * (np.abs(a) @ np.abs(b))
    assert np.all(np.abs(got - ref) <= bound)


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
    res = simulate_artefact(study, trials=1500, seed=5)
    # setup errors are linear in the centres: MC u = GUM u within MC tolerance
    np.testing.assert_allclose(res.mc_u["setup"], res.gum_u["setup"], rtol=0.12)
    np.testing.assert_allclose(res.mc_mean["setup"], res.nominal.setup[0], atol=0.2e-3)
    # r_avg is biased upwards by the noise where the errors are small: MC mean > noise-free
    i00 = 0
    assert res.mc_mean["r_avg_measured"][i00] > res.nominal.r_avg_measured[0, i00]
    j = res.to_json()
    assert [p["b_deg"] for p in j["poses"]] == [0, 0, 0, -5, -5, -5, -10, -10, -10]
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


def test_the_input_rows_of_the_optional_laws_state_them_in_um() -> None:
    # the rows of result.json's inputs for the machine's repeatability and the setup errors
    # (neither in the shipped study), against the study's own numbers in mm
    import dataclasses

    from mtmc.study.artefact import _inputs

    st = load_study(STUDY).study
    n = 3 + 3 * int(st.setup.artefact.n_balls)
    values = np.linspace(-2e-3, 3e-3, n)
    st = dataclasses.replace(
        st, machine_repeatability=(1e-4, 2e-4, 3e-4), setup_u=5e-4, setup_errors=values
    )
    rows = {r["name"]: r for r in _inputs(st)}
    probed = int(st.repetitions) * len(st.poses) * int(st.setup.artefact.n_balls)
    for axis, sd in zip("XYZ", (0.1, 0.2, 0.3), strict=True):
        row = rows[f"machine repeatability, {axis} (each of the {probed} probings)"]
        assert row == {
            "name": row["name"],
            "distribution": f"normal(0, {sd:g})",
            "estimate": 0.0,
            "u": pytest.approx(sd, rel=1e-12),
            "unit": "µm",
        }
    for name, v in zip(st.names, values, strict=True):
        row = rows[f"setup error {name}"]
        assert row["distribution"] == f"normal({1e3 * v:g}, 0.5)"
        assert (row["estimate"], row["u"], row["unit"]) == (
            pytest.approx(1e3 * v, rel=1e-12),
            pytest.approx(0.5, rel=1e-12),
            "µm",
        )
    assert len(rows) == 3 + 1 + 3 + n  # probing, the CMM's centres, machine, setup
