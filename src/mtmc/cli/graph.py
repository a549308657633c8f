"""``mtmc graph``: check, draw, export, run, sweep and edit a measurement graph (Stryczek).

A thin shell: it reads the file, calls :mod:`mtmc.graph` and prints. Errors print one
line (``mtmc: error: FILE:LINE: field F: ...``) and exit with status 2; files are
written atomically (:mod:`mtmc.io`); ``run`` and ``sweep`` show a progress bar on stderr.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    NAN_POLICY_OPTION,
    PROGRESS_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    check_trials,
    engine_message,
    fail,
    nan_policy,
    parallel_options,
    print_json,
    print_trials_seed,
    progress_bar,
    quiet_numpy,
    seed_option,
    warn,
    write_output,
)
from mtmc.cli.run_options import ADAPTIVE_OPTION, run_lines
from mtmc.errors import MtmcError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    import numpy as np
    from numpy.typing import NDArray

    from mtmc.graph.structure import Graph

app = typer.Typer(
    rich_markup_mode=None,
    help="Measurement graphs (Stryczek): check, draw, run, sweep.",
    no_args_is_help=True,
)

#: Suffixes ``graph draw`` writes: Matplotlib formats, and Graphviz DOT text.
DRAW_SUFFIXES = (".svg", ".png", ".pdf", ".dot")

FILE = typer.Argument(..., help="Graph file: .toml, or the assertion database (.pl, .db, .facts).")


def _read(path: Path) -> Graph:
    from mtmc.graph.files import load_graph

    return load_graph(path)


@app.command("check")
def check_cmd(file: Path = FILE, as_json: bool = JSON_OPTION) -> None:
    """Validate FILE and print its places, transitions and firing order."""
    from mtmc.graph.model import check_graph

    try:
        plan = check_graph(_read(file))
    except MtmcError as exc:
        fail(exc)
    warn(plan.warnings)
    g = plan.graph
    if as_json:
        print_json(
            {
                "file": str(file),
                "places": dict(plan.types),
                "marked": list(plan.marked),
                "transitions": [t.name for t in g.transitions],
                "generations": [list(names) for names in plan.generations],
                "warnings": list(plan.warnings),
            }
        )
        return
    typer.echo(
        f"{file.name}: ok: {len(plan.types)} places ({len(plan.marked)} marked), "
        f"{len(g.transitions)} transitions, {len(plan.generations)} generations"
    )
    for i, names in enumerate(plan.generations):
        typer.echo(f"  generation {i}: {' '.join(names)}")


@app.command("draw")
def draw_cmd(
    file: Path = FILE,
    output: Path = typer.Option(
        ..., "-o", "--output", help="Output file: .svg, .png, .pdf or .dot."
    ),
) -> None:
    """Draw FILE: places as circles, transitions as boxes, markers as dots."""
    from mtmc.graph.draw import draw_graph, graph_to_dot
    from mtmc.io import atomic_path

    suffix = output.suffix.lower()
    if suffix not in DRAW_SUFFIXES:
        fail(f"{output}: expected a file ending in {', '.join(DRAW_SUFFIXES)}, got {suffix!r}")
    try:
        g = _read(file)
        if suffix == ".dot":
            write_output(output, graph_to_dot(g))
        else:
            with atomic_path(output) as tmp:
                draw_graph(g, tmp)
    except MtmcError as exc:
        fail(exc)
    except OSError as exc:
        fail(f"{output}: cannot write: {exc.strerror or exc}")
    typer.echo(f"wrote {output}")


@app.command("export")
def export_cmd(
    file: Path = FILE,
    to: str = typer.Option("assertions", "--to", help="assertions, toml or dot."),
    output: Path | None = typer.Option(
        None, "-o", "--output", help="Write to this file (default: stdout)."
    ),
) -> None:
    """Print FILE as Stryczek's assertion database, as TOML or as DOT."""
    from mtmc.graph.assertions import dumps_assertions
    from mtmc.graph.draw import graph_to_dot
    from mtmc.graph.toml_format import dumps_graph

    writers = {"assertions": dumps_assertions, "toml": dumps_graph, "dot": graph_to_dot}
    if to not in writers:
        fail(f"--to: expected one of {', '.join(writers)}, got {to!r}")
    try:
        text = writers[to](_read(file))
    except MtmcError as exc:
        fail(exc)
    if output is None:
        typer.echo(text, nl=False)
    else:
        write_output(output, text)
        typer.echo(f"wrote {output}")


