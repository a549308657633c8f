"""Forward kinematics of a five-axis machine with every error as a degree-3 polynomial.

Compares ``Machine.tool_position`` (element-wise factor chain) with a plain-NumPy,
loop-free chain of (M, 4, 4) homogeneous matrices written here, on the same poses and
errors, and checks that both give the same positions.

Run: ``python benchmarks/bench_kinematics.py [--poses N] [--block B] [--repeat R]``. The
HTM reference runs on the first ``--htm-poses`` poses and is scaled to ``--poses``. The
figure depends on the allocator (see ``docs/performance.md``); the variants alternate in
each repetition and the best repetition is kept, for a shared machine.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from mtmc.kinematics import PolynomialFunction, library_machine

SPEC = "table-table"  # wCAXfYZt


def make_errors(machine, rng):
    """Every standard error: component errors as cubic polynomials, the rest constants."""
    errs = {}
    for name in machine.error_names:
        term = machine.error_term(name)
        s = 2e-5 if term.angular else 2e-3
        if term.kind == "component":
            L = 500.0 if term.axis in "XYZ" else 3.0
            errs[name] = PolynomialFunction(rng.normal(size=4) * s / L ** np.arange(4))
        else:
            errs[name] = float(rng.normal() * s)
    return errs


def _E(d, e):
    """(M, 4, 4) [[I + [e]x, d], [0, 1]] from d, e of shape (M, 3)."""
    m = d.shape[0]
    T = np.zeros((m, 4, 4))
    a, b, c = e[:, 0], e[:, 1], e[:, 2]
    T[:, 0, 0] = T[:, 1, 1] = T[:, 2, 2] = T[:, 3, 3] = 1.0
    T[:, 0, 1], T[:, 1, 0] = -c, c
    T[:, 0, 2], T[:, 2, 0] = b, -b
    T[:, 1, 2], T[:, 2, 1] = -a, a
    T[:, :3, 3] = d
    return T


def _Einv_rot(d, e):
    """(M, 4, 4) [[R^T, -R^T d], [0, 1]] for R = I + [e]x."""
    T = _E(np.zeros_like(d), e)
    R = np.swapaxes(T[:, :3, :3], 1, 2).copy()
    T[:, :3, :3] = R
    T[:, :3, 3] = -np.einsum("mij,mj->mi", R, d)
    return T


def htm_chain(machine, q, errs):
    """Plain NumPy reference: the chain of (M, 4, 4) matrices, multiplied out."""
    m = q.shape[0]
    col = {a: i for i, a in enumerate(machine.axes)}

    def val(name, ax=None):
        v = errs.get(name, 0.0)
        if isinstance(v, PolynomialFunction):
            return v(q[:, col[ax]])
        return np.full(m, float(v))

    def vec(names, ax=None):
        return np.stack([val(n, ax) if n else np.zeros(m) for n in names], axis=1)

    S = _Einv_rot(machine.workpiece + vec(["EXP", "EYP", "EZP"]), vec(["EAP", "EBP", "ECP"]))
    chain = S
    for ax in machine.topology.chain:
        d_names = [f"E{c}{ax}" for c in "XYZ"]
        r_names = [f"E{c}{ax}" for c in "ABC"]
        E = _E(vec(d_names, ax), vec(r_names, ax))
        k = "XYZ".index({"A": "X", "B": "Y", "C": "Z"}.get(ax, ax))
        if ax in "XYZ":
            sq = [None, None, None]
            for j in range(3):
                n = f"E{'ABC'[j]}0{ax}"
                if j != k and n in machine.error_names:
                    sq[j] = n
            direction = np.zeros((m, 3))
            direction[:, k] = 1.0
            s = vec(sq)
            direction = direction + np.cross(s, direction)
            T = _E(q[:, col[ax], None] * direction, np.zeros((m, 3)))
            chain = chain @ T @ E
        else:
            loc_d = vec([None if j == k else f"E{'XYZ'[j]}0{ax}" for j in range(3)])
            loc_r = vec([None if j == k else f"E{'ABC'[j]}0{ax}" for j in range(3)])
            L = _E(loc_d, loc_r)
            Linv = _Einv_rot(loc_d, loc_r)
            ang = q[:, col[ax]]
            R = np.zeros((m, 4, 4))
            i, j = (k + 1) % 3, (k + 2) % 3
            R[:, k, k] = R[:, 3, 3] = 1.0
            R[:, i, i] = R[:, j, j] = np.cos(ang)
            R[:, i, j] = -np.sin(ang)
            R[:, j, i] = np.sin(ang)
            chain = chain @ L @ E @ R @ Linv
    tool = _E(machine.tool + vec(["EXT", "EYT", "EZT"]), vec(["EAT", "EBT", "ECT"]))
    chain = chain @ tool
    return chain[:, :3, 3]


TARGET = 1e7  # poses / s, table-table, every error, one core


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--poses", type=int, default=1_000_000)
    ap.add_argument("--block", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--htm-poses", type=int, default=200_000, help="poses for the HTM reference")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    machine = library_machine(SPEC)
    rng = np.random.default_rng(np.random.SeedSequence(20260101))
    errs = make_errors(machine, rng)
    lo = np.array([machine.travel[a][0] for a in machine.axes])
    hi = np.array([machine.travel[a][1] for a in machine.axes])
    q = lo + (hi - lo) * rng.random((args.poses, len(machine.axes)))
    blocks = [q[i : i + args.block] for i in range(0, args.poses, args.block)]
    q_htm = q[: args.htm_poses]
    blocks_htm = [q_htm[i : i + args.block] for i in range(0, len(q_htm), args.block)]

    def run(fn, parts):
        # the variants alternate within each repetition, so that a change of the load
        # of a shared machine touches them alike; the best of the repetitions is kept
        return min(_timed(fn, parts) for _ in range(args.repeat))

    t_one = t_blk = t_htm = t_nom = c_one = np.inf
    for _ in range(args.repeat):
        c0 = time.process_time()
        t_one = min(t_one, _timed(lambda b: machine.tool_position(b, errs), [q]))
        c_one = min(c_one, time.process_time() - c0)
        t_blk = min(t_blk, _timed(lambda b: machine.tool_position(b, errs), blocks))
        t_nom = min(t_nom, _timed(lambda b: machine.tool_position(b), blocks))
    t_htm = run(lambda b: htm_chain(machine, b, errs), blocks_htm) * args.poses / len(q_htm)
    check = q[:20_000]
    diff = np.max(np.abs(machine.tool_position(check, errs) - htm_chain(machine, check, errs)))
    load1 = os.getloadavg()[0]
    print(
        f"machine {machine.topology} ({SPEC}), {len(machine.error_names)} errors "
        f"(component errors cubic polynomials), {args.poses:,} poses, best of {args.repeat}; "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"NumPy {np.__version__}, OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}, "
        f"load average {load0:.1f} -> {load1:.1f}"
    )
    print(f"{'method':<52}{'time / s':>10}{'poses / s':>14}")
    for label, t in (
        ("mtmc Machine.tool_position, all errors, one call", t_one),
        (f"mtmc Machine.tool_position, all errors, calls of {args.block:,}", t_blk),
        ("plain NumPy (M, 4, 4) HTM chain, all errors", t_htm),
        (f"mtmc Machine.tool_position, no errors, calls of {args.block:,}", t_nom),
    ):
        print(f"{label:<52}{t:>10.3f}{args.poses / t:>14,.0f}")
    best = args.poses / min(t_one, t_blk)
    print(
        f"CPU time of the one call (this process, all threads): {c_one:.3f} s = "
        f"{args.poses / c_one:,.0f} poses per CPU second"
    )
    print(
        f"speed-up over the HTM chain: {t_htm / t_one:.1f}x (one call); "
        f"target {TARGET:.0e} poses/s: {best:.2e} ({best / TARGET:.2f} x target); "
        f"max |difference| = {diff:.2e} mm"
    )


def _timed(fn, parts) -> float:
    t0 = time.perf_counter()
    for b in parts:
        fn(b)
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
