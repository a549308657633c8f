"""The report's plots: CPU time of each kind of figure, with and without fitting its text.

Every quantity of a report draws a histogram and a convergence plot, so their cost sets
the time of a report of many quantities (Wang, Cheung and Kong 2022: 36 quantities, 72
plots). The figures are drawn from the ``result.json`` of shipped studies run here at
``M`` trials (seed 1): the point of the C axis of ``axis_c`` (a histogram, a convergence
plot, its coverage region) and the first field of ``five_axis`` (two views and a 3-D
view). Each line is the best of ``repeats`` interleaved repeats, in CPU seconds of this
process, drawn as the report draws it (``report.plots``) and with ``_fit`` (the check
that thins touching tick labels and keeps every text inside its figure) left out. The
whole report of ``axis_c`` is rendered last (``mtmc report``).

Usage: python benchmarks/bench_report.py [M] [repeats]
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mtmc.report import plots, render
from mtmc.study import load_study, write_result

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ROOT / "examples" / "studies"


def _cpu() -> float:
    t = os.times()
    return t.user + t.system


def _best(fn: Callable[[], Any], repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t = _cpu()
        fn()
        best = min(best, _cpu() - t)
    return best


def _unfitted(fig: Any) -> None:
    """A figure as it was drawn before ``report.plots._fit``: nothing moved."""
    del fig


def _result(name: str, trials: int, out: Path) -> dict[str, Any]:
    study = load_study(STUDIES / f"{name}.toml")
    write_result(study.run(trials=trials, seed=1), out / name, study_text=study.source.text)
    doc: dict[str, Any] = json.loads((out / name / "result.json").read_text(encoding="utf-8"))
    return doc


def main() -> None:
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 20_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        axis_c = _result("axis_c", trials, out)
        five = _result("five_axis", min(trials, 2000), out)
        q = next(x for x in axis_c["quantities"] if x["name"] == "axis_c.point.y")
        figures = {
            "histogram": lambda: plots.histogram_svg(q),
            "convergence": lambda: plots.convergence_svg(q),
            "region": lambda: plots.region_svg(axis_c["regions"][0]),
            "field (2 views and 3-D)": lambda: plots.field_svg(five["fields"][0]),
        }
        fit = plots._fit
        print(f"load average {os.getloadavg()[0]:.2f}; CPU s a figure, best of {repeats}")
        print(f"{'figure':26} {'as drawn':>9} {'no _fit':>9}")
        for name, draw in figures.items():
            draw()  # fonts and caches warm
            with_fit = _best(draw, repeats)
            plots._fit = _unfitted
            try:
                without = _best(draw, repeats)
            finally:
                plots._fit = fit
            print(f"{name:26} {with_fit:9.3f} {without:9.3f}")
        n = len(axis_c["quantities"])
        t = _best(lambda: render(out / "axis_c"), max(1, repeats // 2))
        plotted = 2 * n + len(axis_c["regions"])
        print(f"report of axis_c ({n} quantities, {plotted} plots): {t:.2f} s")


if __name__ == "__main__":
    main()
