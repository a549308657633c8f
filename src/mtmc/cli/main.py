"""The ``mtmc`` command: parses arguments, calls the library, prints. No maths here.

Exit status: 0 on success; 2 on bad input, whether the subcommand found it (through
:func:`mtmc.cli.common.fail`, one line ``mtmc: error: ...`` on stderr) or the argument
parser did (one line naming the command, and ``--help`` for more); 130 on Ctrl-C; 143 on
SIGTERM (the same clean ending: one line, worker processes stopped, no file half-written).
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from types import FrameType

import typer

from mtmc._version import __version__
from mtmc.cli import artefact, circle, graph, kinematics, positioning, propagate, run, verify

app = typer.Typer(
    rich_markup_mode=None,
    name="mtmc",
    help="Machine-tool Monte Carlo: measurement uncertainty by JCGM 101 with the GUM beside it.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command("propagate")(propagate.propagate)
app.command("run")(run.run_cmd)
app.command("report")(run.report_cmd)
app.command("demo")(run.demo_cmd)
app.add_typer(graph.app, name="graph")
app.add_typer(kinematics.app, name="kinematics")
app.add_typer(verify.app, name="verify")
app.add_typer(artefact.app, name="artefact")
app.add_typer(positioning.app, name="positioning")
app.add_typer(circle.app, name="circle")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"mtmc {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(  # noqa: ARG001 - read by its eager callback
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Machine-tool Monte Carlo."""
    from mtmc.uncertainty.heap import keep_heap

    keep_heap()  # a command runs: its process is its own, and its runs reuse freed heap


def _usage_error(exc: Exception) -> int | None:
    """Print an argument-parser error (a click ``UsageError``) and return its status.

    Returns None for anything that is not such an error. The check is by behaviour (an
    ``exit_code`` and a ``format_message``), so it holds whether Typer vendors click or
    depends on it.
    """
    code = getattr(exc, "exit_code", None)
    fmt = getattr(exc, "format_message", None)
    if not isinstance(code, int) or not callable(fmt):
        return None
    ctx = getattr(exc, "ctx", None)
    if type(exc).__name__ == "NoArgsIsHelpError":  # a group called alone: its help
        typer.echo(str(fmt()), err=True)
        return code
    msg = " ".join(str(fmt()).split())
    hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
    typer.echo(f"mtmc: error: {msg}{hint}", err=True)
    return code


class _Terminated:
    """Whether SIGTERM ended the command (its handler raises ``KeyboardInterrupt``)."""

    seen = False


def _on_sigterm(_signum: int, _frame: FrameType | None) -> None:
    _Terminated.seen = True
    raise KeyboardInterrupt


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """Let SIGTERM unwind the command as Ctrl-C does (pools shut, temporaries removed)."""
    _Terminated.seen = False
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupted() -> int:
    if _Terminated.seen:
        typer.echo("mtmc: terminated", err=True)
        return 143
    typer.echo("mtmc: interrupted", err=True)
    return 130


def main(argv: list[str] | None = None) -> int:
    """Run the CLI with ``argv`` and return the exit status (SIGTERM handled as Ctrl-C).

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        As :func:`_main`; 143 after SIGTERM (one line ``mtmc: terminated``).
    """
    with _sigterm_as_interrupt():
        return _main(argv)


def _main(argv: list[str] | None = None) -> int:
    """Run the CLI with ``argv`` and return the exit status.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, the status given to :func:`mtmc.cli.common.fail` (2) on bad input,
        2 on a usage error, 1 on an abort, 130 on Ctrl-C (one line ``mtmc: interrupted``;
        no file is left half-written).
    """
    try:
        # standalone_mode=False: the parser raises instead of exiting, and a typer.Exit
        # raised by a subcommand (cli.common.fail) comes back as its exit code.
        args = sys.argv[1:] if argv is None else list(argv)
        # NumPy's floating-point warnings not shown: a NaN or an overflow is reported once,
        # as one line, by the engine's check of the model values (a filter, not
        # numpy.errstate: `mtmc --help` imports no NumPy)
        with warnings.catch_warnings():
            warnings.filterwarnings(
                "ignore",
                message=r"(overflow|invalid value|divide by zero|underflow) encountered",
                category=RuntimeWarning,
            )
            # printed as one line by the subcommands (Plan.warnings), not with source lines
            from mtmc.errors import ConditioningWarning

            warnings.simplefilter("ignore", ConditioningWarning)
            rv = app(
                args=args, prog_name="mtmc", standalone_mode=False, obj={"argv": ["mtmc", *args]}
            )
    except typer.Exit as exc:
        return int(exc.exit_code)
    except typer.Abort:
        typer.echo("mtmc: aborted", err=True)
        return 1
    except KeyboardInterrupt:
        # Every file is written atomically (mtmc.io): an interrupted run leaves none half-way.
        return _interrupted()
    except SystemExit as exc:
        code = exc.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except Exception as exc:
        code = _usage_error(exc)
        if code is None:
            raise
        return code
    if rv == 130:  # Typer turns Ctrl-C inside a subcommand into this status
        return _interrupted()
    return rv if isinstance(rv, int) else 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
