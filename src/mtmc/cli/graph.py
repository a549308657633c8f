"""``mtmc graph``: subcommands."""

from __future__ import annotations

import typer

app = typer.Typer(help="graph subcommands.", no_args_is_help=True)
