"""The figures and the numbers of the tutorials, from runs of the shipped studies.

Run from the repository root::

    python docs/tutorials/make_figures.py                 # every tutorial
    python docs/tutorials/make_figures.py stryczek        # one (stryczek, aguado2017, ...)
    python docs/tutorials/make_figures.py --check         # the tutorials' tables are current?

For each tutorial it runs the shipped studies of ``examples/studies`` at the seed and
trial counts stated in the tutorial, and writes

- ``docs/tutorials/figures/NAME_*.png``: our figures, one per figure of the paper;
- ``docs/tutorials/numbers/NAME.json``: every number the tutorial quotes, with the spread
  over the trials of the statistic it is the mean of (``sd``) and the trials (``n``), so
  that a run at fewer trials can be compared within its Monte Carlo tolerance;
- the tables of ``docs/tutorials/NAME.md`` between ``<!-- generated: KEY -->`` and
  ``<!-- end generated -->``: the paper's printed numbers (read from its text, in this
  file) beside ours (from the JSON). No number of our side is typed by hand.

``tests/test_tutorials.py`` reruns each case at a few trials and checks the JSON and the
tables against it.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
STUDIES = ROOT / "examples" / "studies"
FIGURES = HERE / "figures"
NUMBERS = HERE / "numbers"

Numbers = dict[str, Any]


# ---------------------------------------------------------------------------- helpers


def mc(value: float, sd: float, n: int) -> dict[str, float]:
    """A Monte Carlo number: the mean over ``n`` trials of a statistic whose spread is ``sd``."""
    return {"value": float(value), "sd": float(sd), "n": int(n)}


def exact(value: float) -> dict[str, float]:
    """A number that does not depend on the trials (noise-free, or a closed form)."""
    return {"value": float(value)}


def tolerance(doc: Mapping[str, float], run: Mapping[str, float]) -> float:
    """How far a rerun may lie from a documented number: 5 standard errors of both, or 1e-9."""
    if "sd" not in doc:
        return 1e-9 * max(1.0, abs(doc["value"]))
    se = doc["sd"] * math.sqrt(1.0 / doc["n"] + 1.0 / run["n"])
    return 5.0 * se + 1e-9 * max(1.0, abs(doc["value"]))


def v(numbers: Numbers, key: str) -> float:
    """The value of a number of the JSON."""
    return float(numbers["values"][key]["value"])


def fmt(x: float, nd: int = 1) -> str:
    """A number for a table (``—`` for NaN)."""
    return "—" if not math.isfinite(x) else f"{x:.{nd}f}"


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def new_figure(w: float, h: float) -> Any:
    """A Matplotlib figure without pyplot's global state."""
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), dpi=90)