@app.command("run")
def run_cmd(
    file: Path = FILE,
    trials: int | None = typer.Option(
        None, "--trials", "-n", help="Number of Monte Carlo trials M (default 100000)."
    ),
    seed: int | None = seed_option("fresh entropy"),
    place: list[str] | None = typer.Option(
        None, "--place", help="Only this place (repeat the option for more)."
    ),
    as_json: bool = JSON_OPTION,
    nan: str = NAN_POLICY_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    adaptive: bool = ADAPTIVE_OPTION,
) -> None:
    """Run FILE by Monte Carlo and print each place's estimate and standard uncertainty.

    The table gives lengths in the graph's units (the file's units), angles in rad (a
    real place written in deg, in deg);
    --json gives the library's result as it is, in mm and rad (its "units").
    """
    from mtmc.graph.model import check_graph
    from mtmc.graph.run import run_graph
    from mtmc.graph.units import file_unit

    check_trials(trials)
    if adaptive and trials is not None:
        fail("--adaptive chooses the number of trials itself (JCGM 101 §7.9); not with --trials")
    try:
        plan = check_graph(_read(file))
        warn(plan.warnings)
        with progress_bar(f"{file.name}: Monte Carlo", progress) as bar, quiet_numpy():
            res = run_graph(
                plan,
                trials,
                seed,
                outputs=place or None,
                progress=bar,
                nan_policy=nan_policy(nan),
                adaptive=adaptive,
                **parallel_options(workers, executor, scheduler),
            )
    except MtmcError as exc:
        fail(engine_message(exc))
    if as_json:
        print_json({**res.to_dict(), "units": {"length": "mm", "angle": "rad"}})
        return
    table = Table(title=f"{file.name}: Monte Carlo over the graph (Stryczek)")
    for col in ("place", "type", "part"):
        table.add_column(col)
    table.add_column("estimate", justify="right")
    table.add_column("u", justify="right")
    table.add_column("unit")
    for name, s in res.places.items():
        first = True
        for part in s.parts:
            r = s.part(part)
            u = r.u if r.dim == 0 else r.u_vector
            scale, unit = file_unit(plan, name, part)
            table.add_row(
                name if first else "",
                s.type if first else "",
                "" if part == "value" else part,
                _fmt(r.estimate if r.dim == 0 else r.estimate_vector, u, scale),
                _fmt(u, u, scale, the_u=True),
                unit,
            )
            first = False
    Console().print(table)
    print_trials_seed(res.trials, res.seed)
    run: dict[str, Any] = {"trials": res.trials, "omitted": res.omitted}
    run |= {"adaptive": res.adaptive, "blocks": res.blocks, "tolerance": res.tolerance}
    run["ndig"] = 2  # the engine's default, which the command does not change
    for line in run_lines(run):
        typer.echo(line)


def _fmt(
    v: float | NDArray[np.float64],
    u: float | NDArray[np.float64],
    scale: float,
    *,
    the_u: bool = False,
) -> str:
    """A number, or the components of an array, in the file's unit (divided by ``scale``).

    Each is rounded as the report rounds it (:func:`mtmc.report.at_place`, JCGM 100
    §7.2.6): its standard uncertainty ``u`` (same shape) to two significant digits and the
    estimate to the same decimal place; with ``the_u`` the text is ``u`` itself so rounded.
    A component whose ``u`` is zero is shown to six significant digits.
    """
    import numpy

    from mtmc.report import at_place

    if isinstance(v, float):
        return at_place(v / scale, float(u) / scale, the_u=the_u)
    us = numpy.broadcast_to(numpy.asarray(u, dtype=numpy.float64), v.shape).ravel()
    cells = (
        at_place(x / scale, ux / scale, the_u=the_u) for x, ux in zip(v.ravel(), us, strict=True)
    )
    return "[" + ", ".join(cells) + "]"


