"""A small XFYZ verification shared by the tests: 5 × 4 × 5 mesh, tool offset 150 mm."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.instruments import LaserTracker, TrackerNoise
from mtmc.kinematics import ErrorModel, Machine, PolynomialFunction

TRAVEL = {"X": (0.0, 800.0), "Y": (0.0, 600.0), "Z": (0.0, 400.0)}


def make_machine() -> Machine:
    return Machine.from_topology("XFYZ", tool=(0.0, 0.0, 150.0), travel=TRAVEL)


def make_model(machine: Machine, order: int = 3) -> ErrorModel:
    """An identifiable XFYZ model for one reflector offset (see :func:`fixed_terms`).

    Positioning and straightness of degree ``order``; squareness; the angular errors
    that have a lever arm (EAX EBX ECX EAY EBY) linear. Z's angular errors act on the
    fixed tool offset only (indistinguishable from Z's straightness) and ECY turns the
    reflector about its own axis line: they are left out.
    """
    t: dict[str, object] = {}
    for ax in "XYZ":
        for c in "XYZ":
            t[f"E{c}{ax}"] = PolynomialFunction([0.0] * (order + 1))
    for name in ("EAX", "EBX", "ECX", "EAY", "EBY"):
        t[name] = PolynomialFunction([0.0, 0.0])
    t.update({"EC0Y": 0.0, "EB0Z": 0.0, "EA0Z": 0.0})
    return ErrorModel(machine, t)  # type: ignore[arg-type]


def fixed_terms(model: ErrorModel) -> tuple[str, ...]:
    """Held at zero: every constant term (the errors are zero at q = 0; a constant is a
    shift or turn of the tracker) and the linear terms of the straightnesses (the
    squarenesses and the tracker's rotation carry them)."""
    out = [n for n in model.parameter_names if n.endswith("[0]")]
    out += [f"{e}[1]" for e in ("EYX", "EZX", "EXY", "EZY", "EXZ", "EYZ")]
    return tuple(out)


def mesh() -> np.ndarray:
    g = np.meshgrid(
        np.linspace(0, 800, 5), np.linspace(0, 600, 4), np.linspace(0, 400, 5), indexing="ij"
    )
    return np.stack([a.ravel() for a in g], axis=-1)


def truth_vector(model: ErrorModel, fixed: tuple[str, ...], rng_seed: int = 7) -> np.ndarray:
    """Plausible coefficients: a few µm of linear error and a few µrad of angle over the travel."""
    rng = np.random.default_rng(np.random.SeedSequence(rng_seed))
    th = np.zeros(model.n_parameters)
    for i, n in enumerate(model.parameter_names):
        if n in fixed:
            continue
        k = int(n.split("[")[1][0]) if "[" in n else 0
        ang = (n[1] in "ABC" and "0" not in n[2:3]) or n in ("EC0Y", "EB0Z", "EA0Z")
        scale = (20e-6 if ang else 0.02) / (700.0**k if "[" in n else 1.0)
        th[i] = scale * rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 1.0)
    return th


@pytest.fixture
def setup() -> dict[str, object]:
    machine = make_machine()
    model = make_model(machine)
    fixed = fixed_terms(model)
    tracker = LaserTracker.from_euler(
        [-900.0, 200.0, 700.0], [0.03, 0.03, 59.0], degrees=True, noise=TrackerNoise.aguado2017()
    )
    return {
        "machine": machine,
        "model": model,
        "fixed": fixed,
        "tracker": tracker,
        "q": mesh(),
        "theta": truth_vector(model, fixed),
    }
