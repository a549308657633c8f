"""The demo: the shipped studies, run one after the other into ``mtmc-demo/``.

``python -m mtmc.demo`` (or ``mtmc demo``, ``make demo``) runs, on built-in defaults and
in well under a minute, the five-axis story as study files (the package's copies of
``examples/studies``, so the demo runs from an installed package):

1. ``mass_calibration``: JCGM 101 §9.3, Monte Carlo beside the GUM (kind ``propagate``);
2. ``ball_centre``: the centre of a calibration ball from 4 + 1 probed points (Stryczek
   Fig. 5–6, kind ``graph``);
3. ``axis_c`` and ``axis_a``: the rotary axes C and A from three ball positions each
   (Stryczek eqs. 8–19);
4. ``bcs_origin``: the A–C offset and the origin of the base coordinate system, with u on
   the σ_probe × σ_machine grid and the fitted surrogate (Stryczek Fig. 12–15);
5. ``five_axis``: a five-axis table-table machine with uncertain ISO 230 geometric errors
   through its forward kinematics to the tool position at four poses (kind
   ``kinematics``);
6. ``aguado2017``: the laser-tracker volumetric verification of an XFYZ machine of Aguado
   et al. 2017, its identified error functions and calibration uncertainty (kind
   ``verification``);
7. ``wang2022``: the fiducial artefact of Wang, Cheung and Kong (2022), its setup errors
   and volumetric errors at nine rotary poses (kind ``artefact``);
8. ``circle_xy`` and ``circle_c_axis``: an ISO 230-4 circular test in XY and the C-axis
   R-test of a five-axis machine, each a whole test a trial (kind ``circular``).

Each study writes its result folder (``result.json``, CSV tables, ``provenance.json``,
``report.html``) under the output folder, and ``index.html`` links the reports. There is
no mathematics here: every number comes from :mod:`mtmc.study`.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from mtmc.errors import InputError
from mtmc.report import plotted_from_text

__all__ = ["STUDIES", "main", "run_demo", "study_path"]

#: The shipped studies the demo runs, in order (files of ``mtmc/data/studies``).
STUDIES: tuple[str, ...] = (
    "mass_calibration.toml",
    "bore_type_a.toml",
    "gauge_blocks_correlated.toml",
    "polar_coordinates.toml",
    "ball_centre.toml",
    "axis_c.toml",
    "axis_a.toml",
    "bcs_origin.toml",
    "five_axis.toml",
    "aguado2017.toml",
    "wang2022.toml",
    "circle_xy.toml",
    "circle_c_axis.toml",
)


def _unit(unit: str) -> str:
    """A unit after a number: ``" mm"``; nothing for a quantity of dimension one."""
    return "" if unit in ("", "1") else f" {unit}"


def _k(k: float | None) -> str:
    """`` (k = 1.96)``: the coverage factor of an expanded uncertainty, k = U/u."""
    return "" if k is None else f" (k = {k:.2f})"


def study_path(name: str) -> Path:
    """The path of a shipped study file (``mtmc/data/studies/NAME``)."""
    return Path(str(resources.files("mtmc").joinpath("data", "studies", name)))


def run_demo(
    out: str | Path = "mtmc-demo",
    *,
    trials: int | None = None,
    seed: int | None = None,
    studies: Sequence[str] | None = None,
    progress: Callable[[str], Any] | None = None,
    echo: Callable[[str], Any] = print,
    on_result: Callable[[Path, Any], Any] | None = None,
    plotted: int | str | None = None,
    **parallel: Any,
) -> Path:
    """Run the shipped studies into ``out`` and write ``out/index.html``.

    Parameters
    ----------
    out : str or Path
        The output folder (created); each study writes ``out/STEM/``.
    trials : int, optional
        Overrides the trials of every study (the sweeps keep theirs per grid point).
    seed : int, optional
        Overrides the seed of every study.
    studies : sequence of str, optional
        Which shipped studies (default :data:`STUDIES`).
    progress : callable, optional
        ``progress(label)`` gives a context manager yielding a progress callback (the
        CLI's Rich bar); None: no bar.
    echo : callable
        Where the one-line summaries go (each states the seed of its study).
    on_result : callable, optional
        ``on_result(folder, result)`` after each study's result folder is written.
    plotted : int or "all", optional
        How many quantities of each report, from the first, get a histogram and a
        convergence plot (default :data:`mtmc.report.MAX_PLOTTED`).
    **parallel
        ``workers``, ``executor``, ``scheduler`` of every run (:meth:`Study.run`).

    Returns
    -------
    pathlib.Path
        ``out/index.html``.
    """
    import contextlib

    from mtmc.report import plotted_count, render_index
    from mtmc.study import load_study, write_result
    from mtmc.study.write import now

    plotted_count({}, plotted)  # checked before the first study runs
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    entries = []
    start = time.perf_counter()
    for name in STUDIES if studies is None else studies:
        study = load_study(study_path(name))
        stem = Path(name).stem
        t0 = time.perf_counter()
        started = now()
        bar = progress(name) if progress is not None else contextlib.nullcontext(None)
        with bar as step:
            result = study.run(trials=trials, seed=seed, progress=step, **parallel)
        write_result(
            result,
            folder / stem,
            study_text=study.source.text,
            started=started,
            argv=["mtmc", "demo"],
            plotted=plotted,
        )
        if on_result is not None:
            on_result(folder / stem, result)
        entries.append((stem, stem))
        heads = "; ".join(
            f"{q.name} = {q.reported.estimate}{_unit(q.unit)}, "
            f"U = {q.reported.U}{_unit(q.unit)}{_k(q.mc.k)}"
            for q in result.quantities[:2]
        )
        p = f"{100 * result.p:g} %"
        took = f"{time.perf_counter() - t0:.1f} s"
        echo(f"{result.title}: {heads} (U at p = {p}; seed {result.seed}; {took})")
    index = render_index(entries, folder / "index.html")
    echo(f"{len(entries)} studies in {time.perf_counter() - start:.1f} s.")
    echo(f"Report: {index}")
    return index


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m mtmc.demo [--out DIR] [--trials N] [--seed S] [--plots N|all]``.

    Returns 0, or 130 on Ctrl-C.

    Each study's folder is written whole or not at all, so an interrupted demo leaves the
    studies done so far, complete, and none half-written.
    """
    parser = argparse.ArgumentParser(prog="python -m mtmc.demo", description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("mtmc-demo"), help="output folder")
    parser.add_argument("--trials", type=int, default=None, help="trials of every study")
    parser.add_argument("--seed", type=int, default=None, help="seed of every study")
    parser.add_argument(
        "--plots",
        default=None,
        metavar="N|all",
        help="quantities of each report with a histogram and a convergence plot",
    )
    args = parser.parse_args(argv)
    if args.trials is not None and args.trials < 2:
        parser.error(f"--trials: expected an integer >= 2, got {args.trials}")
    try:
        plotted = plotted_from_text(args.plots)
    except InputError as exc:
        parser.error(f"--plots: {exc.message}")
    if args.out.exists() and not args.out.is_dir():
        parser.error(f"--out: expected a folder, but {args.out} is a file")
    try:
        run_demo(args.out, trials=args.trials, seed=args.seed, plotted=plotted)
    except KeyboardInterrupt:
        print("mtmc demo: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
