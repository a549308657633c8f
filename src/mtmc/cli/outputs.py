"""``mtmc propagate "y1 = ...; y2 = ..."``: several outputs of the same inputs (JCGM 102).

An expression of the form ``NAME = MODEL; NAME = MODEL`` names several outputs. They are
evaluated on the same Monte Carlo trials and propagated by the GUM as one vector model:
``mtmc propagate`` builds a study with ``[outputs]`` and runs it (:mod:`mtmc.study.outputs`);
this module parses the text and checks the ``-i`` options, and prints each output and
their correlation and coverage region, or one JSON object. No maths here.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.table import Table

from mtmc.cli.common import input_specs, print_json, validated_text
from mtmc.cli.run import print_outcome
from mtmc.errors import InputError, MtmcError

if TYPE_CHECKING:  # the library is imported inside the commands: a fast --help
    from mtmc.uncertainty.distributions import Distribution
    from mtmc.uncertainty.joint import ModelOutput

__all__ = ["check_inputs", "is_several", "parse_outputs", "print_outputs", "summary_record"]


def is_several(text: str) -> bool:
    """Whether ``text`` names outputs (``y1 = ...; y2 = ...``) rather than being one model.

    A model expression never holds ``=`` or ``;``, so the two forms cannot be confused.
    """
    return "=" in text or ";" in text


def parse_outputs(text: str) -> tuple[ModelOutput, ...]:
    """The outputs of ``"NAME = MODEL; NAME = MODEL"``, as :class:`~mtmc.study.outputs.ModelOutput`.

    Raises
    ------
    InputError
        Naming the part (``field`` ``EXPR``): a part without ``NAME =``, a name that is not
        an identifier or is given twice, or a model that does not parse.
    """
    from mtmc.uncertainty.formula import expression
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


def check_inputs(outputs: tuple[ModelOutput, ...], specs: list[str]) -> dict[str, Distribution]:
    """The ``-i`` options checked against the outputs: each variable has one, no other.

    Raises
    ------
    InputError
        Naming the input or ``EXPR``.
    """
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


def summary_record(q: Any, with_gum: bool) -> dict[str, Any]:
    """One output's numbers of ``--json``: y, U, k, u, the intervals, the unit.

    With ``with_gum`` (``--gum``) the GUM and the JCGM 101 §8 validation too.
    """
    mc = q.mc
    out: dict[str, Any] = {
        "unit": q.unit,
        "estimate": mc.estimate,
        "U": mc.U,
        "k": mc.k,
        "u": mc.u,
        "p": mc.p,
        "interval_kind": mc.interval,
        "shortest": list(mc.shortest),
        "symmetric": list(mc.symmetric),
        "reported": q.reported.to_dict(),
    }
    if with_gum and q.gum is not None and q.validation is not None:
        g, v = q.gum, q.validation
        out["gum"] = {
            "estimate": g.estimate,
            "U": g.U,
            "k": g.k,
            "u": g.u,
            "interval": list(g.interval),
        }
        out["validation"] = {
            "d_low": v.d_low,
            "d_high": v.d_high,
            "delta": v.delta,
            "passed": v.passed,
            "verdict": v.verdict,
        }
    return out


def print_outputs(
    result: Any, outdir: Path | None, *, with_gum: bool, as_json: bool, quiet: bool
) -> None:
    """Print the result of a propagate study of several outputs: a table or one JSON object."""
    run = result.extra.get("run") or {}
    models = result.extra["models"]
    out: dict[str, Any] = {
        "outputs": {
            q.name: {"model": models[q.name], **summary_record(q, with_gum)}
            for q in result.quantities
        },
        "trials": result.trials,
        "omitted": run.get("omitted", 0),
        "seed": result.seed,
        "run": result.extra.get("run"),
        "output": None if outdir is None else str(outdir),
    }
    joint = dict(result.extra["joint"])
    if joint.get("region") is not None:
        joint["region"] = {k: v for k, v in joint["region"].items() if k != "scatter"}
    out["joint"] = joint
    if as_json:
        print_json(out)
        return
    if not quiet:
        _print(out, result.p, with_gum)
    print_outcome(result, outdir, seed_line=True)


def _print(out: dict[str, Any], p: float, with_gum: bool) -> None:
    console = Console()
    names = list(out["outputs"])
    table = Table(title=f"Monte Carlo (JCGM 101, JCGM 102) of {len(names)} outputs")
    big_u = f"U (k, p = {100 * p:g} %)"
    for col in ("output", "estimate y", big_u, "u(y)"):
        table.add_column(col, justify="left" if col == "output" else "right")
    if with_gum:
        table.add_column("u(y), GUM", justify="right")
        table.add_column("GUM validated", justify="right")
    for name, r in out["outputs"].items():
        k = "" if r["k"] is None else f" (k = {r['k']:.3f})"
        cells = [name, _fmt(r["estimate"]), _fmt(r["U"]) + k, _fmt(r["u"])]
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
