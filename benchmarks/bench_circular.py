"""The Monte Carlo of a whole ISO 230-4 circular test: two directions of 720 points.

Each trial is one test: the machine's squareness, scale mismatch, backlash of both axes,
servo mismatch and the set-up's centre offset as PDFs, the ballbar's calibration, its
expansion and temperature, the noise and the resolution of each of the 1440 readings
(2880 drawn numbers a trial); from the readings F, G by the least-squares and the
minimum-zone circle, H and G(b), and the least-squares identification of the eight
errors of the model. Target: 10^4 trials in <= 2 s on one core. The GUM beside it
(central differences, 2897 inputs in one batched call) is timed apart.

Then the five-axis test: the C axis of ``wCBXfYZt`` through 360 positions, X, Y, Z
following, read by an R-test (3 x 360 readings, gain errors and noise) and by a radial
ballbar (360 readings), the location errors and the set-up as PDFs, and in each trial the
ranges and the identification. Target: 10^4 trials in <= 2 s on one core each.

Run: ``python benchmarks/bench_circular.py [--trials N] [--repeat R]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from mtmc.circular import Ballbar, circular_model, design, follow_positions, rotary_model
from mtmc.kinematics import Machine
from mtmc.uncertainty import Normal, Uniform, gum, monte_carlo
from mtmc.uncertainty.heap import keep_heap


def main() -> int:
    keep_heap()  # as the mtmc command does when it starts
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, nargs="*", default=[1])
    args = ap.parse_args()
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    t = np.linspace(0.0, 2 * np.pi, 720, endpoint=False)
    des = design(radius=150.0, theta_ccw=t, theta_cw=t)
    errors = {
        "squareness": Normal(2e-5, 2e-6),
        "scale_mismatch": Normal(1e-5, 1e-6),
        "backlash_x": Normal(0.003, 0.0005),
        "backlash_y": Normal(0.002, 0.0005),
        "servo_mismatch": Normal(5e-4, 5e-5),
        "centre_x": Uniform(-0.005, 0.005),
        "centre_y": Uniform(-0.005, 0.005),
    }
    bar = Ballbar(
        length_error=Normal(0.0, 0.0005),
        alpha=Normal(11.5e-6, 1e-6),
        temperature=Normal(20.5, 0.3),
        resolution=1e-4,
        noise=3e-4,
    )
    model, inputs = circular_model(des, bar, errors=errors)
    for w in args.workers:
        walls, cpus = [], []
        for _ in range(args.repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            mc = monte_carlo(model, inputs, args.trials, 1, keep=True, workers=w)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        assert mc.samples is not None
        print(
            f"Monte Carlo of {args.trials} tests of 2 x 720 points, {len(model.outputs)} outputs, "
            f"{w} worker(s): wall {min(walls):.2f} s (best of {args.repeat}; "
            f"{', '.join(f'{x:.2f}' for x in walls)}), CPU {min(cpus):.2f} s"
        )
    t0 = time.perf_counter()
    g = gum(model, inputs)
    print(f"GUM beside it ({g.method}): {time.perf_counter() - t0:.2f} s")
    i = model.outputs.index("G_mz")
    print(
        f"G_mz: Monte Carlo {mc.estimate_vector[i] * 1e3:.2f} µm, u {mc.u_vector[i] * 1e3:.2f} µm"
    )
    _rotary(args.trials, args.repeat, bar)
    return 0


def _rotary(trials: int, repeat: int, bar: Ballbar) -> None:
    """The C-axis test of 360 positions by an R-test and by a radial ballbar (docstring)."""
    m = Machine.from_topology("wCBXfYZt")
    c = np.radians(np.arange(360.0))
    q = follow_positions(m, {"B": 0.0, "C": c}, [150.0, 0.0, 80.0])
    errors = {
        "EX0C": Normal(0.01, 0.002),
        "EY0C": Normal(-0.02, 0.002),
        "EA0C": Normal(3e-5, 5e-6),
        "EB0C": Normal(-2e-5, 5e-6),
        "EXP": Normal(0.005, 0.001),
        "EYP": Normal(0.004, 0.001),
        "EZP": Normal(-0.003, 0.001),
    }
    jac = m.jacobian(q, None, names=list(errors))
    cases = {
        "R-test": rotary_model(jac, errors, gain=Normal(0.0, 5e-4), noise=2e-4),
        "ballbar": rotary_model(jac, errors, ballbar=bar, direction=[1, 0, 0], length=100.0),
    }
    for name, (model, inputs) in cases.items():
        walls, cpus = [], []
        for _ in range(repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            monte_carlo(model, inputs, trials, 1, keep=True, workers=1)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        print(
            f"C-axis test, 360 positions, {name}, {len(model.outputs)} outputs, {trials} trials, "
            f"1 worker: wall {min(walls):.2f} s (best of {repeat}), CPU {min(cpus):.2f} s"
        )


if __name__ == "__main__":
    raise SystemExit(main())
