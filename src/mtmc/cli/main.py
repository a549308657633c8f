"""The ``mtmc`` command: parses arguments, calls the library, prints. No maths here."""

from __future__ import annotations

import typer

from mtmc import __version__
from mtmc.cli import graph, kinematics, propagate

app = typer.Typer(
    name="mtmc",
    help="Machine-tool Monte Carlo: measurement uncertainty by JCGM 101 with the GUM beside it.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command("propagate")(propagate.propagate)
app.add_typer(graph.app, name="graph")
app.add_typer(kinematics.app, name="kinematics")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"mtmc {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Machine-tool Monte Carlo."""


def main(argv: list[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default: ``sys.argv[1:]``) and return the exit code."""
    try:
        # With standalone_mode=False click returns the exit code of typer.Exit/click.Exit.
        rv = app(args=argv, prog_name="mtmc", standalone_mode=False)
    except SystemExit as exc:  # pragma: no cover - typer/click exit paths
        return int(exc.code or 0)
    except typer.Exit as exc:
        return int(exc.exit_code)
    except Exception as exc:  # click usage errors
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show()
            return exc.exit_code
        if isinstance(exc, click.exceptions.Abort):
            return 1
        raise
    return rv if isinstance(rv, int) else 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
