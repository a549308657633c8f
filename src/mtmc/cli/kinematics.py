"""``mtmc kinematics``: subcommands."""

from __future__ import annotations

import typer

app = typer.Typer(help="kinematics subcommands.", no_args_is_help=True)
