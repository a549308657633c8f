"""``mtmc propagate``: propagate distributions through an expression."""

from __future__ import annotations

import typer


def propagate(expr: str = typer.Argument(..., help="Model expression.")) -> None:
    """Propagate input distributions through EXPR by Monte Carlo."""
    raise typer.Exit(1)