def save(fig: Any, out: Path, name: str) -> Path:
    """Write ``fig`` as ``out/name`` (PNG, no time stamp)."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / name
    fig.savefig(path, format="png", metadata={"Software": None})
    return path


def load(name: str) -> Any:
    """A shipped study."""
    import mtmc

    return mtmc.load_study(STUDIES / f"{name}.toml")


# ---------------------------------------------------------------------------- Stryczek


def stryczek(scale: float = 1.0) -> tuple[Numbers, dict[str, Any]]:
    """Stryczek: Fig. 4, Fig. 1 (a probed ball centre) and Fig. 14-15 (the sweep, eq. 31).

    Fig. 4 is a sum of two normals; Fig. 14-15 u of the A-C distance over sigma_p x sigma_m.
    Returns the numbers (JSON-ready) and the data of the figures.
    """
    import mtmc

    values: dict[str, Any] = {}
    data: dict[str, Any] = {}

    # Fig. 4: X1 + X2, X1 ~ N(0, 1), X2 ~ N(0.5, 0.5), 3000 samples as the paper
    n4 = max(200, int(3000 * scale))
    r4 = mtmc.monte_carlo(
        mtmc.expression("X1 + X2"),
        {"X1": "normal(0, 1)", "X2": "normal(0.5, 0.5)"},
        trials=n4,
        seed=4,
        keep=True,
    )
    values["fig4.mean"] = mc(r4.estimate, r4.u, n4)
    values["fig4.u"] = mc(r4.u, r4.u / math.sqrt(2.0), n4)
    values["fig4.u_exact"] = exact(math.sqrt(1.0 + 0.25))
    data["fig4"] = np.asarray(r4.samples, dtype=np.float64).ravel()

    # Fig. 1: the ball centre from 4 + 1 probed points
    study = ball = load("ball_centre")
    n1 = max(1000, int(study.settings.trials * scale))
    res = study.run(trials=n1, seed=study.settings.seed)
    probe = study.graph.probe
    u_w = math.sqrt(probe.u_axis**2 + probe.u_probe**2 + probe.u_perp**2)  # along the probing
    u_r1 = float(study.graph.place("neg_r1").u)
    closed = {"x": u_w / math.sqrt(2.0), "y": u_w / math.sqrt(2.0), "z": math.hypot(u_w, u_r1)}
    for c in "xyz":
        q = res.quantity(f"p.{c}")
        u = float(q.mc["u"])
        values[f"fig1.u_{c}_um"] = mc(1e3 * u, 1e3 * u / math.sqrt(2.0), n1)
        values[f"fig1.u_{c}_closed_um"] = exact(1e3 * closed[c])
        values[f"fig1.gum_u_{c}_um"] = exact(1e3 * float(q.gum["u"]))
    values["fig1.u_w_um"] = exact(1e3 * u_w)
    values["fig1.u_1_um"] = exact(1e3 * probe.u_axis)
    data["fig1"] = [r.to_dict() for r in res.regions if r.name in ("p: x, y", "p: x, z")]

    # Fig. 14-15: the sweep of u(d_AC) and its surrogate
    study = load("bcs_origin")
    n14 = max(1000, int(study.settings.trials * scale))
    res = study.run(trials=n14, seed=study.settings.seed)
    d = res.quantity("d_ac")
    values["d_ac.estimate_mm"] = mc(d.mc["estimate"], d.mc["u"], n14)
    values["d_ac.u_um"] = mc(1e3 * d.mc["u"], 1e3 * d.mc["u"] / math.sqrt(2.0), n14)
    values["d_ac.gum_u_um"] = exact(1e3 * d.gum["u"])
    values["d_ac.sigma_p_um"] = exact(1e3 * study.graph.probe.u_probe)
    values["d_ac.sigma_m_um"] = exact(1e3 * study.graph.probe.u_axis)
    sw = res.extra["sweep"]
    data["sweep"] = sw
    # the sweep keeps its trials per grid point whatever the scale: the same numbers
    m = int(sw["trials"])
    u_grid = np.asarray(sw["u"], dtype=np.float64)
    for i, (sp, sm) in enumerate(np.asarray(sw["grid"])):
        values[f"sweep.u_um[{1e3 * sp:g},{1e3 * sm:g}]"] = exact(1e3 * u_grid[i])
    fits = (("intercept", sw["surrogate"]), ("no_intercept", sw["surrogate_no_intercept"]))
    for key, fit in fits:
        cp, cm = (float(c) for c in fit["coefficients"])
        values[f"surrogate.{key}.sens_p"] = exact(math.sqrt(cp))
        values[f"surrogate.{key}.sens_m"] = exact(math.sqrt(cm))
        values[f"surrogate.{key}.c0_um"] = exact(1e3 * math.sqrt(fit["c0"]))
        values[f"surrogate.{key}.max_rel_error_pct"] = exact(100.0 * fit["max_rel_error"])
    settings = {
        "fig4": {"trials": n4, "seed": 4},
        "ball_centre": {"trials": n1, "seed": ball.settings.seed},
        "bcs_origin": {"trials": n14, "seed": study.settings.seed, "sweep_trials": m},
    }
    return {"settings": settings, "values": values}, data


#: Stryczek eq. (31): U = 0.05999 sqrt(sigma_p^2/845 + sigma_m^2/868); Fig. 4: 0.502, 1.117.
STRYCZEK_EQ31 = (0.05999, 845.0, 868.0)
STRYCZEK_FIG4 = (0.502, 1.117)


def stryczek_eq31_um(sp_um: Any, sm_um: Any) -> Any:
    """Eq. (31) read with sigma in µm and U in mm, returned in µm."""
    a, b, c = STRYCZEK_EQ31
    return 1e3 * a * np.sqrt(np.asarray(sp_um) ** 2 / b + np.asarray(sm_um) ** 2 / c)


def stryczek_figures(data: dict[str, Any], out: Path) -> list[Path]:
    """Fig. 4, Fig. 1 and Fig. 14-15 of Stryczek, redrawn from our runs."""
    from matplotlib.patches import Ellipse

    paths = []
    x = data["fig4"]
    fig = new_figure(4.2, 2.8)
    fig.subplots_adjust(left=0.13, right=0.97, bottom=0.16, top=0.9)
    ax = fig.add_subplot(1, 1, 1)
    ax.hist(x, bins=40, density=True, color="C0", alpha=0.6, label=f"{x.size} trials")
    t = np.linspace(-4, 5, 200)
    s = math.sqrt(1.25)
    ax.plot(t, np.exp(-0.5 * ((t - 0.5) / s) ** 2) / (s * math.sqrt(2 * math.pi)), "k-", lw=1)
    ax.set_xlabel("Y = X1 + X2")
    ax.set_title("X1 ~ N(0, 1), X2 ~ N(0.5, 0.5) (Stryczek Fig. 4)", fontsize=8)
    ax.legend(fontsize=7)
    paths.append(save(fig, out, "stryczek_fig4.png"))

    fig = new_figure(6.4, 3.2)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.15, top=0.9, wspace=0.35)
    for i, r in enumerate(data["fig1"]):
        ax = fig.add_subplot(1, 2, i + 1)
        pts = (np.asarray(r["scatter"]) - np.asarray(r["centre"])) * 1e3
        ax.plot(pts[:, 0], pts[:, 1], ".", ms=1.5, color="C0", alpha=0.4)
        axes = np.asarray(r["axes"])
        semi = np.asarray(r["semi_axes"]) * 1e3
        ang = float(np.degrees(np.arctan2(axes[1, 1], axes[0, 1])))
        ell = Ellipse((0, 0), 2 * semi[1], 2 * semi[0], angle=ang, fill=False, color="C3", lw=1.4)
        ax.add_patch(ell)
        ax.set_aspect("equal")
        lim = 1.2 * float(np.abs(pts).max())
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        a, b = r["labels"]
        ax.set_xlabel(f"{a} − {a}₀ / µm")
        ax.set_ylabel(f"{b} − {b}₀ / µm")
        ax.set_title(f"ball centre, {a}–{b}: 95 % region", fontsize=8)
    paths.append(save(fig, out, "stryczek_fig1.png"))

    sw = data["sweep"]
    grid = np.asarray(sw["grid"]) * 1e3
    u = np.asarray(sw["u"]) * 1e3
    fit = sw["surrogate"]
    a = np.linspace(grid[:, 0].min(), grid[:, 0].max(), 25)
    aa, bb = np.meshgrid(a, a, indexing="ij")
    cp, cm = fit["coefficients"]
    zz = 1e3 * np.sqrt(fit["c0"] + cp * (aa / 1e3) ** 2 + cm * (bb / 1e3) ** 2)
    fig = new_figure(8.4, 3.6)
    fig.subplots_adjust(left=0.0, right=0.97, bottom=0.06, top=0.92, wspace=0.05)
    ax1: Any = fig.add_subplot(1, 2, 1, projection="3d")
    n = round(math.sqrt(len(u)))
    ax1.plot_surface(
        grid[:, 0].reshape(n, n), grid[:, 1].reshape(n, n), u.reshape(n, n), cmap="viridis"
    )
    ax1.set_title(f"Fig. 14: Monte Carlo, {sw['trials']} trials per point", fontsize=8)
    ax2: Any = fig.add_subplot(1, 2, 2, projection="3d")
    ax2.plot_surface(aa, bb, zz, cmap="viridis", alpha=0.6)
    ax2.plot_wireframe(aa, bb, stryczek_eq31_um(aa, bb), color="k", lw=0.4, rstride=4, cstride=4)
    ax2.scatter(grid[:, 0], grid[:, 1], u, color="C3", s=8)
    ax2.set_title("Fig. 15: our surrogate (colour), eq. 31 (black)", fontsize=8)
    for ax in (ax1, ax2):
        ax.set_xlabel("σ_p / µm", fontsize=7)
        ax.set_ylabel("σ_m / µm", fontsize=7)
        ax.set_zlabel("u(d_AC) / µm", fontsize=7)
        ax.tick_params(labelsize=6)
    paths.append(save(fig, out, "stryczek_fig14_15.png"))
    return paths


def stryczek_tables(nb: Numbers) -> dict[str, str]:
    """The generated tables of ``stryczek.md``."""
    s = nb["settings"]
    a, b, c = STRYCZEK_EQ31
    out = {}
    out["fig4"] = table(
        ["", "Stryczek Fig. 4 (3000 samples)", f"mtmc ({s['fig4']['trials']} trials)", "exact"],
        [
            ["mean of Y", f"{STRYCZEK_FIG4[0]:.3f}", fmt(v(nb, "fig4.mean"), 3), "0.500"],
            [
                "standard deviation of Y",
                f"{STRYCZEK_FIG4[1]:.3f}",
                fmt(v(nb, "fig4.u"), 3),
                fmt(v(nb, "fig4.u_exact"), 3),
            ],
        ],
    )
    rows = []
    for ch in "xyz":
        rows.append(
            [
                f"u(p.{ch}) / µm",
                fmt(v(nb, f"fig1.u_{ch}_um"), 3),
                fmt(v(nb, f"fig1.gum_u_{ch}_um"), 3),
                fmt(v(nb, f"fig1.u_{ch}_closed_um"), 3),
            ]
        )
    out["fig1"] = (
        f"u_w = {fmt(v(nb, 'fig1.u_w_um'), 3)} µm along the probing direction, "
        f"u_1 = {fmt(v(nb, 'fig1.u_1_um'), 3)} µm across it "
        f"({s['ball_centre']['trials']} trials, seed {s['ball_centre']['seed']}).\n\n"
        + table(["", "Monte Carlo", "GUM", "closed form"], rows)
    )
    rows = []
    for key, label in (("intercept", "with c0"), ("no_intercept", "without c0 (eq. 31's form)")):
        rows.append(
            [
                f"mtmc, {label}",
                fmt(v(nb, f"surrogate.{key}.sens_p"), 3),
                fmt(v(nb, f"surrogate.{key}.sens_m"), 3),
                fmt(v(nb, f"surrogate.{key}.c0_um"), 2),
                fmt(v(nb, f"surrogate.{key}.max_rel_error_pct"), 2),
            ]
        )
    out["fig15"] = table(
        ["", "√c_p = u/σ_p", "√c_m = u/σ_m", "√c0 / µm", "largest relative error / %"],
        [
            [
                "Stryczek eq. 31 (U in mm, σ in µm)",
                f"{1e3 * a / math.sqrt(b):.3f}",
                f"{1e3 * a / math.sqrt(c):.3f}",
                "—",
                "≤ 5",
            ],
            *rows,
        ],
    )
    grid = [k for k in nb["values"] if k.startswith("sweep.u_um[")]
    rows = []
    for k in grid:
        sp, sm = (float(t) for t in k[len("sweep.u_um[") : -1].split(","))
        if sp == sm or (sp, sm) in ((1.0, 5.0), (5.0, 1.0)):
            rows.append(
                [
                    f"{sp:g}",
                    f"{sm:g}",
                    fmt(float(stryczek_eq31_um(sp, sm)), 2),
                    fmt(v(nb, k), 2),
                ]
            )
    out["fig14"] = table(["σ_p / µm", "σ_m / µm", "eq. 31 U / µm", "mtmc u(d_AC) / µm"], rows)
    d = s["bcs_origin"]
    out["d_ac"] = (
        f"d_AC = {fmt(v(nb, 'd_ac.estimate_mm'), 4)} mm, u = {fmt(v(nb, 'd_ac.u_um'), 2)} µm "
        f"(GUM {fmt(v(nb, 'd_ac.gum_u_um'), 2)} µm) at the file's "
        f"σ_p = {v(nb, 'd_ac.sigma_p_um'):g} µm, σ_m = {v(nb, 'd_ac.sigma_m_um'):g} µm; "
        f"{d['trials']} trials, seed {d['seed']}; the sweep {d['sweep_trials']} trials per "
        "grid point."
    )
    return out


# ---------------------------------------------------------------------------- driver

Case = tuple[
    Callable[[float], tuple[Numbers, dict[str, Any]]],
    Callable[[dict[str, Any], Path], list[Path]],
    Callable[[Numbers], dict[str, str]],
]

CASES: dict[str, Case] = {
    "stryczek": (stryczek, stryczek_figures, stryczek_tables),
}

_BLOCK = re.compile(r"(<!-- generated: (\S+) -->\n)(.*?)(^<!-- end generated -->)", re.S | re.M)


def fill(text: str, blocks: Mapping[str, str]) -> str:
    """``text`` with every generated block replaced by ``blocks[KEY]``.

    Raises
    ------
    KeyError
        A block of the text that ``blocks`` lacks.
    """

    def sub(m: re.Match[str]) -> str:
        return m.group(1) + blocks[m.group(2)].rstrip("\n") + "\n" + m.group(4)

    return _BLOCK.sub(sub, text)


def blocks(name: str, numbers: Numbers) -> dict[str, str]:
    """Every generated block of a tutorial: its tables and the shipped studies it shows.

    A block ``study:STEM`` is the file ``examples/studies/STEM.toml`` as a TOML code block.
    """
    _, _, tables = CASES[name]
    out = dict(tables(numbers))
    text = (HERE / f"{name}.md").read_text(encoding="utf-8")
    for key in re.findall(r"<!-- generated: study:(\S+) -->", text):
        body = (STUDIES / f"{key}.toml").read_text(encoding="utf-8")
        out[f"study:{key}"] = f"```toml\n{body.rstrip()}\n```"
    return out


def read_numbers(name: str) -> Numbers:
    """The committed numbers of a tutorial."""
    result: Numbers = json.loads((NUMBERS / f"{name}.json").read_text(encoding="utf-8"))
    return result


def main(argv: list[str] | None = None) -> int:
    """Run the cases and write figures, numbers and tables (or ``--check`` the tables)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", help=f"of {sorted(CASES)} (default all)")
    ap.add_argument("--check", action="store_true", help="only check the tables are current")
    args = ap.parse_args(argv)
    stale = []
    for name in args.cases or list(CASES):
        run, figures, _ = CASES[name]
        md = HERE / f"{name}.md"
        if args.check:
            text = md.read_text(encoding="utf-8")
            if fill(text, blocks(name, read_numbers(name))) != text:
                stale.append(name)
            continue
        numbers, data = run(1.0)
        NUMBERS.mkdir(parents=True, exist_ok=True)
        (NUMBERS / f"{name}.json").write_text(json.dumps(numbers, indent=1) + "\n")
        for p in figures(data, FIGURES):
            print(f"{p.relative_to(ROOT)}: {p.stat().st_size // 1024} kB")
        md.write_text(fill(md.read_text(encoding="utf-8"), blocks(name, numbers)), encoding="utf-8")
        print(f"{md.relative_to(ROOT)}: tables written")
    if stale:
        print("stale tables: " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
