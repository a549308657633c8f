"""``mtmc graph``: check, draw, run and sweep a measurement graph (seed 000).

A thin shell: it reads the file, calls :mod:`mtmc.graph` and prints. Errors print one
line (``mtmc: error: FILE:LINE: field F: ...``) and exit with status 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import NoReturn

import typer

from mtmc.cli.common import fail as _common_fail
from mtmc.cli.common import print_json
from mtmc.errors import MtmcError
from mtmc.graph.model import Graph

app = typer.Typer(
    help="Measurement graphs (seed 000): check, draw, run, sweep.", no_args_is_help=True
)


def fail(exc: BaseException | str) -> NoReturn:
    """Print one error line and exit with status 2 (as ``SystemExit``).

    ``mtmc.cli.main.main`` runs the app with ``standalone_mode=False``, where click turns a
    ``typer.Exit`` into a return value that ``main`` drops; ``SystemExit`` reaches it.
    """
    try:
        _common_fail(exc)
    except typer.Exit as stop:
        raise SystemExit(stop.exit_code) from None


FILE = typer.Argument(..., help="Graph file: .toml, or the assertion database (.pl, .db, .facts).")


def _read(path: Path) -> Graph:
    from mtmc.graph.files import read_graph

    return read_graph(path)


@app.command("check")
def check_cmd(file: Path = FILE) -> None:
    """Validate FILE and print its places, transitions and firing order."""
    from mtmc.graph.model import check

    try:
        plan = check(_read(file))
    except MtmcError as exc:
        fail(exc)
    g = plan.graph
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
    from mtmc.graph.draw import draw, to_dot

    try:
        g = _read(file)
        if output.suffix.lower() == ".dot":
            output.write_text(to_dot(g), encoding="utf-8")
        else:
            draw(g, output)
    except MtmcError as exc:
        fail(exc)
    except OSError as exc:
        fail(f"{output}: cannot write: {exc.strerror}")
    typer.echo(f"wrote {output}")


@app.command("export")
def export_cmd(
    file: Path = FILE,
    to: str = typer.Option("assertions", "--to", help="assertions, toml or dot."),
) -> None:
    """Print FILE as the seed's assertion database, as TOML or as DOT."""
    from mtmc.graph.assertions import dumps_assertions
    from mtmc.graph.draw import to_dot
    from mtmc.graph.toml_format import dumps

    writers = {"assertions": dumps_assertions, "toml": dumps, "dot": to_dot}
    if to not in writers:
        fail(f"--to: expected one of {', '.join(writers)}, got {to!r}")
    try:
        typer.echo(writers[to](_read(file)), nl=False)
    except MtmcError as exc:
        fail(exc)


@app.command("run")
def run_cmd(
    file: Path = FILE,
    trials: int = typer.Option(100_000, "--trials", "-n", help="Number of Monte Carlo trials M."),
    seed: int | None = typer.Option(None, "--seed", help="Seed (default: fresh, printed)."),
    place: list[str] | None = typer.Option(None, "--place", "-p", help="Only these places."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Run FILE by Monte Carlo and print each place's estimate and standard uncertainty."""
    from mtmc.graph.run import run_graph

    try:
        res = run_graph(_read(file), trials, seed, outputs=place or None)
    except MtmcError as exc:
        fail(exc)
    if as_json:
        print_json(res.to_dict())
        return
    typer.echo(f"trials {res.trials}  seed {res.seed}  (lengths mm, angles rad)")
    for name, s in res.places.items():
        d = s.to_dict()
        if "estimate" in d:
            typer.echo(f"{name:>14} {s.type:<7} estimate {_fmt(d['estimate'])}  u {_fmt(d['u'])}")
        else:
            typer.echo(f"{name:>14} {s.type:<7}")
            for part, v in d.items():
                if part != "type":
                    typer.echo(
                        f"{'':>14} {part:<11} estimate {_fmt(v['estimate'])}  u {_fmt(v['u'])}"
                    )


def _fmt(v: object) -> str:
    import numpy as np

    a = np.asarray(v, dtype=float)
    if a.ndim == 0:
        return f"{float(a):.6g}"
    return "[" + ", ".join(f"{x:.6g}" for x in a.ravel()) + "]"


@app.command("sweep")
def sweep_cmd(
    file: Path = FILE,
    vary: list[str] = typer.Option(
        ..., "--vary", help="KEY=LOW:HIGH:N, e.g. probe.u_probe=0.001:0.005:5 (repeatable)."
    ),
    output: str = typer.Option(..., "--output", help="The scalar output place."),
    trials: int = typer.Option(1000, "--trials", "-n", help="Trials per grid point."),
    seed: int | None = typer.Option(None, "--seed", help="Seed of every grid point."),
    csv: Path | None = typer.Option(None, "--csv", help="Write the grid as CSV here."),
    no_intercept: bool = typer.Option(False, "--no-intercept", help="Fit without c0."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Run FILE on a grid and fit the surrogate U^2 = c0 + sum c_i sigma_i^2 (seed 000 eq. 31)."""
    from mtmc.graph.sweep import parse_range, sweep

    try:
        ranges = {}
        for item in vary:
            key, eq, rng = item.partition("=")
            if not eq:
                fail(f"--vary: expected KEY=LOW:HIGH:N, got {item!r}")
            ranges[key.strip()] = parse_range(rng, field=key.strip())
        res = sweep(_read(file), ranges, output, trials=trials, seed=seed)
        fit = res.fit(intercept=not no_intercept)
    except MtmcError as exc:
        fail(exc)
    text = res.to_csv(fit)
    if csv is not None:
        csv.write_text(text, encoding="utf-8")
    if as_json:
        print_json(
            {
                "trials": res.trials,
                "seed": res.seed,
                "output": output,
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
