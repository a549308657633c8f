"""The demo prints the library's own numbers: run it with a small M and compare."""

from __future__ import annotations

from mtmc import demo, gum, monte_carlo, validate


def test_mass_calibration_section_prints_library_results(capsys):
    assert demo.main(["--trials", "20000", "--seed", "3"]) == 0
    out = capsys.readouterr().out
    model = demo.mass_calibration_model()
    inputs = demo.mass_calibration_inputs()
    mc = monte_carlo(model, inputs, trials=20_000, seed=3)
    g = gum(model, inputs)
    v = validate(g, mc, kind="shortest")
    lo, hi = mc.coverage_interval(0.95, kind="shortest")
    f = demo.fmt
    for text in (
        "JCGM 101 §9.3",
        f(mc.estimate),
        f(mc.u),
        f"[{f(lo)}, {f(hi)}]",
        "20000",
        f(g.u),
        f"[{f(g.interval[0])}, {f(g.interval[1])}]",
        f(v.d_low),
        f(v.d_high),
        f(v.delta),
        "GUM validated",
    ):
        assert text in out, text
    for entry in g.budget:
        assert entry.name in out
        assert f"{100 * entry.share:.1f} %" in out
    # the inputs of JCGM 101 Table 6
    assert "normal(100000, 0.05)" in out and "uniform(7000, 9000)" in out


def test_sections_are_listed_and_selectable(capsys):
    names = [name for name, _ in demo.SECTIONS]
    assert names[0] == "mass-calibration"
    assert demo.main(["--trials", "1000", "--seed", "1", "--section", "mass-calibration"]) == 0
    assert "mass calibration" in capsys.readouterr().out
