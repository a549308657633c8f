"""Monte Carlo of a verification: shared factorisation vs exact; MC vs GUM; JCGM 101 §8."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.instruments import LaserTracker
from mtmc.verification.identify import identify
from mtmc.verification.simulate import (
    VE_NAMES,
    Verification,
    VerificationModel,
    gum_verification,
    reference_identification,
    simulate,
    validate_verification,
)


def _ver(s, **kw):  # type: ignore[no-untyped-def]
    return Verification(
        s["model"], s["q"], s["tracker"], s["model"].errors(s["theta"]), fixed=s["fixed"], **kw
    )


def test_shared_factorisation_matches_exact_identification(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    ver = _ver(s)
    ref = reference_identification(ver)
    vm = VerificationModel.build(ver, ref)
    assert vm.refine == 2
    rng = np.random.default_rng(np.random.SeedSequence(21))
    z = rng.normal(size=(6, ver.n_points, 3))
    x = vm.noise.perturb(np.broadcast_to(vm.x_true, z.shape), z)
    est, r, _, _ = vm.solve(x)
    exact = identify(s["model"], s["q"], x, s["tracker"], fixed=s["fixed"])
    assert exact.converged.all()
    # every coefficient and the pose, noise and all, to 1e-6 relative
    assert np.abs(est / exact.estimate - 1.0).max() < 1e-6
    # the chord iterations alone stop short: their fixed point solves J0^T r = 0
    chord, _, _, _ = VerificationModel.build(ver, ref, refine=0).solve(x)
    assert np.abs(chord / exact.estimate - 1.0).max() > 1e-5
    # the linearised machine model of the residual leaves out products of errors
    assert np.abs(np.linalg.norm(r, axis=-1) - exact.residual_ve).max() < 1e-5


def test_noise_free_machine_in_model_gives_zero_residual_and_true_coefficients(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    ref = reference_identification(_ver(s))
    free = [s["model"].parameter_names.index(n) for n in ref.names[:-6]]
    assert np.abs(ref.estimate[0, :-6] / s["theta"][free] - 1).max() < 1e-9
    assert ref.residual_ve.max() < 1e-10


def test_monte_carlo_against_gum(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    ver = _ver(s)
    r = simulate(ver, 3000, 2026, repeatability=0.002)
    assert r.coef_samples.shape == (3000, len(r.names))
    assert not r.coef_u.flags.writeable
    # standard uncertainty of each coefficient: MC vs GUM within the MC's sampling error
    assert np.allclose(r.coef_u, r.gum.u, rtol=0.08)
    assert np.allclose(r.point_u, r.gum.point_u, rtol=0.08)
    # the noise raises the initial error and leaves a residual (Aguado et al. 2017 Fig. 5, 6)
    assert r.ve("residual.mean")[0] < r.ve("initial.mean")[0]
    assert len(VE_NAMES) == r.ve_estimate.size == 9
    # the bias of the compensation is zero when the model represents the machine
    assert np.abs(r.comp_bias).max() < 4 * r.comp_u.max() / np.sqrt(3000) + 1e-9


def test_monte_carlo_against_gum_pose_known(setup) -> None:  # type: ignore[no-untyped-def]
    """Pose not identified: its uncertainty and the reflector offset's are inputs."""
    s = setup
    ver = _ver(s, pose=False)
    pu = [2e-6, 2e-6, 2e-6, 0.005, 0.005, 0.005]
    r = simulate(ver, 3000, 99, pose_u=pu, reflector_u=0.003)
    assert np.allclose(r.coef_u, r.gum.u, rtol=0.08)
    assert np.allclose(r.point_u, r.gum.point_u, rtol=0.08)
    with pytest.raises(InputError, match="absorbed"):
        simulate(_ver(s), 10, 1, pose_u=pu)


def test_gum_of_the_engine_agrees_with_the_analytic_linearisation(setup) -> None:  # type: ignore[no-untyped-def]
    """mtmc.uncertainty.gum (differences through the whole model) vs A Σ Aᵀ."""
    from mtmc.uncertainty import gum

    s = setup
    ver = _ver(s)
    vm = VerificationModel.build(ver, reference_identification(ver))
    g = gum(lambda noise: vm(noise)["coef"], vm.inputs())
    assert np.allclose(g.u_vector, gum_verification(vm).u, rtol=1e-4)


