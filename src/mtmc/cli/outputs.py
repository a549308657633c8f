"""``mtmc propagate "y1 = ...; y2 = ..."``: several outputs of the same inputs (JCGM 102).

An expression of the form ``NAME = MODEL; NAME = MODEL`` names several outputs. They are
evaluated on the same Monte Carlo trials and propagated by the GUM as one vector model
(:mod:`mtmc.study.outputs`, as a study with ``[outputs]``); this module parses the text
and the ``-i`` options and prints each output and their correlation and coverage region,
or one JSON object. No maths here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.table import Table

from mtmc.cli.common import (
    engine_message,
    fail,
    gum_lines,
    input_specs,
    nan_policy,
    parallel_options,
    print_json,
    progress_bar,
    quiet_numpy,
    validated_text,
)
from mtmc.errors import InputError, MtmcError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    from mtmc.uncertainty.distributions import Distribution
    from mtmc.uncertainty.joint import ModelOutput

__all__ = ["is_several", "parse_outputs", "propagate_outputs"]


def is_several(text: str) -> bool:
    """Whether ``text`` names outputs (``y1 = ...; y2 = ...``) rather than being one model.

    A model expression never holds ``=`` or ``;``, so the two forms cannot be confused.
    """
    return "=" in text or ";" in text


def parse_outputs(text: str) -> tuple[ModelOutput, ...]:
    """The outputs of ``"NAME = MODEL; NAME = MODEL"``, as :class:`~mtmc.uncertainty.ModelOutput`.

    Raises
    ------
    InputError
        Naming the part (``field`` ``EXPR``): a part without ``NAME =``, a name that is not
        an identifier or is given twice, or a model that does not parse.
    """
    from mtmc.uncertainty.expression import expression
    from mtmc.uncertainty.joint import ModelOutput

    outputs: list[ModelOutput] = []
    for part in (p.strip() for p in text.split(";")):
        if not part:
            continue
        name, sep, model = part.partition("=")
        name = name.strip()
        if not sep or not name.isidentifier() or name.startswith("_"):
            raise InputError(
                f"expected NAME = MODEL for each output, e.g. 'y1 = x[0] + x[1]; y2 = x[0] * a', "
                f"got {part!r}",
                field="EXPR",
            )
        if any(o.name == name for o in outputs):
            raise InputError(f"output {name} is given twice in {text!r}", field="EXPR")
        try:
            outputs.append(ModelOutput(name=name, model=expression(model), unit="1"))
        except MtmcError as exc:
            raise InputError(f"output {name}: {exc.message}", field="EXPR") from None
    if not outputs:
        raise InputError(f"expected NAME = MODEL for each output, got {text!r}", field="EXPR")
    return tuple(outputs)


def _inputs(outputs: tuple[ModelOutput, ...], specs: list[str]) -> dict[str, Distribution]:
    from mtmc.study.outputs import check_vector_use
    from mtmc.uncertainty.joint import JointModel

    names = JointModel(outputs).names
    dists = input_specs(specs)
    extra = [n for n in dists if n not in names]
    if extra:
        raise InputError(
            f"input(s) {', '.join(extra)} not in any output (their variables: {', '.join(names)})",
            field=extra[0],
        )
    missing = [n for n in names if n not in dists]
    if missing:
        raise InputError(
            f"variable(s) {', '.join(missing)} have no -i NAME=DISTRIBUTION", field=missing[0]
        )
    for o in outputs:

        def err(msg: str, _name: str = o.name) -> InputError:
            return InputError(f"output {_name}: {msg}", field="EXPR")

        check_vector_use(o.model, dists, err)
    return {n: dists[n] for n in names}


def _fmt(x: float | None) -> str:
    return "—" if x is None else f"{x:.6g}"


def propagate_outputs(
    text: str,
    specs: list[str],
    *,
    trials: int,
    seed: int | None,
    adaptive: bool,
    with_gum: bool,
    p: float,
    as_json: bool,
    nan: str,
    workers: int,
    executor: str,
    scheduler: str | None,
    progress: bool | None,
) -> None:
    """Run and print several outputs of the same inputs (see the module docstring)."""
    from mtmc.study.outputs import joint_summary
    from mtmc.uncertainty.gum import gum
    from mtmc.uncertainty.joint import JointModel, NamedOutputs
    from mtmc.uncertainty.montecarlo import monte_carlo
    from mtmc.uncertainty.results import MonteCarloResults

    try:
        outputs = parse_outputs(text)
        dists = _inputs(outputs, specs)
        with progress_bar("Monte Carlo", progress) as bar, quiet_numpy():
            mc = monte_carlo(
                NamedOutputs(outputs),
                dists,
                trials=None if adaptive else trials,
                seed=seed,
                adaptive=adaptive,
                p=p,
                progress=bar,
                nan_policy=nan_policy(nan),
                keep=True,
                **parallel_options(workers, executor, scheduler),
            )
        assert isinstance(mc, MonteCarloResults)
        with quiet_numpy():
            g = gum(JointModel(outputs), dists, p=p)
        out: dict[str, Any] = {"outputs": {}, "trials": mc.trials, "omitted": mc.omitted}
        out["seed"] = mc.seed
        for i, o in enumerate(outputs):
            r = mc[o.name]
            row: dict[str, Any] = {
                "model": o.model.text,
                "estimate": r.estimate,
                "u": r.u,
                "p": p,
                "shortest": list(r.coverage_interval(p, kind="shortest")),
                "symmetric": list(r.coverage_interval(p, kind="symmetric")),
            }
            if with_gum:
                row["gum"], row["validation"] = gum_lines(g.component(i), r, p)
            out["outputs"][o.name] = row
        joint = joint_summary(outputs, mc, g, p)
        joint.pop("units")
        if joint["region"] is not None:
            joint["region"].pop("scatter", None)
        out["joint"] = joint
    except (MtmcError, ValueError) as exc:
        fail(engine_message(exc))
    if as_json:
        print_json(out)
        return
    _print(out, p, with_gum)


def _print(out: dict[str, Any], p: float, with_gum: bool) -> None:
    console = Console()
    names = list(out["outputs"])
    table = Table(title=f"Monte Carlo (JCGM 101, JCGM 102) of {len(names)} outputs")
    for col in ("output", "estimate y", "u(y)", f"symmetric {100 * p:g} % interval"):
        table.add_column(col, justify="left" if col == "output" else "right")
    if with_gum:
        table.add_column("u(y), GUM", justify="right")
        table.add_column("GUM validated", justify="right")
    for name, r in out["outputs"].items():
        cells = [name, _fmt(r["estimate"]), _fmt(r["u"])]
        cells.append(f"[{_fmt(r['symmetric'][0])}, {_fmt(r['symmetric'][1])}]")
        if with_gum:
            cells += [_fmt(r["gum"]["u"]), validated_text(r["validation"]["passed"])]
        table.add_row(*cells)
    console.print(table)
    for name, r in out["outputs"].items():
        console.print(f"{name} = {r['model']}")
    joint = out["joint"]
    ct = Table(title="Correlation matrix: Monte Carlo / GUM (JCGM 102 §3.22)")
    ct.add_column("")
    for name in names:
        ct.add_column(name, justify="right")
    for a, name in enumerate(names):
        ct.add_row(
            name,
            *(
                f"{_fmt(joint['monte_carlo']['corr'][a][b])} / {_fmt(joint['gum']['corr'][a][b])}"
                for b in range(len(names))
            ),
        )
    console.print(ct)
    region = joint["region"]
    if region is not None:
        console.print(
            f"{100 * p:g} % coverage region (JCGM 102 §7.7): k = "
            f"{region['monte_carlo']['k']:.4f} (Monte Carlo), {region['gum']['k']:.4f} (GUM, "
            f"χ²); the GUM region holds {100 * region['gum']['gum_coverage']:.2f} % of the trials"
        )
    elif joint["region_note"]:
        console.print(f"no coverage region: {joint['region_note']}")
    console.print(f"trials {out['trials']}  seed {out['seed']}")
