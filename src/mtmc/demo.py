"""Worked examples on built-in defaults, printed as tables (``python -m mtmc.demo``).

The demo is a list of sections, :data:`SECTIONS`; each is a function
``section(console, options)`` that runs one study and prints it. For now it holds the
JCGM 101 §9.3 mass calibration: the inputs, the Monte Carlo result, the GUM result with
its uncertainty budget, and the JCGM 101 §8 validation of the GUM by Monte Carlo, each
beside the values JCGM 101 publishes.

Run ``python -m mtmc.demo --trials 200000 --seed 7`` to change the number of trials or
the seed; ``--section NAME`` runs one section.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from rich.console import Console
from rich.table import Table

from mtmc.uncertainty.distributions import Distribution, Normal, Uniform
from mtmc.uncertainty.expression import Expression, expression
from mtmc.uncertainty.gum import gum, validate
from mtmc.uncertainty.montecarlo import monte_carlo

__all__ = [
    "DemoOptions",
    "SECTIONS",
    "fmt",
    "main",
    "mass_calibration",
    "mass_calibration_inputs",
    "mass_calibration_model",
]


@dataclass(frozen=True)
class DemoOptions:
    """Settings shared by every section.

    Attributes
    ----------
    trials : int
        Monte Carlo trials per study (JCGM 101 §9 uses 10⁶).
    seed : int
        Seed of every Monte Carlo run; printed with the results so they can be repeated.
    """

    trials: int = 10**6
    seed: int = 101


def fmt(x: float) -> str:
    """The demo's number format: six significant digits (``f"{x:.6g}"``)."""
    return f"{x:.6g}"


def mass_calibration_model() -> Expression:
    """JCGM 101 §9.3 model, in mg: the weight's conventional mass minus 100 g.

    ``δm = (m_R,c + δm_R,c) (1 + (ρ_a - ρ_a0)(1/ρ_W - 1/ρ_R)) - m_nom`` with
    ``ρ_a0 = 1.2 kg/m³`` and ``m_nom = 100 000 mg``.

    Returns
    -------
    Expression
    """
    return expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")


def mass_calibration_inputs() -> dict[str, Distribution]:
    """JCGM 101 §9.3 Table 6: the input PDFs (mg, kg/m³).

    Returns
    -------
    dict of str to Distribution
        ``m_rc`` N(100 000.000, 0.050²), ``dm_rc`` N(1.234, 0.020²), ``rho_a``
        R(1.10, 1.30), ``rho_w`` R(7 000, 9 000), ``rho_r`` R(7 950, 8 050).
    """
    return {
        "m_rc": Normal(100_000.000, 0.050),
        "dm_rc": Normal(1.234, 0.020),
        "rho_a": Uniform(1.10, 1.30),
        "rho_w": Uniform(7_000.0, 9_000.0),
        "rho_r": Uniform(7_950.0, 8_050.0),
    }


# JCGM 101 Tables 7 and 8, as printed (mg).
_PUBLISHED_MC = {"estimate": "1.2341", "u": "0.0754", "shortest": "[1.0834, 1.3825]"}
_PUBLISHED_GUM = {"estimate": "1.2340", "u": "0.0539", "interval": "[1.1285, 1.3395]"}
_PUBLISHED_VALIDATION = {"d_low": "0.0451", "d_high": "0.0430", "delta": "0.0005"}


def _table(title: str, *columns: str) -> Table:
    table = Table(title=title, title_justify="left")
    for i, col in enumerate(columns):
        table.add_column(col, justify="left" if i == 0 else "right")
    return table