def test_jcgm101_validation_of_a_near_linear_case(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    vm = VerificationModel.build(_ver(s), reference_identification(_ver(s)))
    v = validate_verification(vm, "EC0Y", 5000, 7, ndig=1)
    assert v.passed, v


def test_same_seed_same_numbers(setup) -> None:  # type: ignore[no-untyped-def]
    s = setup
    a = simulate(_ver(s), 200, 5)
    b = simulate(_ver(s), 200, 5)
    assert np.array_equal(a.coef_samples, b.coef_samples)
    bare = LaserTracker(s["tracker"].rotation, s["tracker"].position)
    with pytest.raises(InputError, match="noise"):
        Verification(s["model"], s["q"], bare, {})


def test_point_mean_statistics_against_numpy_on_kept_samples(setup) -> None:  # type: ignore[no-untyped-def]
    from mtmc.uncertainty import monte_carlo

    s = setup
    ver = _ver(s)
    trials, seed = 80, 31
    sim = simulate(ver, trials, seed)
    # the same trials, the noise and the compensated errors kept, the statistics by NumPy
    vm = VerificationModel.build(ver, reference_identification(ver))

    def model(noise):  # type: ignore[no-untyped-def]
        return {**vm(noise), "z": noise}

    kept = monte_carlo(model, vm.inputs(), trials, seed, keep=["z", "comp"])
    z = np.asarray(kept["z"].samples).reshape(trials, -1, 3)
    x_nom = s["tracker"].to_tracker(s["machine"].tool_position(s["q"]))
    reading = vm.noise.perturb(np.broadcast_to(ver.readings(), z.shape), z)
    errors = {
        "initial": np.linalg.norm(reading - x_nom, axis=-1),
        "compensated": np.linalg.norm(
            np.asarray(kept["comp"].samples).reshape(trials, -1, 3), axis=-1
        ),
    }
    for which, e in errors.items():
        got = sim.point_mean_ve(which)
        per_point = e.mean(axis=0)
        i, j = int(np.argmax(per_point)), int(np.argmin(per_point))
        want = {
            "max": (per_point[i], e[:, i].std(ddof=1)),
            "mean": (per_point.mean(), e.mean(axis=1).std(ddof=1)),
            "min": (per_point[j], e[:, j].std(ddof=1)),
        }
        for k in ("max", "mean", "min"):
            assert np.allclose(got[k], want[k], rtol=1e-9, atol=0.0), (which, k, got[k], want[k])
        # not the mean over the verifications of each one's max and min
        assert got["max"][0] < sim.ve(f"{which}.max")[0]
        assert got["min"][0] > sim.ve(f"{which}.min")[0]
    with pytest.raises(InputError, match="initial"):
        sim.point_mean_ve("residual")
    # the same numbers in blocks on two workers
    par = simulate(ver, trials, seed, workers=2)
    assert np.array_equal(par.initial_point_mean, sim.initial_point_mean)
    assert np.array_equal(par.compensated_point_u, sim.compensated_point_u)


def test_the_initial_error_is_the_reading_against_the_nominal_machine(setup) -> None:  # type: ignore[no-untyped-def]
    # The "initial" error of Aguado et al.: a reading of the true machine against
    # the reading the nominal machine would give at the nominal tracker pose. Without
    # noise it is the machine's own error, which identify() computes on its own route;
    # with noise the noise is added to it (measured against the truth it would vanish).
    s = setup
    ver = _ver(s)
    ref = reference_identification(ver)
    vm = VerificationModel.build(ver, ref)
    n = ver.n_points
    out = vm(np.zeros((1, 3 * n)))
    assert ref.initial_ve.max() > 1e-3  # some µm of machine error
    np.testing.assert_allclose(out["point_initial"][0], ref.initial_ve[0], rtol=1e-9, atol=1e-12)
    z = np.random.default_rng(np.random.SeedSequence(5)).normal(size=(3, 3 * n))
    noisy = vm(z)["point_initial"]
    x_meas = vm.noise.perturb(np.broadcast_to(vm.x_true, (3, n, 3)), z.reshape(3, n, 3))
    np.testing.assert_allclose(noisy, np.linalg.norm(x_meas - vm.x_nom, axis=-1), rtol=1e-12)


def test_a_verification_is_the_same_bits_whatever_the_evaluation_block(setup, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # each trial's identification is summed on its own (no BLAS product over the batch,
    # whose kernels change with the number of rows): blocks of 37, 100 or all 300 trials
    # give the same numbers, as the engine promises for any chunking
    from mtmc.uncertainty import montecarlo

    original = montecarlo.evaluation_block_size
    ver = _ver(setup)
    out = []
    for size in (37, 100, 300):
        monkeypatch.setattr(
            montecarlo, "evaluation_block_size", lambda d, s, n=size: min(n, original(d, s))
        )
        r = simulate(ver, 300, 11)
        out.append((np.asarray(r.ve_samples), np.asarray(r.coef_samples)))
    for ve, coef in out[1:]:
        np.testing.assert_array_equal(ve, out[0][0])
        np.testing.assert_array_equal(coef, out[0][1])


def test_the_model_sent_to_a_worker_gives_the_same_bits(setup) -> None:  # type: ignore[no-untyped-def]
    # a worker process gets the model pickled: its arrays must have the layout they have
    # here (a view pickles as a contiguous copy, and a product then sums in another order)
    import pickle

    ver = _ver(setup)
    vm = VerificationModel.build(ver, reference_identification(ver))
    sent = pickle.loads(pickle.dumps(vm))
    z = np.random.default_rng(np.random.SeedSequence(3)).normal(size=(100, 3 * ver.n_points))
    here, there = vm(z), sent(z)
    for key in ("ve", "coef", "comp"):
        np.testing.assert_array_equal(here[key], there[key])


class _PerTrialNoise:
    """The noise of the readings recomputed from the true points for every block of trials."""

    def __init__(self, noise, x) -> None:  # type: ignore[no-untyped-def]
        self.noise, self.x = noise, x

    def perturb(self, z):  # type: ignore[no-untyped-def]
        return self.noise.perturb(np.broadcast_to(self.x, z.shape), z)


def test_the_noise_computed_once_gives_the_bits_of_perturbing_every_trial(setup) -> None:  # type: ignore[no-untyped-def]
    # the model keeps the spherical coordinates of the true readings and their standard
    # deviations; recomputing them for every block (the reference) changes no bit
    import dataclasses

    ver = _ver(setup)
    vm = VerificationModel.build(ver, reference_identification(ver))
    every = dataclasses.replace(vm, noise_at=_PerTrialNoise(vm.noise, vm.x_true))
    z = np.random.default_rng(np.random.SeedSequence(4)).normal(size=(50, 3 * ver.n_points))
    once, again = vm(z), every(z)
    assert sorted(once) == sorted(again)
    for key in once:
        np.testing.assert_array_equal(once[key], again[key])


def test_slices_of_trials_give_the_bits_of_one_pass(setup, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # the model evaluates a block in slices of trials to bound its working memory; every
    # trial is computed on its own, so slices of 7 trials (the last one short) give the
    # numbers of one pass over the 50 trials, with every optional input present
    from mtmc.verification import simulate as sim

    ver = _ver(setup, pose=False)
    vm = VerificationModel.build(
        ver, reference_identification(ver), repeatability=1e-3, pose_u=[1e-6] * 3 + [1e-3] * 3
    )
    rng = np.random.default_rng(np.random.SeedSequence(6))
    n3 = 3 * ver.n_points
    draws = {"noise": rng.normal(size=(50, n3)), "repeatability": rng.normal(size=(50, n3))}
    draws["pose"] = rng.normal(size=(50, 6))
    whole = vm(**draws)
    monkeypatch.setattr(sim, "_SLICE", 7 * ver.n_points)
    sliced = vm(**draws)
    assert sorted(sliced) == sorted(whole)
    for key in whole:
        np.testing.assert_array_equal(sliced[key], whole[key])


def test_a_verification_on_a_process_pool_gives_the_same_bits(setup, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # the model (its noise at the true readings included) is pickled to two worker
    # processes, three blocks of trials among them; the result equals the one in-process
    from mtmc.uncertainty import montecarlo

    original = montecarlo.evaluation_block_size
    monkeypatch.setattr(montecarlo, "evaluation_block_size", lambda d, s: min(40, original(d, s)))
    ver = _ver(setup)
    here = simulate(ver, 120, 13)
    there = simulate(ver, 120, 13, workers=2, executor="process")
    for name in ("ve_samples", "coef_samples", "comp_u", "compensated_point_mean"):
        np.testing.assert_array_equal(getattr(there, name), getattr(here, name))


def test_evaluation_at_the_measured_points_gives_the_bits_of_the_general_path(setup) -> None:  # type: ignore[no-untyped-def]
    # without eval_q the compensated readings are the identification's model readings,
    # computed once; eval_q given as a copy of q takes the general path (the evaluation
    # points' own Jacobian and positions): every output the same bits, optional inputs too
    import pickle

    s = setup
    z = np.random.default_rng(np.random.SeedSequence(8)).normal(size=(30, 3 * len(s["q"])))
    rep = np.random.default_rng(np.random.SeedSequence(9)).normal(size=z.shape)
    for extra in ({}, {"repeatability": 1e-3}):
        ver = _ver(s)
        vm = VerificationModel.build(ver, reference_identification(ver), **extra)
        other = _ver(s, eval_q=np.array(s["q"]))
        vg = VerificationModel.build(other, reference_identification(other), **extra)
        assert vm.at_measured
        assert not vg.at_measured
        # one array for both, and one in the copy a worker gets
        assert vm.Jpe is vm.Jp
        assert vm.pe_fit is vm.p_fit
        assert vm.xe_true is vm.x_true
        sent = pickle.loads(pickle.dumps(vm))
        assert sent.Jpe is sent.Jp
        draws = {"noise": z, "repeatability": rep} if extra else {"noise": z}
        here, general = vm(**draws), vg(**draws)
        assert sorted(here) == sorted(general)
        for key in here:
            np.testing.assert_array_equal(here[key], general[key])


def test_chord_operators_equal_their_sums() -> None:
    """G, S and K of the module notes against their sums over the points written out."""
    from mtmc.geometry.transforms import matrix_from_rotation_vector
    from mtmc.verification.simulate import _chord_operators

    rng = np.random.default_rng(5)
    p, n, k = 6, 50, 4
    A = rng.normal(size=(p, 3 * n))
    p_fit = rng.normal(size=(n, 3)) * 100.0
    Jp = rng.normal(size=(n, 3, k))
    R = matrix_from_rotation_vector(np.array([0.1, -0.2, 0.3]))
    t = np.array([1.0, 2.0, -3.0])
    y, G, S, K = _chord_operators(A, p_fit, Jp, R, t)
    A3 = A.reshape(p, n, 3)
    want_y = np.array([R.T @ (p_fit[i] - t) for i in range(n)])
    want_G = np.zeros((p, 3, 3))
    want_K = np.zeros((p, 3, 3, k))
    for i in range(3):
        for j in range(3):
            want_G[:, i, j] = A3[:, :, j] @ want_y[:, i]
            want_K[:, i, j] = A3[:, :, j] @ Jp[:, i]
    # sums of n products (BLAS): a few ulps of the largest term
    for got, want in ((y, want_y), (G, want_G.reshape(p, 9)), (K, want_K.reshape(p, 9 * k))):
        assert got.flags.c_contiguous
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * np.abs(want).max())
    np.testing.assert_allclose(S, A3.sum(axis=1), rtol=0, atol=1e-14 * np.abs(A3).max() * n)


def test_gum_propagation_equals_the_dense_sandwich():
    """A Σ Aᵀ (+ Σ E Eᵀ) and G cov Gᵀ against the products with Σ written out whole."""
    from mtmc.verification.simulate import _gum_propagate

    rng = np.random.default_rng(3)
    p, n, k = 7, 40, 9
    A = rng.normal(size=(p, 3 * n))
    L = rng.normal(size=(n, 3, 3))
    C = L @ L.transpose(0, 2, 1) + 0.1 * np.eye(3)
    G = rng.normal(size=(n, 3, p))
    E = rng.normal(size=(n, 3, k))
    cov, pc = _gum_propagate(A, C, G, [E])
    sigma = np.zeros((3 * n, 3 * n))
    for i in range(n):
        sigma[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = C[i]
    e = E.reshape(3 * n, k)
    want = A @ (sigma + e @ e.T) @ A.T
    # well-conditioned sums of products: a few ulps of the largest term
    np.testing.assert_allclose(cov, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    assert np.array_equal(cov, cov.T)
    for i in range(n):
        w = G[i] @ want @ G[i].T
        np.testing.assert_allclose(pc[i], w, rtol=1e-11, atol=1e-11 * np.abs(w).max())
    assert np.array_equal(pc, pc.transpose(0, 2, 1))


def test_the_set_up_and_the_gum_run_blas_on_one_thread(setup, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # thin factorisations and products, whose idle BLAS threads would spin on the
    # workers' cores: one thread in the reference identification, the model's build and
    # the GUM; the process's setting comes back after the run
    from threadpoolctl import threadpool_info, threadpool_limits

    from mtmc.verification import simulate as sim

    def threads() -> int:
        return max(d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas")

    seen: list[tuple[str, int]] = []

    def spy(name, fn):  # type: ignore[no-untyped-def]
        def wrapped(*a, **kw):  # type: ignore[no-untyped-def]
            seen.append((name, threads()))
            return fn(*a, **kw)

        return wrapped

    monkeypatch.setattr(sim, "reference_identification", spy("ref", sim.reference_identification))
    monkeypatch.setattr(sim, "gum_verification", spy("gum", sim.gum_verification))
    build = VerificationModel.build.__func__  # type: ignore[attr-defined]
    monkeypatch.setattr(
        VerificationModel,
        "build",
        classmethod(spy("build", lambda cls, *a, **kw: build(cls, *a, **kw))),
    )
    with threadpool_limits(limits=2, user_api="blas"):
        before = threads()
        sim.simulate(_ver(setup), 20, 1)
        after = threads()
    assert before == 2
    assert seen == [("ref", 1), ("build", 1), ("gum", 1)]
    assert after == before
