"""``mtmc kinematics``: library, machine summary, equation of motion, chain drawing.

A thin shell over :mod:`mtmc.kinematics`. ``SPEC`` is a library name (``table-table``) or
a topology string (``wCBXfYZt``, ``XFYZ``). Errors print one line and exit with status 2;
the drawing is written atomically (:mod:`mtmc.io`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from mtmc.cli.common import fail, print_json, write_output
from mtmc.errors import MtmcError, TopologyError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    from mtmc.kinematics.machine import Machine

app = typer.Typer(
    rich_markup_mode=None,
    help="Machine kinematics with ISO 230 errors: library, chains, equations of motion.",
    no_args_is_help=True,
)

SPEC = typer.Argument(
    ..., help="A library name (see `list`) or a topology string (wCBXfYZt, XFYZ)."
)


def _machine(spec: str) -> Machine:
    from mtmc.kinematics import library_names
    from mtmc.kinematics.library import library_machine
    from mtmc.kinematics.machine import Machine

    if spec.strip().lower() in library_names():
        return library_machine(spec)
    try:
        return Machine.from_topology(spec)
    except TopologyError as exc:
        raise TopologyError(
            f"{exc.message}; nor is it a library name ({', '.join(library_names())})",
            field=exc.field,
        ) from exc


@app.command("list")
def list_cmd(as_json: bool = typer.Option(False, "--json", help="Print one JSON object.")) -> None:
    """List the machine configurations of the library."""
    from mtmc.kinematics import library_entries

    entries = library_entries()
    if as_json:
        print_json(
            {
                e.name: {
                    "topology": str(e.machine.topology),
                    "description": e.description,
                    "source": e.source,
                }
                for e in entries
            }
        )
        return
    width = max(len(e.name) for e in entries)
    for e in entries:
        typer.echo(f"{e.name:<{width}}  {e.machine.topology!s:<10}  {e.description}")


@app.command("show")
def show_cmd(
    spec: str = SPEC,
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Show the axes, the chain and the error names of a machine."""
    try:
        m = _machine(spec)
    except MtmcError as exc:
        fail(exc)
    topo = m.topology
    info = {
        "name": m.name,
        "topology": str(topo),
        "aguado": topo.aguado,
        "axes": list(m.axes),
        "part_axes": list(topo.part_axes),
        "tool_axes": list(topo.tool_axes),
        "tool": m.tool,
        "workpiece": m.workpiece,
        "errors": list(m.error_names),
    }
    if as_json:
        print_json(info)
        return
    typer.echo(f"machine {m.name or spec}: {topo} ({topo.aguado})")
    typer.echo(f"axes (column order of q): {' '.join(m.axes)}")
    chain = " -> ".join(["workpiece", *topo.part_axes, "frame", *topo.tool_axes, "tool"])
    typer.echo(f"chain: {chain}")
    for ax in topo.chain:
        kind = "linear" if ax in topo.linear_axes else "rotary"
        trav = m.travel.get(ax)
        if not trav:
            extra = ""
        elif kind == "linear":
            extra = f", travel {trav[0]:g} .. {trav[1]:g} mm"
        else:  # rad inside, shown in degrees as library.toml gives them
            extra = f", travel {math.degrees(trav[0]):g} .. {math.degrees(trav[1]):g} deg"
        typer.echo(f"  {ax}: {kind}, moves the {topo.side(ax)}{extra}")
    typer.echo(f"tool point: {m.tool.tolist()} mm; workpiece origin: {m.workpiece.tolist()} mm")
    typer.echo(f"errors ({len(m.error_names)}): {' '.join(m.error_names)}")


@app.command("equation")
def equation_cmd(
    spec: str = SPEC,
    latex: bool = typer.Option(False, "--latex", help="Print LaTeX instead of text."),
    full: bool = typer.Option(
        False, "--full", help="The full small-angle product (default: first order in the errors)."
    ),
    errors: list[str] | None = typer.Option(
        None, "--error", "-e", help="Keep only these errors (repeat the option)."
    ),
) -> None:
    """Write out the equation of motion of a machine (Aguado et al. 2016, section 4.1)."""
    from mtmc.kinematics import equation_of_motion

    try:
        m = _machine(spec)
        eq = equation_of_motion(m, errors=errors or None, first_order=not full)
    except MtmcError as exc:
        if errors and exc.field in errors:  # a bad name given to --error: name the option
            fail(f"--error: {exc.message}")
        fail(exc)
    typer.echo(eq.latex() if latex else eq.text())


@app.command("draw")
def draw_cmd(
    spec: str = SPEC,
    output: Path = typer.Option(..., "-o", "--output", help="Output SVG file (.svg)."),
) -> None:
    """Draw the kinematic chain of a machine as SVG."""
    from mtmc.kinematics.draw import draw_chain

    if output.suffix.lower() != ".svg":
        fail(f"{output}: the chain is drawn as SVG; expected a file ending in .svg")
    try:
        m = _machine(spec)
    except MtmcError as exc:
        fail(exc)
    write_output(output, draw_chain(m))
    typer.echo(f"wrote {output}")