@app.command("sweep")
def sweep_cmd(
    file: Path = FILE,
    vary: list[str] = typer.Option(
        ..., "--vary", help="KEY=LOW:HIGH:N, e.g. probe.u_probe=0.001:0.005:5 (repeatable)."
    ),
    quantity: str = typer.Option(
        ..., "--quantity", help="The scalar place whose standard uncertainty is swept."
    ),
    trials: int = typer.Option(1000, "--trials", "-n", help="Trials per grid point."),
    seed: int | None = seed_option("fresh entropy; one seed for every grid point"),
    csv: Path | None = typer.Option(None, "--csv", help="Write the grid as CSV here."),
    no_intercept: bool = typer.Option(False, "--no-intercept", help="Fit without c0."),
    as_json: bool = JSON_OPTION,
    nan: str = NAN_POLICY_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
) -> None:
    """Run FILE on a grid and fit the surrogate u^2 = c0 + sum c_i sigma_i^2 (Stryczek eq. 31)."""
    from mtmc.graph.sweep import parse_range, sweep_graph

    try:
        ranges = {}
        for item in vary:
            key, eq, rng = item.partition("=")
            if not eq:
                fail(f"--vary: expected KEY=LOW:HIGH:N, got {item!r}")
            ranges[key.strip()] = parse_range(rng, field=f"--vary {key.strip()}")
        g = _read(file)
        with progress_bar(f"{file.name}: sweep", progress) as bar:
            res = sweep_graph(
                g,
                ranges,
                quantity,
                trials=trials,
                seed=seed,
                progress=bar,
                nan_policy=nan_policy(nan),
                **parallel_options(workers, executor, scheduler),
            )
        fit = res.fit(intercept=not no_intercept)
    except MtmcError as exc:
        fail(engine_message(exc))
    text = res.to_csv(fit)
    if csv is not None:
        write_output(csv, text)
    if as_json:
        print_json(
            {
                "trials": res.trials,
                "seed": res.seed,
                "omitted": res.omitted,
                "output": quantity,
                "names": list(res.names),
                "grid": res.grid,
                "u": res.u,
                "surrogate": {
                    "c0": fit.c0,
                    "coefficients": dict(zip(fit.names, fit.coefficients.tolist(), strict=True)),
                    "max_rel_error": fit.max_rel_error,
                },
            }
        )
        return
    if csv is None:
        typer.echo(text, nl=False)
    typer.echo(f"surrogate: {fit.formula()}")
    typer.echo(f"largest relative error on the grid: {100 * fit.max_rel_error:.2f} %")
    print_trials_seed(res.trials, res.seed)
    if res.omitted:
        total = res.trials * len(res.u)
        typer.echo(f"{res.omitted} of {total} trials left out: a model value was NaN or infinite")


@app.command("edit")
def edit_cmd(
    file: Path = typer.Argument(
        ..., help="Graph file (.toml); a new one is written on the first save if it does not exist."
    ),
    port: int = typer.Option(0, "--port", help="Port on 127.0.0.1 (default: a free one)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Print the URL; open nothing."),
) -> None:
    """Edit FILE in the browser and see its uncertainties live (the extra "editor").

    The first line printed is the page's URL (127.0.0.1 only, with a random token).
    Ctrl-C stops the server; over an unsaved edit, press it twice.
    """
    try:
        from mtmc.workbench import serve
    except ImportError as exc:
        fail(f'the workbench needs the editor extra ({exc.name}): pip install "mtmc[editor]"')
    try:
        serve(file, port=port, open_browser=not no_browser, echo=typer.echo)
    except MtmcError as exc:
        fail(exc)
