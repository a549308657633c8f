"""``--adaptive`` and ``--nan-policy`` of the commands that run a study or a graph.

The options say the same as ``[run] trials = "adaptive"`` and ``[run] nan_policy`` of a
study file (``docs/study-format.md``); given on the command line they override the file.
The engine's advice on NaN or infinite model values names its Python keyword; a command
names the option the user can set instead (:func:`run_message`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import typer

__all__ = [
    "ADAPTIVE_OPTION",
    "RUN_NAN_POLICY_OPTION",
    "run_lines",
    "run_message",
]

#: ``--adaptive``: the number of trials chosen by the adaptive procedure of JCGM 101 §7.9.
ADAPTIVE_OPTION: Any = typer.Option(
    False,
    "--adaptive",
    help="Adaptive Monte Carlo (JCGM 101 §7.9): add blocks of trials until u, the estimate "
    "and the interval ends of every output are stable to ndig significant digits of u "
    "(a study's [run] ndig; 2 otherwise); not with --trials.",
)

#: ``--nan-policy`` of ``mtmc run``: no default, the study's ``[run] nan_policy`` holds.
RUN_NAN_POLICY_OPTION: Any = typer.Option(
    None,
    "--nan-policy",
    help="raise: stop at a model value that is NaN or infinite; omit: leave those trials "
    "out (their number is printed and kept in result.json). Default: the study's "
    "[run] nan_policy, else raise.",
    show_default=False,
)


def run_message(exc: BaseException) -> str:
    """The text of an error of ``mtmc run``, its advice in the terms of the command and file.

    The engine advises ``nan_policy='omit'`` (its keyword); ``mtmc run`` takes
    ``--nan-policy omit`` or ``nan_policy = "omit"`` in the study's ``[run]`` table.
    An option refused by a kind names the option of the command.

    Examples
    --------
    >>> from mtmc.errors import InputError
    >>> run_message(InputError("y is not finite; or nan_policy='omit' to leave them out"))
    'y is not finite; or --nan-policy omit (or [run] nan_policy = "omit") to leave them out'
    """
    from mtmc.errors import MtmcError

    text = str(exc)
    if isinstance(exc, MtmcError) and exc.file is None and exc.field in ("adaptive", "nan_policy"):
        text = text.replace(f"field {exc.field}:", f"--{exc.field.replace('_', '-')}:", 1)
    return text.replace("nan_policy='omit'", '--nan-policy omit (or [run] nan_policy = "omit")')


def run_lines(run: Mapping[str, Any] | None) -> list[str]:
    """The lines a command prints on how its Monte Carlo run went (``run`` of a result).

    Parameters
    ----------
    run : mapping or None
        :func:`mtmc.study.options.run_record` of the result (None: nothing to say).

    Returns
    -------
    list of str
        For an adaptive run, its trials, blocks, ``ndig`` and δ (JCGM 101 §7.9.4); where
        trials were left out, how many.

    Examples
    --------
    >>> run_lines({"adaptive": True, "trials": 30000, "blocks": 3, "ndig": 2,
    ...            "tolerance": 0.0005, "omitted": 2, "nan_policy": "omit"})
    ['adaptive Monte Carlo (JCGM 101 §7.9): 30000 trials in 3 blocks, u stable to ndig = 2 \
significant digits (δ = 0.0005)', '2 of 30000 trials left out: a model value was NaN or infinite']
    """
    if not run:
        return []
    lines = []
    if run.get("adaptive"):
        tol = run.get("tolerance")
        delta = "" if tol is None else f" (δ = {tol:.3g})"
        lines.append(
            f"adaptive Monte Carlo (JCGM 101 §7.9): {run['trials']} trials in {run['blocks']} "
            f"blocks, u stable to ndig = {run['ndig']} significant digits{delta}"
        )
    if run.get("omitted"):
        lines.append(
            f"{run['omitted']} of {run['trials']} trials left out: a model value was NaN or "
            "infinite"
        )
    return lines
