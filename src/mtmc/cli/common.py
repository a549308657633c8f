"""Options and helpers shared by the subcommands: errors, JSON output, progress bars, files.

Every subcommand fails the same way, through :func:`fail` (one line on stderr, exit status
2); prints JSON through :func:`print_json` (one object on stdout); shows progress through
:func:`progress_bar` (a Rich bar on stderr, so stdout stays clean for ``--json``); and
writes files through :func:`write_output` (atomic, :mod:`mtmc.io`).
"""

from __future__ import annotations

import contextlib
import json
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, NoReturn

import typer

from mtmc.errors import InputError, MtmcError
from mtmc.io import to_jsonable, write_bytes_atomic, write_text_atomic
from mtmc.report import MAX_PLOTTED, plotted_from_text

if TYPE_CHECKING:  # the library and Rich's progress bar are imported where they are used
    from rich.console import Console

    from mtmc.uncertainty.distributions import Distribution
    from mtmc.uncertainty.montecarlo import ProgressFn

#: The ``--progress/--no-progress`` option of the long-running subcommands.
PROGRESS_OPTION: Any = typer.Option(
    None,
    "--progress/--no-progress",
    help="Show a progress bar on stderr (default: when stderr is a terminal).",
    show_default=False,
)


#: ``-q/--quiet`` of the commands that run a Monte Carlo.
QUIET_OPTION: Any = typer.Option(
    False,
    "--quiet",
    "-q",
    help="No progress bar and no table: the line 'trials M  seed S' stays, with how the run "
    "went (adaptive, trials left out), the JCGM 106 decisions and the report's path.",
)

#: ``-o/--output`` of the commands that run a Monte Carlo and may keep it.
RESULT_OPTION: Any = typer.Option(
    None,
    "-o",
    "--output",
    help="Also write the result folder (result.json, the study file, report.html) here; "
    "created with its parents.",
    show_default=False,
)


#: ``--plots N|all`` of the commands that write a report: how many quantities, from the
#: first, get a histogram and a convergence plot (:func:`mtmc.report.plotted_count`).
PLOTS_OPTION: Any = typer.Option(
    None,
    "--plots",
    metavar="N|all",
    help="How many quantities, from the first, get a histogram and a convergence "
    f"plot in the report: a whole number or 'all' (default {MAX_PLOTTED}).",
    show_default=False,
)


def plots_value(plots: str | None) -> int | str | None:
    """``--plots`` as :func:`mtmc.report.render` takes it; one line and exit 2 on a bad value."""
    try:
        return plotted_from_text(plots)
    except InputError as exc:
        fail(f"--plots: {exc.message}")


def progress_flag(progress: bool | None, quiet: bool) -> bool | None:
    """``--progress/--no-progress`` as ``-q`` leaves it: ``-q`` turns the bar off."""
    return False if quiet else progress


#: ``--nan-policy``: what a run does with trials whose model value is NaN or infinite.
NAN_POLICY_OPTION: Any = typer.Option(
    "raise",
    "--nan-policy",
    help="raise: stop with one line at a model value that is NaN or infinite; omit: leave "
    "those trials out (the number left out is printed).",
)


def nan_policy(value: str) -> Literal["raise", "omit"]:
    """``--nan-policy`` checked: ``raise`` or ``omit``.

    Raises
    ------
    InputError
        For any other value.
    """
    from mtmc.errors import InputError

    if value not in ("raise", "omit"):
        raise InputError(f"expected raise or omit, got {value!r}", field="--nan-policy")
    return "raise" if value == "raise" else "omit"


@contextlib.contextmanager
def quiet_numpy() -> Iterator[None]:
    """NumPy's floating-point warnings off: a NaN or inf is reported once, by the engine."""
    import numpy as np

    with np.errstate(all="ignore"):
        yield


def load_study_of_kind(path: Path, kind: str) -> Any:
    """The study of ``path`` as ``mtmc run`` reads it, which must be of ``kind``.

    Raises
    ------
    InputError
        For another kind (naming the file and the field ``kind``), or as
        :func:`mtmc.study.load_study`.
    """
    from mtmc.errors import InputError
    from mtmc.study import load_study

    study = load_study(path)
    if study.kind != kind:
        raise InputError(
            f"expected a{'n' if kind[0] in 'aeiou' else ''} {kind} study, got kind {study.kind!r}",
            file=str(path),
            field="kind",
        )
    return study


