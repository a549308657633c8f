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
    JSON_OPTION,
    NAN_POLICY_OPTION,
    PROGRESS_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    check_trials,
    engine_message,
    fail,
    gum_lines,
    input_specs,
    nan_policy,
    parallel_options,
    print_json,
    progress_bar,
    quiet_numpy,
    seed_option,
    validated_text,
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
        On a spec without ``=``, a name given twice, a name not in the expression, a
        variable of the expression without an input (each named in the message), or a
        component ``x[i]`` out of range of the input ``x``.
    DistributionError
        On a distribution that does not parse (the message names the input).
    """
    from mtmc.uncertainty.expression import check_components

    dists = input_specs(specs)
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
    check_components(expr, {n: d.dim for n, d in dists.items()})  # x[i] of a k-variate x
    return {n: dists[n] for n in expr.names}


def parse_correlation(specs: list[str], copula: str) -> tuple[dict[tuple[str, str], float], Any]:
    """Turn ``--correlate A,B,R`` and ``--copula`` texts into engine arguments.

    Parameters
    ----------
    specs : list of str
        ``A,B,R`` texts, e.g. ``"e1,e2,0.9"``.
    copula : str
        ``"gaussian"`` or ``"t:DOF"``, e.g. ``"t:4"``.

    Returns
    -------
    dict, Copula
        The pairs ``{(A, B): R}`` (empty without ``--correlate``) and the copula; the
        engine checks the names and the matrix.

    Raises
    ------
    InputError
        On a spec that is not ``A,B,R`` with a number ``R``, or a copula text that is
        neither form (naming the option).
    """
    from mtmc.uncertainty.copula import Copula

    pairs: dict[tuple[str, str], float] = {}
    for spec in specs:
        parts = [t.strip() for t in spec.split(",")]
        try:
            if len(parts) != 3 or not parts[0] or not parts[1]:
                raise ValueError
            pairs[(parts[0], parts[1])] = float(parts[2])
        except ValueError:
            raise InputError(
                f"expected A,B,R (two input names and a coefficient), got {spec!r}",
                field="--correlate",
            ) from None
    kind, _, dof = copula.partition(":")
    if kind == "gaussian" and not dof:
        return pairs, Copula()
    try:
        if kind != "t":
            raise ValueError
        value = float(dof)
    except ValueError:
        raise InputError(
            f"expected 'gaussian' or 't:DOF' (e.g. t:4), got {copula!r}", field="--copula"
        ) from None
    return pairs, Copula("t", value)


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _sensitivity(
    model: Expression,
    dists: dict[str, Distribution],
    trials: int,
    seed: Any,
    u_mc: float,
    p: float,
    workers: int,
    executor: str,
    scheduler: str | None,
) -> dict[str, Any]:
    """The ``sensitivity`` record of ``--sensitivity`` (as a study's ``[sensitivity]``)."""
    from mtmc.study.sensitivity import SensitivitySettings, sensitivity_record
    from mtmc.uncertainty.gum import gum
    from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE

    if trials < 2 * SEED_BLOCK_SIZE or trials % SEED_BLOCK_SIZE:
        raise InputError(
            f"expected a multiple of {SEED_BLOCK_SIZE}, at least {2 * SEED_BLOCK_SIZE}, "
            f"got {trials}",
            field="--sensitivity-trials",
        )
    with quiet_numpy():
        return sensitivity_record(
            model,
            dists,
            SensitivitySettings(trials=trials),
            seed=int(seed),
            output="y",
            unit="1",
            u_mc=u_mc,
            gum_result=gum(model, dists, p=p),
            parallel=parallel_options(workers, executor, scheduler),
        )


def _print_sensitivity(console: Console, rec: dict[str, Any]) -> None:
    """The Monte Carlo budget and Sobol indices as a table, and what they say."""
    st = Table(title="Monte Carlo budget (JCGM 101 Annex B) and Sobol indices, ± standard error")
    for col in ("input", "|c| u(x), GUM", "u_i(y), alone", "S_i", "S_Ti"):
        st.add_column(col, justify="left" if col == "input" else "right")
    for b, s in zip(rec["budget"], rec["sobol"]["indices"], strict=True):
        st.add_row(
            b["name"] + ("" if b["linear"] is not False else " (not linear)"),
            _fmt(b["gum_contribution"]),
            f"{_fmt(b['u'])} ± {b['u_se']:.1g}",
            f"{s['first']:.4f} ± {s['first_se']:.1g}",
            f"{s['total']:.4f} ± {s['total_se']:.1g}",
        )
    sob = rec["sobol"]
    st.add_row("sum", "", "", f"{sob['first_sum']:.4f} ± {sob['first_sum_se']:.1g}", "")
    console.print(st)
    if rec["interacting"]:
        console.print(f"interactions: {', '.join(rec['interacting'])} (Σ S_i < 1)")
    if rec["nonlinear"]:
        console.print(f"not linear over the PDF: {', '.join(rec['nonlinear'])}")


def propagate(
    expr: str = typer.Argument(
        ...,
        help="Model expression, e.g. 'a * b + c', or several outputs of the same inputs, "
        "'y1 = x[0] + x[1]; y2 = x[0] * a' (JCGM 102).",
    ),
    inputs: list[str] = typer.Option(
        [], "-i", "--input", help="An input as NAME=DISTRIBUTION, e.g. x='normal(0, 1)'."
    ),
    trials: int = typer.Option(10**6, "--trials", "-n", help="Number of Monte Carlo trials."),
    seed: int | None = seed_option("fresh entropy"),
    adaptive: bool = typer.Option(False, "--adaptive", help="Adaptive MC (JCGM 101 §7.9)."),
    with_gum: bool = typer.Option(False, "--gum", help="Also the GUM and §8 validation."),
    sensitivity: bool = typer.Option(
        False,
        "--sensitivity",
        help="Also the Monte Carlo budget and Sobol indices beside the GUM's (JCGM 101 Annex B).",
    ),
    sensitivity_trials: int = typer.Option(
        8 * 16384,
        "--sensitivity-trials",
        help="Rows of each Sobol matrix: a multiple of 16384, at least 32768.",
    ),
    correlate: list[str] = typer.Option(
        [],
        "--correlate",
        help="Correlate two scalar inputs as A,B,R (repeatable): the copula's correlation "
        "in the Monte Carlo, r of JCGM 100 eq. (13) in the GUM.",
    ),
    copula: str = typer.Option(
        "gaussian", "--copula", help="The copula of --correlate: 'gaussian' or 't:DOF'."
    ),
    p: float = typer.Option(
        0.95, "--coverage-probability", "-p", help="Coverage probability p, 0 < p < 1."
    ),
    as_json: bool = JSON_OPTION,
    nan: str = NAN_POLICY_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
) -> None:
    """Propagate input distributions through EXPR by Monte Carlo (JCGM 101)."""
    from mtmc.cli.outputs import is_several, propagate_outputs
    from mtmc.uncertainty.expression import expression
    from mtmc.uncertainty.gum import gum
    from mtmc.uncertainty.montecarlo import monte_carlo

    check_trials(trials)
    if is_several(expr):  # NAME = MODEL; NAME = MODEL: several outputs (JCGM 102)
        if sensitivity or correlate:
            fail("--sensitivity and --correlate apply to one model, not to several outputs")
        propagate_outputs(
            expr,
            inputs,
            trials=trials,
            seed=seed,
            adaptive=adaptive,
            with_gum=with_gum,
            p=p,
            as_json=as_json,
            nan=nan,
            workers=workers,
            executor=executor,
            scheduler=scheduler,
            progress=progress,
        )
        return
    try:
        model = expression(expr)
        dists = parse_inputs(model, inputs)
        corr, cop = parse_correlation(correlate, copula)
        if corr and sensitivity:
            raise InputError(
                "--sensitivity varies each input alone, which assumes independent inputs",
                field="--correlate",
            )
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
                **({"correlation": corr, "copula": cop} if corr else {}),
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
        if corr:
            out["correlation"] = {
                "copula": cop.to_dict(),
                "pairs": [[a, b, r] for (a, b), r in corr.items()],
            }
        if with_gum:
            with quiet_numpy():
                g = gum(model, dists, p=p, correlation=corr or None)
            out["gum"], out["validation"] = gum_lines(g, mc, p)
        if sensitivity:
            out["sensitivity"] = _sensitivity(
                model, dists, sensitivity_trials, mc.seed, mc.u, p, workers, executor, scheduler
            )
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
    if corr:
        pairs = ", ".join(f"r({a}, {b}) = {r:g}" for (a, b), r in corr.items())
        table.add_row(f"correlation ({cop} copula)", pairs)
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
        passed = v_out["passed"]
        gt.add_row("GUM validated", validated_text(passed))
        console.print(gt)
    if sensitivity:
        _print_sensitivity(console, out["sensitivity"])
