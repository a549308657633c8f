"""``mtmc propagate``: propagate distributions through an expression.

Parses the expression and the ``-i NAME=DIST`` options into a ``propagate`` study
(:func:`study_text`), runs it through the study layer as ``mtmc run`` runs a study file
(:func:`mtmc.cli.run.run_study`: the Monte Carlo, the GUM, the JCGM 101 §8 validation and,
asked for, the sensitivity of :mod:`mtmc.study.propagate`), and prints a table or one JSON
object; with ``-o`` the result folder too. No maths here.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer
from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    EXECUTOR_OPTION,
    JSON_OPTION,
    NAN_POLICY_OPTION,
    PLOTS_OPTION,
    PROGRESS_OPTION,
    QUIET_OPTION,
    RESULT_OPTION,
    SCHEDULER_OPTION,
    WORKERS_OPTION,
    check_trials,
    engine_message,
    fail,
    input_specs,
    input_texts,
    nan_policy,
    parallel_options,
    plots_value,
    print_json,
    progress_flag,
    quiet_numpy,
    seed_option,
    validated_text,
)
from mtmc.cli.run import command_line, print_outcome, run_study
from mtmc.cli.run_options import ADAPTIVE_OPTION
from mtmc.errors import InputError, MtmcError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    from mtmc.uncertainty.distributions import Distribution
    from mtmc.uncertainty.formula import Expression


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
    from mtmc.uncertainty.formula import check_components

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


#: The name of the study text that ``mtmc propagate`` builds from its options.
COMMAND_FILE = "mtmc propagate"

#: A study's field, as the option of ``mtmc propagate`` that gave it.
_OPTION_OF_FIELD = (
    ("inputs.", "-i "),
    ("outputs", "EXPR"),
    ("model", "EXPR"),
    ("correlation", "--correlate"),
    ("sensitivity", "--sensitivity-trials"),
    ("run.trials", "--trials"),
    ("run.p", "--coverage-probability"),
    ("run.nan_policy", "--nan-policy"),
)


def option_error(exc: MtmcError) -> InputError:
    """An error of the study built from the options, naming the option instead of a line.

    The study text is the command's, not a file of the user's: its line numbers point
    nowhere, so the error names the option (``-i a``, ``EXPR``, ``--correlate``) that
    gave the field.

    Examples
    --------
    >>> str(option_error(InputError("output a has the name of an input", file=COMMAND_FILE,
    ...                              line=9, field="outputs.a")))
    'field EXPR: output a has the name of an input'
    """
    field = exc.field
    for prefix, option in _OPTION_OF_FIELD:
        if field is not None and field.startswith(prefix):
            field = option + field[len(prefix) :] if option.endswith(" ") else option
            break
    return InputError(exc.message, field=field)


def _at_option(exc: MtmcError | ValueError) -> MtmcError | ValueError:
    """A run's error located in the command's study text, at its option instead."""
    if isinstance(exc, MtmcError) and exc.file == COMMAND_FILE:
        return option_error(exc)
    return exc


def study_text(
    outputs: dict[str, str] | str,
    inputs: dict[str, str],
    *,
    trials: int | None,
    seed: int | None,
    p: float,
    nan: str,
    correlation: list[tuple[str, str, float]] | None = None,
    copula: Any = None,
    sensitivity_trials: int | None = None,
) -> str:
    """The ``propagate`` study (``docs/study-format.md``) that the options describe.

    Parameters
    ----------
    outputs : str or dict of str to str
        The model text of one output ``y``, or the model texts of several named outputs
        (``[outputs]``).
    inputs : dict of str to str
        Each input's distribution text, as given to ``-i NAME=DISTRIBUTION``.
    trials : int or None
        ``[run] trials`` (None: ``"adaptive"``).
    seed : int or None
        ``[run] seed`` (None: fresh entropy, drawn by the run and recorded).
    p, nan
        ``[run] p`` and ``nan_policy``.
    correlation, copula : optional
        ``[correlation] pairs`` and ``copula`` (:class:`~mtmc.uncertainty.copula.Copula`).
    sensitivity_trials : int, optional
        ``[sensitivity] trials``.

    Returns
    -------
    str
        The TOML text, read by :func:`mtmc.study.loads_study` as a study file is and copied
        into the result folder, so that ``mtmc run`` repeats the run from it.
    """
    import tomlkit

    doc = tomlkit.document()
    doc["kind"] = "propagate"
    doc["title"] = "Propagation of distributions"
    if isinstance(outputs, str):
        doc["model"] = outputs
    else:
        doc["outputs"] = outputs
    doc["inputs"] = inputs
    run: dict[str, Any] = {"trials": "adaptive" if trials is None else trials, "p": p}
    if seed is not None:
        run["seed"] = seed
    run["nan_policy"] = nan
    doc["run"] = run
    if correlation:
        cop = copula.to_dict()
        doc["correlation"] = {
            "pairs": [list(pair) for pair in correlation],
            "copula": cop["kind"] if cop["kind"] == "gaussian" else cop,
        }
    if sensitivity_trials is not None:
        doc["sensitivity"] = {"trials": sensitivity_trials}
    return tomlkit.dumps(doc)


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
    ctx: typer.Context,
    expr: str = typer.Argument(
        ...,
        help="Model expression, e.g. 'a * b + c', or several outputs of the same inputs, "
        "'y1 = x[0] + x[1]; y2 = x[0] * a' (JCGM 102).",
    ),
    inputs: list[str] = typer.Option(
        [], "-i", "--input", help="An input as NAME=DISTRIBUTION, e.g. x='normal(0, 1)'."
    ),
    trials: int | None = typer.Option(
        None,
        "--trials",
        "-n",
        min=2,
        help="Monte Carlo trials (default: 1000000).",
        show_default=False,
    ),
    seed: int | None = seed_option("fresh entropy"),
    adaptive: bool = ADAPTIVE_OPTION,
    with_gum: bool = typer.Option(False, "--gum", help="Also print the GUM and §8 validation."),
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
    outdir: Path | None = RESULT_OPTION,
    as_json: bool = JSON_OPTION,
    quiet: bool = QUIET_OPTION,
    nan: str = NAN_POLICY_OPTION,
    workers: int = WORKERS_OPTION,
    executor: str = EXECUTOR_OPTION,
    scheduler: str | None = SCHEDULER_OPTION,
    progress: bool | None = PROGRESS_OPTION,
    plots: str | None = PLOTS_OPTION,
) -> None:
    """Propagate input distributions through EXPR by Monte Carlo (JCGM 101).

    The options make a propagate study (docs/study-format.md), run as mtmc run runs a
    study file; with -o its result folder holds that study file and the report.
    """
    from mtmc.cli.outputs import (
        check_inputs,
        is_several,
        parse_outputs,
        print_outputs,
    )
    from mtmc.study import loads_study
    from mtmc.uncertainty.formula import expression

    plotted = plots_value(plots)
    check_trials(trials, None if adaptive else p)
    if adaptive and trials is not None:
        fail("--adaptive chooses the number of trials itself (JCGM 101 §7.9); not with --trials")
    several = is_several(expr)  # NAME = MODEL; NAME = MODEL: several outputs (JCGM 102)
    if several and (sensitivity or correlate):
        fail("--sensitivity and --correlate apply to one model, not to several outputs")
    try:
        if not 0.0 < p < 1.0:
            raise InputError(f"expected 0 < p < 1, got {p}", field="--coverage-probability")
        texts = input_texts(inputs)
        models: dict[str, str] | str
        if several:
            outputs = parse_outputs(expr)
            check_inputs(outputs, inputs)
            models = {o.name: o.model.text for o in outputs}
        else:
            model = expression(expr)
            parse_inputs(model, inputs)
            texts = {n: texts[n] for n in model.names}
            models = model.text
        pairs, cop = parse_correlation(correlate, copula)
        if pairs and sensitivity:
            raise InputError(
                "--sensitivity varies each input alone, which assumes independent inputs",
                field="--correlate",
            )
        if sensitivity:
            check_sensitivity_trials(sensitivity_trials)
        text = study_text(
            models,
            texts,
            trials=None if adaptive else (10**6 if trials is None else trials),
            seed=seed,
            p=p,
            nan=nan_policy(nan),
            correlation=[(a, b, r) for (a, b), r in pairs.items()],
            copula=cop,
            sensitivity_trials=sensitivity_trials if sensitivity else None,
        )
        try:
            study = loads_study(text, file=COMMAND_FILE)
        except MtmcError as exc:
            raise option_error(exc) from None
        with quiet_numpy():
            result = run_study(
                study,
                outdir,
                label="propagate",
                progress=progress_flag(progress, quiet),
                argv=command_line(ctx),
                parallel=parallel_options(workers, executor, scheduler),
                plotted=plotted,
            )
    except (MtmcError, ValueError) as exc:
        fail(engine_message(_at_option(exc)))
    except OSError as exc:
        fail(f"{outdir}: cannot write: {exc.strerror or exc}")
    if several:
        print_outputs(result, outdir, with_gum=with_gum, as_json=as_json, quiet=quiet)
        return
    out = one_output(result, outdir, with_gum)
    if as_json:
        print_json(out)
        return
    if not quiet:
        _print(out, model.text)
    print_outcome(result, outdir, seed_line=True)


def check_sensitivity_trials(trials: int) -> None:
    """Refuse ``--sensitivity-trials`` that are not whole seed blocks (naming the option)."""
    from mtmc.uncertainty.sampling import SEED_BLOCK_SIZE

    if trials < 2 * SEED_BLOCK_SIZE or trials % SEED_BLOCK_SIZE:
        raise InputError(
            f"expected a multiple of {SEED_BLOCK_SIZE}, at least {2 * SEED_BLOCK_SIZE}, "
            f"got {trials}",
            field="--sensitivity-trials",
        )


def one_output(result: Any, outdir: Path | None, with_gum: bool) -> dict[str, Any]:
    """The ``--json`` object of a propagate study of one output (``docs/cli.md``)."""
    from mtmc.cli.outputs import summary_record

    out = summary_record(result.quantities[0], with_gum)
    run = result.extra.get("run") or {}
    out |= {
        "trials": result.trials,
        "omitted": run.get("omitted", 0),
        "seed": result.seed,
        "run": result.extra.get("run"),
        "output": None if outdir is None else str(outdir),
    }
    for key in ("correlation", "sensitivity"):
        if key in result.extra:
            out[key] = result.extra[key]
    return out


def _print(out: dict[str, Any], text: str) -> None:
    """The tables of one output: U (k, p) first, u beside it; the GUM and budget if asked."""
    console = Console()
    p = out["p"]
    table = Table(title=f"Monte Carlo (JCGM 101): {text}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("estimate y", _fmt(out["estimate"]))
    k = "" if out["k"] is None else f"k = {out['k']:.3f}, "
    table.add_row(f"expanded uncertainty U ({k}p = {100 * p:g} %)", _fmt(out["U"]))
    table.add_row("standard uncertainty u(y)", _fmt(out["u"]))
    for kind in ("shortest", "symmetric"):
        lo, hi = out[kind]
        table.add_row(f"{kind} {100 * p:g} % interval", f"[{_fmt(lo)}, {_fmt(hi)}]")
    corr = out.get("correlation")
    if corr is not None:
        cop = corr["copula"]
        name = "gaussian" if cop["kind"] == "gaussian" else f"t (ν = {cop['dof']:g})"
        pairs = ", ".join(f"r({x['a']}, {x['b']}) = {x['r']:g}" for x in corr["pairs"])
        table.add_row(f"correlation ({name} copula)", pairs)
    console.print(table)
    if "gum" in out:
        gt = Table(title="GUM (JCGM 100) and JCGM 101 §8 validation")
        gt.add_column("quantity")
        gt.add_column("value", justify="right")
        g_out, v_out = out["gum"], out["validation"]
        gt.add_row("estimate y", _fmt(g_out["estimate"]))
        gt.add_row(f"expanded uncertainty U (k = {g_out['k']:.3f})", _fmt(g_out["U"]))
        gt.add_row("standard uncertainty u(y)", _fmt(g_out["u"]))
        gt.add_row(
            "interval y ± U", f"[{_fmt(g_out['interval'][0])}, {_fmt(g_out['interval'][1])}]"
        )
        gt.add_row("d_low", _fmt(v_out["d_low"]))
        gt.add_row("d_high", _fmt(v_out["d_high"]))
        gt.add_row("numerical tolerance δ", _fmt(v_out["delta"]))
        gt.add_row("GUM validated", validated_text(v_out["passed"]))
        console.print(gt)
    if "sensitivity" in out:
        _print_sensitivity(console, out["sensitivity"])