def engine_message(exc: BaseException) -> str:
    """The text of an engine error, with its ``nan_policy`` advice in CLI terms."""
    return str(exc).replace("nan_policy='omit'", "--nan-policy omit")


#: ``--json``: the results as one JSON object on stdout (see ``docs/cli.md``).
JSON_OPTION: Any = typer.Option(
    False, "--json", help="Print the results as one JSON object on stdout, and nothing else there."
)


def seed_option(default: str) -> Any:
    """The ``-s/--seed`` option of a command that runs a Monte Carlo.

    Parameters
    ----------
    default : str
        What seeds the run when the option is not given, e.g. ``"the study's run.seed"``.

    Returns
    -------
    typer.models.OptionInfo
        A non-negative integer option; the command prints the seed it used (given, from
        the study, or drawn from fresh entropy) so that the run can be repeated.
    """
    return typer.Option(
        None,
        "--seed",
        "-s",
        min=0,
        help=f"Seed of the random numbers (default: {default}); the seed used is printed.",
    )


def print_trials_seed(trials: int, seed: int) -> None:
    """Print ``trials M  seed S``: what repeats a Monte Carlo run (``-n M -s S``)."""
    typer.echo(f"trials {trials}  seed {seed}")


#: ``--workers N``: blocks of trials (or grid points) evaluated at once.
WORKERS_OPTION: Any = typer.Option(
    1, "--workers", "-w", min=1, help="Workers that evaluate blocks of trials at once."
)

#: ``--executor``: where the workers run.
EXECUTOR_OPTION: Any = typer.Option(
    "thread",
    "--executor",
    help="thread, process, or dask (a local Dask cluster of --workers processes, or the "
    "cluster of --scheduler). The numbers do not depend on it.",
)

#: ``--scheduler ADDRESS``: a running Dask cluster.
SCHEDULER_OPTION: Any = typer.Option(
    None,
    "--scheduler",
    help="Address of a running Dask scheduler, e.g. tcp://127.0.0.1:8786 (implies "
    "--executor dask).",
)


def parallel_options(workers: int, executor: str, scheduler: str | None) -> dict[str, Any]:
    """The ``workers``, ``executor`` and ``scheduler`` arguments of a run, checked.

    Parameters
    ----------
    workers : int
        ``--workers``.
    executor : str
        ``--executor``: ``thread``, ``process`` or ``dask``.
    scheduler : str or None
        ``--scheduler``; it implies ``--executor dask``.

    Returns
    -------
    dict
        Keyword arguments for :func:`mtmc.uncertainty.monte_carlo`, ``run_graph`` or
        ``sweep``.

    Raises
    ------
    InputError
        For an unknown executor.
    """
    from mtmc.errors import InputError

    if executor not in ("thread", "process", "dask"):
        raise InputError(f"expected thread, process or dask, got {executor!r}", field="--executor")
    if scheduler is not None:
        executor = "dask"
    return {"workers": workers, "executor": executor, "scheduler": scheduler}


def with_u(y: float, u: float) -> str:
    """An estimate with its standard uncertainty: ``"282 (u = 43)"``.

    Both rounded as JCGM 100 §7.2.6 says (u to two significant digits, y to the same
    decimal place), written with ``u =`` and not ``±`` (JCGM 100 §7.2.2 keeps ``±`` for an
    expanded uncertainty). A ``u`` that is not positive leaves y unrounded.

    Examples
    --------
    >>> with_u(282.3712, 43.0711), with_u(0.0, 0.0)
    ('282 (u = 43)', '0 (u = 0)')
    """
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    if not (u > 0.0 and abs(u) < float("inf")):
        return f"{y:g} (u = {u:g})"
    y_text, u_text = round_to_uncertainty(y, u)
    return f"{y_text} (u = {u_text})"


