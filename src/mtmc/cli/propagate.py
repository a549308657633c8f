"""``mtmc propagate``: propagate distributions through an expression.

Parses the expression and the ``-i NAME=DIST`` options, calls
:func:`mtmc.monte_carlo` (and, with ``--gum``, :func:`mtmc.gum` and
:func:`mtmc.validate`), and prints a table or one JSON object. No maths here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
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
    progress_bar,
    quiet_numpy,
)
from mtmc.errors import InputError, MtmcError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    from mtmc.uncertainty.distributions import Distribution
    from mtmc.uncertainty.expression import Expression


def parse_inputs(expr: Expression, specs: list[str]) -> dict[str, Distribution]:
    """Turn ``NAME=DIST`` strings into distributions, checked against the expression.

    Parameters
    ----------
    expr : Expression
        The model; every one of its variables needs exactly one input.
    specs : list of str
        ``NAME=DIST`` texts, e.g. ``"x=normal(0, 1)"``.

    Returns
    -------
    dict
        Name to distribution, in the order of ``expr.names``.

    Raises
    ------
    InputError
        On a spec without ``=``, a name given twice, a name not in the expression, or a
        variable of the expression without an input (each named in the message).
    DistributionError
        On a distribution that does not parse (the message names the input).
    """
    from mtmc.uncertainty.distributions import parse_distribution

    dists: dict[str, Distribution] = {}
    for spec in specs:
        name, sep, text = spec.partition("=")
        name = name.strip()
        if not sep or not name:
            raise InputError(
                f"expected NAME=DISTRIBUTION, e.g. x=normal(0, 1), got {spec!r}", field="-i"
            )
        if name in dists:
            raise InputError(f"input {name} given more than once", field=name)
        try:
            dists[name] = parse_distribution(text.strip(), field=name)
        except MtmcError as exc:  # "line 1" would point at no file: name the option instead
            where = f" (column {exc.column})" if exc.column is not None else ""
            raise type(exc)(exc.message + where, field=f"-i {name}") from None
    extra = [n for n in dists if n not in expr.names]
    if extra:
        raise InputError(
            f"input(s) {', '.join(extra)} not in the expression {expr.text!r} "
            f"(its variables: {', '.join(expr.names) or 'none'})",
            field=extra[0],
        )
    missing = [n for n in expr.names if n not in dists]
    if missing:
        raise InputError(
            f"variable(s) {', '.join(missing)} of {expr.text!r} have no -i NAME=DISTRIBUTION",
            field=missing[0],
        )
    return {n: dists[n] for n in expr.names}


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def propagate(
    expr: str = typer.Argument(..., help="Model expression, e.g. 'a * b + c'."),
    inputs: list[str] = typer.Option(
        [], "-i", "--input", help="An input as NAME=DISTRIBUTION, e.g. x='normal(0, 1)'."
    ),
    trials: int = typer.Option(10**6, "--trials", "-n", help="Number of Monte Carlo trials."),
    seed: int | None = typer.Option(None, "--seed", help="Seed (recorded in the output)."),
    adaptive: bool = typer.Option(False, "--adaptive", help="Adaptive MC (JCGM 101 §7.9)."),
    with_gum: bool = typer.Option(False, "--gum", help="Also the GUM and §8 validation."),
    p: float = typer.Option(0.95, "--p", help="Coverage probability."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    nan: str = NAN_POLICY_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
) -> None:
    """Propagate input distributions through EXPR by Monte Carlo (JCGM 101)."""
    from mtmc.uncertainty.expression import expression
    from mtmc.uncertainty.gum import gum, validate
    from mtmc.uncertainty.montecarlo import monte_carlo

    check_trials(trials)
    try:
        model = expression(expr)
        dists = parse_inputs(model, inputs)
        with progress_bar("Monte Carlo", progress) as bar, quiet_numpy():
            mc = monte_carlo(
                model,
                dists,
                trials=None if adaptive else trials,
                seed=seed,
                adaptive=adaptive,
                p=p,
                progress=bar,
                nan_policy=nan_policy(nan),
                **parallel_options(workers, executor, scheduler),
            )
        if mc.dim != 0:
            raise InputError(
                f"the expression gives an output of {mc.dim} components; propagate "
                "reports scalar outputs",
                field="EXPR",
            )
        shortest = mc.coverage_interval(p, kind="shortest")
        symmetric = mc.coverage_interval(p, kind="symmetric")
        out: dict[str, Any] = {
            "estimate": mc.estimate,
            "u": mc.u,
            "p": p,
            "shortest": list(shortest),
            "symmetric": list(symmetric),
            "trials": mc.trials,
            "omitted": mc.omitted,
            "seed": mc.seed,
        }
        if with_gum:
            with quiet_numpy():
                g = gum(model, dists, p=p)
            v = validate(g, mc, p=p)
            out["gum"] = {
                "estimate": g.estimate,
                "u": g.u,
                "k": g.coverage_factor(),
                "interval": list(g.coverage_interval()),
            }
            out["validation"] = {
                "d_low": v.d_low,
                "d_high": v.d_high,
                "delta": v.delta,
                "passed": v.passed,
            }
    except (MtmcError, ValueError) as exc:
        fail(engine_message(exc))
    if as_json:
        print_json(out)
        return
    console = Console()
    table = Table(title=f"Monte Carlo (JCGM 101): {model.text}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("estimate y", _fmt(out["estimate"]))
    table.add_row("standard uncertainty u(y)", _fmt(out["u"]))
    table.add_row(f"shortest {100 * p:g} % interval", f"[{_fmt(shortest[0])}, {_fmt(shortest[1])}]")
    table.add_row(
        f"symmetric {100 * p:g} % interval", f"[{_fmt(symmetric[0])}, {_fmt(symmetric[1])}]"
    )
    table.add_row("trials", str(out["trials"]))
    if out["omitted"]:
        table.add_row("trials left out (NaN or inf)", str(out["omitted"]))
    table.add_row("seed", str(out["seed"]))
    console.print(table)
    if with_gum:
        gt = Table(title="GUM (JCGM 100) and JCGM 101 §8 validation")
        gt.add_column("quantity")
        gt.add_column("value", justify="right")
        g_out, v_out = out["gum"], out["validation"]
        gt.add_row("estimate y", _fmt(g_out["estimate"]))
        gt.add_row("standard uncertainty u(y)", _fmt(g_out["u"]))
        gt.add_row("coverage factor k", _fmt(g_out["k"]))
        gt.add_row(
            "interval y ± k u", f"[{_fmt(g_out['interval'][0])}, {_fmt(g_out['interval'][1])}]"
        )
        gt.add_row("d_low", _fmt(v_out["d_low"]))
        gt.add_row("d_high", _fmt(v_out["d_high"]))
        gt.add_row("numerical tolerance δ", _fmt(v_out["delta"]))
        gt.add_row("GUM validated", "yes" if v_out["passed"] else "no")
        console.print(gt)