def mass_calibration(console: Console, options: DemoOptions) -> None:
    """JCGM 101 §9.3: calibration of a 100 g weight against a reference (mg).

    Prints the inputs, the Monte Carlo result (fixed number of trials, shortest 95 %
    interval as in Table 7), the first-order GUM result with its budget, and the §8
    validation with the shortest interval (Table 8), beside the published values.

    Parameters
    ----------
    console : rich.console.Console
        Where to print.
    options : DemoOptions
        Trials and seed.
    """
    model = mass_calibration_model()
    inputs = mass_calibration_inputs()
    console.rule("JCGM 101 §9.3 — mass calibration")
    console.print(f"model: δm = {model.text}   [mg]")

    t_in = _table("Inputs (JCGM 101 Table 6)", "quantity", "PDF", "expectation", "std. dev.")
    for name, dist in inputs.items():
        t_in.add_row(name, str(dist), fmt(dist.mean), fmt(dist.std))
    console.print(t_in)

    start = time.perf_counter()
    mc = monte_carlo(model, inputs, trials=options.trials, seed=options.seed)
    elapsed = time.perf_counter() - start
    lo, hi = mc.coverage_interval(0.95, kind="shortest")
    t_mc = _table("Monte Carlo (JCGM 101 §7)", "", "mtmc", "JCGM 101 Table 7 (M = 10⁶)")
    t_mc.add_row("estimate δm / mg", fmt(mc.estimate), _PUBLISHED_MC["estimate"])
    t_mc.add_row("u(δm) / mg", fmt(mc.u), _PUBLISHED_MC["u"])
    t_mc.add_row(
        "shortest 95 % interval / mg", f"[{fmt(lo)}, {fmt(hi)}]", _PUBLISHED_MC["shortest"]
    )
    t_mc.add_row("length of that interval / mg", fmt(hi - lo), "0.2991")
    t_mc.add_row("trials", str(mc.trials), "")
    t_mc.add_row("seed", str(mc.seed), "")
    t_mc.add_row("time / s", f"{elapsed:.2f}", "")
    console.print(t_mc)
    console.print(
        "The output PDF is nearly flat near the ends of the shortest interval: its length "
        "is well determined, its position moves by about ±0.002 mg from seed to seed at "
        "M = 10⁶ (JCGM 101 §7.7.3)."
    )

    g = gum(model, inputs)
    t_g = _table("GUM, first order (JCGM 100 §5)", "", "mtmc", "JCGM 101 Table 7")
    t_g.add_row("estimate δm / mg", fmt(g.estimate), _PUBLISHED_GUM["estimate"])
    t_g.add_row("u(δm) / mg", fmt(g.u), _PUBLISHED_GUM["u"])
    t_g.add_row("k", fmt(g.k), "1.96")
    t_g.add_row(
        "95 % interval / mg",
        f"[{fmt(g.interval[0])}, {fmt(g.interval[1])}]",
        _PUBLISHED_GUM["interval"],
    )
    t_g.add_row("sensitivities by", g.method, "")
    console.print(t_g)

    t_b = _table("Uncertainty budget", "input", "x", "u(x)", "c", "|c| u(x)", "share of u²")
    for entry in g.budget:
        t_b.add_row(
            entry.name,
            fmt(entry.estimate),
            fmt(entry.u),
            fmt(entry.sensitivity),
            fmt(entry.contribution),
            f"{100 * entry.share:.1f} %",
        )
    console.print(t_b)

    v = validate(g, mc, p=0.95, ndig=2, kind="shortest")
    t_v = _table("Validation of the GUM by MC (JCGM 101 §8)", "", "mtmc", "JCGM 101 Table 8")
    t_v.add_row("d_low / mg", fmt(v.d_low), _PUBLISHED_VALIDATION["d_low"])
    t_v.add_row("d_high / mg", fmt(v.d_high), _PUBLISHED_VALIDATION["d_high"])
    t_v.add_row("δ (ndig = 2) / mg", fmt(v.delta), _PUBLISHED_VALIDATION["delta"])
    t_v.add_row("GUM validated", "yes" if v.passed else "no", "no")
    console.print(t_v)
    console.print(
        "The first-order GUM misses the buoyancy term: its sensitivities to ρ_W and ρ_R "
        "vanish at the estimates, while their product with (ρ_a - ρ_a0) does not."
    )


#: The demo's sections, run in order: (name, function).
SECTIONS: list[tuple[str, Callable[[Console, DemoOptions], None]]] = [
    ("mass-calibration", mass_calibration),
]


def main(argv: Sequence[str] | None = None, console: Any = None) -> int:
    """Run the demo sections and print their tables.

    Parameters
    ----------
    argv : sequence of str, optional
        ``[--trials N] [--seed S] [--section NAME]`` (default: ``sys.argv[1:]``).
    console : rich.console.Console, optional
        Where to print (default: standard output).

    Returns
    -------
    int
        0.
    """
    parser = argparse.ArgumentParser(prog="python -m mtmc.demo", description=__doc__)
    parser.add_argument("--trials", type=int, default=DemoOptions.trials)
    parser.add_argument("--seed", type=int, default=DemoOptions.seed)
    parser.add_argument("--section", choices=[name for name, _ in SECTIONS], default=None)
    args = parser.parse_args(argv)
    options = DemoOptions(trials=args.trials, seed=args.seed)
    if console is None:
        console = Console()
        if console.width < 100:
            console = Console(width=100)
    for name, section in SECTIONS:
        if args.section in (None, name):
            section(console, options)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