def fail(exc: BaseException | str, code: int = 2) -> NoReturn:
    """Print a one-line error on stderr and stop the subcommand with status ``code``.

    This is the one way a subcommand fails: :func:`mtmc.cli.main.main` returns ``code``.

    Parameters
    ----------
    exc : exception or str
        The error; only the first line of its text is printed, after ``mtmc: error:``.
    code : int, default 2
        The exit status.

    Raises
    ------
    typer.Exit
        Always, carrying ``code``.
    """
    msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    typer.echo(f"mtmc: error: {msg}", err=True)
    raise typer.Exit(code)


def input_texts(specs: list[str]) -> dict[str, str]:
    """The ``-i NAME=DISTRIBUTION`` options, split: each name's distribution text, in order.

    Raises
    ------
    InputError
        On a text without ``=`` or a name, or a name given twice.
    """
    texts: dict[str, str] = {}
    for spec in specs:
        name, sep, text = spec.partition("=")
        name = name.strip()
        if not sep or not name:
            raise InputError(
                f"expected NAME=DISTRIBUTION, e.g. x=normal(0, 1), got {spec!r}", field="-i"
            )
        if name in texts:
            raise InputError(f"input {name} given more than once", field=name)
        texts[name] = text.strip()
    return texts


def input_specs(specs: list[str]) -> dict[str, Distribution]:
    """The ``-i NAME=DISTRIBUTION`` options of ``mtmc propagate``, parsed, in their order.

    Raises
    ------
    InputError, DistributionError
        On a text without ``=`` or a name, a name given twice, or a distribution that
        does not parse (named ``-i NAME``, with its column).
    """
    from mtmc.uncertainty.distributions import parse_distribution

    dists: dict[str, Distribution] = {}
    for name, text in input_texts(specs).items():
        try:
            dists[name] = parse_distribution(text, field=name)
        except MtmcError as exc:  # "line 1" would point at no file: name the option instead
            where = f" (column {exc.column})" if exc.column is not None else ""
            raise type(exc)(exc.message + where, field=f"-i {name}") from None
    return dists


def validated_text(passed: bool | None) -> str:
    """The "GUM validated" cell of a command's table: yes, no or not applicable."""
    return "not applicable" if passed is None else "yes" if passed else "no"


def check_trials(trials: int | None, p: float | None = None) -> None:
    """Refuse ``--trials`` above the most a study's ``[run] trials`` may ask (10⁹).

    With ``p``, also fewer than the coverage interval needs
    (:func:`mtmc.uncertainty.require_trials`).

    Parameters
    ----------
    trials : int or None
        The option's value (None: not given).
    p : float, optional
        The coverage probability of the run.

    Raises
    ------
    typer.Exit
        Through :func:`fail`, with one line naming the option.
    """
    from mtmc.study.settings import MAX_TRIALS
    from mtmc.uncertainty.results import require_trials

    if trials is not None and trials > MAX_TRIALS:
        fail(f"--trials: expected at most {MAX_TRIALS} trials, got {trials}")
    if trials is not None and p is not None:
        try:
            require_trials(trials, p)
        except InputError as exc:
            if exc.field == "trials":  # not p itself: that is refused where it is read
                fail(f"--trials: {exc.message}")


def warn(lines: Iterable[str]) -> None:
    """Print each warning as one line ``mtmc: warning: ...`` on stderr."""
    for line in lines:
        typer.echo(f"mtmc: warning: {line}", err=True)


def print_json(obj: Any) -> None:
    """Write exactly one JSON object on stdout: strict JSON, NaN and infinities as null."""
    sys.stdout.write(json.dumps(to_jsonable(obj, nonfinite_as_null=True), allow_nan=False) + "\n")


def write_output(path: Path, content: str | bytes) -> None:
    """Write a file of the CLI atomically (:mod:`mtmc.io`), or fail with one line.

    Parameters
    ----------
    path : Path
        The destination; its folder must exist.
    content : str or bytes
        Text (written as UTF-8) or bytes.

    Raises
    ------
    typer.Exit
        Through :func:`fail` (status 2) when the file cannot be written; the message
        names the file and the reason. An existing file is then left as it was.
    """
    try:
        if isinstance(content, bytes):
            write_bytes_atomic(path, content)
        else:
            write_text_atomic(path, content)
    except OSError as exc:
        fail(f"{path}: cannot write: {exc.strerror or exc}")


