"""Options and helpers shared by the subcommands: error printing and JSON output."""

from __future__ import annotations

import json
import sys
from typing import Any, NoReturn

import numpy as np
import typer

from mtmc.errors import MtmcError


def fail(exc: BaseException | str, code: int = 2) -> NoReturn:
    """Print a one-line error on stderr and exit with ``code``."""
    msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    typer.echo(f"mtmc: error: {msg}", err=True)
    raise typer.Exit(code)


def to_jsonable(obj: Any) -> Any:
    """Convert NumPy scalars and arrays (nested in dicts/lists) to plain JSON types."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def print_json(obj: Any) -> None:
    """Write exactly one JSON object on stdout."""
    sys.stdout.write(json.dumps(to_jsonable(obj), allow_nan=True) + "\n")


__all__ = ["MtmcError", "fail", "print_json", "to_jsonable"]