def progress_wanted(flag: bool | None) -> bool:
    """Resolve ``--progress/--no-progress``: unset means "when stderr is a terminal"."""
    if flag is not None:
        return flag
    isatty = getattr(sys.stderr, "isatty", None)
    return bool(isatty and isatty())


#: A run whose remaining time is estimated above this (seconds) says so, once.
LONG_RUN_S: float = 60.0


def duration_text(seconds: float) -> str:
    """``"45 s"``, ``"3 min 20 s"``, ``"2 h 05 min"``: a duration as a person reads it."""
    s = round(seconds)
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


class _Estimate:
    """Progress callback that says, once, how long a long run will take.

    After one second of a run (from the first report of progress) the trials done give
    the rate; where the trials left would take more than :data:`LONG_RUN_S` at that
    rate, one line on stderr gives the trials per second and the estimated time, so a
    run of 10⁹ trials can be stopped (Ctrl-C) before the wait, not after.
    """

    def __init__(self, description: str) -> None:
        self.description = description
        self.start: float | None = None
        self.said = False

    def __call__(self, done: int, total: int | None) -> None:
        import time

        now = time.perf_counter()
        if self.start is None:
            self.start = now
            self.first = done
            return
        elapsed = now - self.start
        if self.said or total is None or elapsed < 1.0 or done <= self.first:
            return
        self.said = True
        rate = (done - self.first) / elapsed
        left = (total - done) / rate
        if left > LONG_RUN_S:
            typer.echo(
                f"mtmc: {self.description}: {total:,} trials at {rate:,.0f} trials/s: about "
                f"{duration_text(left)} to go (Ctrl-C stops the run; nothing is written)",
                err=True,
            )


@contextlib.contextmanager
def progress_bar(
    description: str,
    enabled: bool | None = None,
    *,
    console: Console | None = None,
    unit: str = "trials",
) -> Iterator[ProgressFn]:
    """A Rich progress bar on stderr, as a library progress callback.

    Parameters
    ----------
    description : str
        The text before the bar.
    enabled : bool or None
        ``True``/``False`` from ``--progress/--no-progress``; ``None``: only when stderr
        is a terminal (:func:`progress_wanted`).
    console : rich.console.Console, optional
        Where to draw (default: a console on stderr). On a terminal the bar is removed
        when done; elsewhere (stderr redirected to a file) its final state is printed once.
    unit : str
        What the bar counts (``verify place``: the steps of its search).

    Yields
    ------
    callable
        ``update(done, total)`` to pass as ``progress=`` to :func:`mtmc.monte_carlo`,
        :func:`mtmc.graph.run_graph` or :func:`mtmc.graph.sweep_graph`. A ``total`` of
        None shows a bar of unknown length. With the bar on or off, a run whose
        remaining time is estimated above :data:`LONG_RUN_S` says so once on stderr,
        with its trials per second (:class:`_Estimate`).
    """
    estimate = _Estimate(description)
    if not progress_wanted(enabled):
        yield estimate
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    con = console if console is not None else Console(stderr=True)
    bar = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn(unit),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=con,
        transient=con.is_terminal,
    )
    with bar:
        task = bar.add_task(description, total=None)

        def update(done: int, total: int | None) -> None:
            bar.update(task, completed=done, total=total)
            estimate(done, total)

        yield update


__all__ = [
    "JSON_OPTION",
    "NAN_POLICY_OPTION",
    "PROGRESS_OPTION",
    "QUIET_OPTION",
    "RESULT_OPTION",
    "input_texts",
    "progress_flag",
    "check_trials",
    "validated_text",
    "input_specs",
    "duration_text",
    "engine_message",
    "load_study_of_kind",
    "nan_policy",
    "quiet_numpy",
    "seed_option",
    "MtmcError",
    "fail",
    "print_json",
    "print_trials_seed",
    "progress_bar",
    "progress_wanted",
    "to_jsonable",
    "warn",
    "write_output",
]
