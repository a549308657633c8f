"""``propagate`` studies with vector inputs and several outputs (JCGM 102)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from mtmc.errors import MtmcError
from mtmc.report import html
from mtmc.study import loads_study
from mtmc.uncertainty import MultivariateNormal, expression, gum, monte_carlo

# x ~ N((1, 2), U_x), a ~ N(3, 0.1²): y1 = x0 + x1, y2 = x0 a
TWO = """\
kind = "propagate"
title = "two outputs"

[inputs]
x = "mvnormal([1, 2], [[0.01, 0.002], [0.002, 0.04]])"
a = "normal(3, 0.1)"

[outputs]
y1 = "x[0] + x[1]"
y2 = { model = "x[0] * a", unit = "mm" }

[run]
trials = 20000
seed = 7
"""

ONE = """\
kind = "propagate"
model = "x[0] * a"
output = "y2"
unit = "mm"

[inputs]
x = "mvnormal([1, 2], [[0.01, 0.002], [0.002, 0.04]])"
a = "normal(3, 0.1)"

[run]
trials = 20000
seed = 7
"""

U_X = np.array([[0.01, 0.002], [0.002, 0.04]])
# closed form, at the estimates x = (1, 2), a = 3: C = [[1, 1, 0], [a, 0, x0]] over
# (x0, x1, a), U_y = C diag(U_x, 0.01) Cᵀ = [[0.054, 0.036], [0.036, 0.1]]
U_Y = np.array([[0.054, 0.036], [0.036, 0.1]])


def test_two_outputs_gum_is_c_ux_ct_and_mc_is_within_its_standard_error():
    r = loads_study(TWO, file="two.toml").run()
    j = r.to_dict()["joint"]
    assert j["outputs"] == ["y1", "y2"]
    assert j["units"] == ["1", "mm"]
    np.testing.assert_allclose(j["gum"]["cov"], U_Y, rtol=1e-14)  # rounding of products
    assert j["gum"]["corr"][0][1] == pytest.approx(0.036 / math.sqrt(0.054 * 0.1), rel=1e-14)
    # the sample covariance of M trials: variance (U_ii U_jj + U_ij²)/(M - 1) for a
    # Gaussian output; y2 = x0 a is not Gaussian, but its excess kurtosis is small
    # (u(x0)/x0 = 0.1, u(a)/a = 0.03): 5 standard errors bound every entry
    m = 20_000
    se = np.sqrt((np.outer(np.diag(U_Y), np.diag(U_Y)) + U_Y**2) / (m - 1))
    assert np.all(np.abs(np.array(j["monte_carlo"]["cov"]) - U_Y) <= 5 * se)
    # each output is also a quantity, with the GUM of its own row of C
    assert r.quantity("y1").gum.u == pytest.approx(math.sqrt(0.054), rel=1e-14)
    assert r.quantity("y2").gum.u == pytest.approx(math.sqrt(0.1), rel=1e-14)
    assert r.quantity("y2").unit == "mm"


def test_each_output_is_bit_for_bit_the_study_of_that_output_alone():
    # a second run: the same seed gives each input the same draws whatever the other
    # inputs and outputs, so y2 of the joint study is the single-output study of y2
    both = loads_study(TWO).run(samples=True)
    alone = loads_study(ONE).run(samples=True)
    np.testing.assert_array_equal(both.samples["y2"], alone.samples["y2"])
    assert both.quantity("y2").to_dict() == alone.quantity("y2").to_dict()


def test_the_joint_samples_are_the_library_runs_of_the_expressions():
    # a second method: monte_carlo of each expression alone, with the same seed
    r = loads_study(TWO).run(samples=True)
    x = {"x": MultivariateNormal([1, 2], U_X), "a": "normal(3, 0.1)"}
    y1 = monte_carlo(expression("x[0] + x[1]"), {"x": x["x"]}, trials=20_000, seed=7)
    np.testing.assert_array_equal(r.samples["y1"], y1.values)
    j = r.to_dict()["joint"]
    joint = np.column_stack([r.samples["y1"], r.samples["y2"]])
    np.testing.assert_array_equal(j["monte_carlo"]["cov"], np.cov(joint, rowvar=False))


def test_the_two_output_region_and_its_gum_coverage():
    r = loads_study(TWO).run()
    region = r.to_dict()["joint"]["region"]
    # JCGM 102 §6.5.2.3: k² = χ²₂(0.95) = -2 ln 0.05, closed form
    assert region["gum"]["k"] ** 2 == pytest.approx(-2 * math.log(0.05), rel=1e-12)
    # the output is close to Gaussian: the fraction of trials in the GUM ellipse is
    # 0.95 within 4 binomial standard errors sqrt(p(1-p)/M) (plus the small departure
    # from Gaussian of x0 a, well inside that)
    assert abs(region["gum"]["gum_coverage"] - 0.95) <= 4 * math.sqrt(0.95 * 0.05 / 20_000)
    # the Monte Carlo k² is near χ²₂(0.95): 4 standard errors of a sample quantile
    se = math.sqrt(0.95 * 0.05 / 20_000) / (0.5 * 0.05)  # χ²₂ density at its 95 % point
    assert abs(region["monte_carlo"]["k"] ** 2 + 2 * math.log(0.05)) <= 4 * se
    assert len(region["scatter"]) == 400


def test_three_outputs_give_the_correlation_table_and_a_region_without_a_plot():
    text = TWO.replace(
        'y2 = { model = "x[0] * a", unit = "mm" }', 'y2 = "x[0] * a"\ny3 = "x[1] - a"'
    )
    r = loads_study(text).run(trials=5000)
    d = r.to_dict()
    j = d["joint"]
    # closed form: y3 = x1 - a, u² = 0.04 + 0.01; cov(y1, y3) = U11 + U01 = 0.042;
    # cov(y2, y3) = a U01 - x0 u²(a) = 0.006 - 0.01 = -0.004
    expected = np.array([[0.054, 0.036, 0.042], [0.036, 0.1, -0.004], [0.042, -0.004, 0.05]])
    np.testing.assert_allclose(j["gum"]["cov"], expected, rtol=1e-13, atol=1e-17)
    assert "scatter" not in j["region"]
    assert j["region"]["gum"]["k"] ** 2 == pytest.approx(7.814727903251178, rel=1e-12)  # χ²₃(0.95)
    page = html(d)
    assert 'data-key="joint.gum.corr[1][2]"' in page
    assert 'data-plot="joint"' not in page


def test_the_report_draws_the_two_outputs_together():
    d = loads_study(TWO).run(trials=2000).to_dict()
    page = html(d)
    assert '<section id="joint">' in page
    assert 'data-plot="joint"><svg' in page
    corr = d["joint"]["monte_carlo"]["corr"][0][1]
    assert f'data-key="joint.monte_carlo.corr[0][1]" data-value="{corr!r}"' in page
    # every number of the section is the one in result.json, shown to 4 digits (or in %)
    cells = re.findall(r'data-key="(joint\.[^"]+)" data-value="([^"]+)">([^<]+)<', page)
    assert len(cells) == 2 * 4 + 2 * 4 + 3  # corr and cov, MC and GUM; k, k, coverage
    for key, value, text in cells:
        want = d
        for name, index in re.findall(r"([A-Za-z_]+)|\[(\d+)\]", key):
            want = want[name] if name else want[int(index)]
        assert float(value) == want, key
        shown = f"{100 * want:.1f} %" if key.endswith("gum_coverage") else f"{want:.4g}"
        assert text == shown, key


def test_linearly_dependent_outputs_have_no_region_and_say_why():
    text = TWO.replace('{ model = "x[0] * a", unit = "mm" }', '"2 * x[0] + 2 * x[1] + 0 * a"')
    j = loads_study(text).run(trials=2000).to_dict()["joint"]
    assert j["region"] is None
    assert "singular" in j["region_note"]
    assert 'data-plot="joint"' not in html(loads_study(text).run(trials=2000).to_dict())


def test_a_single_model_of_components_of_a_vector_input():
    # closed form: u²(x0 + x1) = 0.054; the inputs entry lists the components
    text = ONE.replace('"x[0] * a"', '"x[0] + x[1]"').replace('a = "normal(3, 0.1)"\n', "")
    r = loads_study(text).run(trials=2000)
    assert r.quantity("y2").gum.u ** 2 == pytest.approx(0.054, rel=1e-14)
    x = r.to_dict()["inputs"][0]
    assert x["estimate"] == [1.0, 2.0]
    assert x["u"] == pytest.approx([0.1, 0.2], rel=1e-15)  # sqrt of the diagonal
    # one output in [outputs] is the same study (the same Monte Carlo values)
    r1 = loads_study(
        text.replace('model = "x[0] + x[1]"\noutput = "y2"\nunit = "mm"\n', "")
        + '\n[outputs]\ny2 = { model = "x[0] + x[1]", unit = "mm" }\n'
    ).run(trials=2000)
    assert r1.quantity("y2").mc == r.quantity("y2").mc
    assert r1.to_dict()["joint"]["region"] is None


def test_iid_components_in_a_study():
    # closed form: y = x0 + x1 + x2 of iid normal(0, 1): u² = 3
    text = """\
kind = "propagate"
[inputs]
x = "iid(normal(0, 1), 3)"
[outputs]
s = "x[0] + x[1] + x[2]"
d = "x[0] - x[1]"
"""
    r = loads_study(text).run(trials=2000, seed=1)
    j = r.to_dict()["joint"]
    np.testing.assert_allclose(j["gum"]["cov"], [[3.0, 0.0], [0.0, 2.0]], rtol=1e-14, atol=1e-15)
    assert j["gum"]["corr"][0][1] == pytest.approx(0.0, abs=1e-15)


# (replace this, with this, expected line, expected field, words in the message)
CASES = [
    (
        'y1 = "x[0] + x[1]"',
        'y1 = "x[0] + x[2]"',
        9,
        "outputs.y1",
        "x[2] in 'x[0] + x[2]' is out of range: x has 2",
    ),
    ('"x[0] * a"', '"x[0] * a[0]"', 10, "outputs.y2.model", "a is a scalar input"),
    ('y1 = "x[0] + x[1]"', 'y1 = "x[b]"', 9, "outputs.y1", "the index b of x"),
    ('y1 = "x[0] + x[1]"', 'y1 = "x[-1]"', 9, "outputs.y1", "the negative index"),
    ('y1 = "x[0] + x[1]"', 'y1 = "x[0:1]"', 9, "outputs.y1", "slices"),
    ('y1 = "x[0] + x[1]"', 'y1 = "x.T[0]"', 9, "outputs.y1", "subscripts of anything but"),
    (
        'y1 = "x[0] + x[1]"',
        'y1 = "x + 1"',
        9,
        "outputs.y1",
        "x has 2 components and 'x + 1' uses it whole",
    ),
    (
        'y1 = "x[0] + x[1]"',
        'y1 = "x[0] + b"',
        9,
        "outputs.y1",
        'b have no input; expected b = "normal(...)"',
    ),
    ('y1 = "x[0] + x[1]"', 'y1 = "3"', 9, "outputs.y1", "has no input variable"),
    ('y1 = "x[0] + x[1]"', "y1 = 3", 9, "outputs.y1", "expected a model text"),
    ('y1 = "x[0] + x[1]"', 'a = "x[0]"', 9, "outputs.a", "has the name of an input"),
    ('y1 = "x[0] + x[1]"', '"y 1" = "x[0]"', 9, "outputs.y 1", "expected an output name"),
    ('unit = "mm" }', 'unit = "mm", colour = 1 }', 10, "outputs.y2.colour", "unknown key"),
    (
        '{ model = "x[0] * a", unit = "mm" }',
        '{ unit = "mm" }',
        10,
        "outputs.y2.model",
        "missing model",
    ),
    (
        'a = "normal(3, 0.1)"',
        'a = "normal(3, 0.1)"\nc = 1.0',
        7,
        "inputs.c",
        "not a variable of any output",
    ),
    (
        "[[0.01, 0.002], [0.002, 0.04]]",
        "[[0.01, 0.2], [0.2, 0.04]]",
        5,
        "inputs.x",
        "positive semi-definite",
    ),
    (
        "[[0.01, 0.002], [0.002, 0.04]]",
        "[[0.01, 0.002], [0.003, 0.04]]",
        5,
        "inputs.x",
        "symmetric",
    ),
    ("[[0.01, 0.002], [0.002, 0.04]]", "[[0.01, 0.002]]", 5, "inputs.x", "2x2 matrix"),
    (
        'title = "two outputs"',
        'title = "two outputs"\nmodel = "x[0]"',
        3,
        "model",
        "either model, output and unit, or [outputs]",
    ),
    (
        'title = "two outputs"',
        'title = "two outputs"\noutput = "y"',
        3,
        "output",
        "with [outputs] each output",
    ),
    (
        '[outputs]\ny1 = "x[0] + x[1]"\ny2 = { model = "x[0] * a", unit = "mm" }',
        "[outputs]",
        8,
        "outputs",
        "at least one output",
    ),
]


@pytest.mark.parametrize(("old", "new", "line", "field", "words"), CASES)
def test_a_broken_file_names_file_line_and_field(old, new, line, field, words):
    text = TWO.replace(old, new, 1)
    assert text != TWO
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="broken.toml")
    err = info.value
    assert (err.file, err.line, err.field) == ("broken.toml", line, field)
    assert words in err.message
    assert "\n" not in str(err)


SINGLE_CASES = [
    ('"x[0] * a"', '"x[0] * a * x[5]"', 2, "model", "x[5] in 'x[0] * a * x[5]' is out of range"),
    ('"x[0] * a"', '"x * a"', 2, "model", "x has 2 components and 'x * a' uses it whole"),
    ('"x[0] * a"', '"x[0] * a[1]"', 2, "model", "a is a scalar input"),
    ('"x[0] * a"', '"x[0] * a + x"', 2, "model", "using x both whole and by components"),
]


@pytest.mark.parametrize(("old", "new", "line", "field", "words"), SINGLE_CASES)
def test_a_broken_single_model_names_file_line_and_field(old, new, line, field, words):
    text = ONE.replace(old, new, 1)
    with pytest.raises(MtmcError) as info:
        loads_study(text, file="one.toml")
    err = info.value
    assert (err.file, err.line, err.field) == ("one.toml", line, field)
    assert words in err.message


def test_gum_of_the_study_is_the_library_gum():
    # a second route: the library's gum of the expression alone, bit for bit
    r = loads_study(ONE).run(trials=2000)
    g = gum(expression("x[0] * a"), {"x": MultivariateNormal([1, 2], U_X), "a": "normal(3, 0.1)"})
    assert r.quantity("y2").gum.u == g.u


def test_the_polar_coordinates_example_has_the_gum_of_docs_vector_inputs():
    # docs/vector-inputs.md by hand: C = [[0.6, 0.8], [-0.016, 0.012]] at (30, 40) mm,
    # U_y = C U_x Cᵀ = [[0.000816, 4.24e-6], [4.24e-6, 1.936e-7]]. hypot and arctan2 are
    # not complex-safe: central differences with h = 1e-3 u = 2e-5 mm, whose rounding
    # error eps · f / h (f = 50 mm or 0.93 rad) is about 1e-9 of each c (1e-8: a margin)
    from pathlib import Path

    from mtmc.study import load_study

    path = Path(__file__).resolve().parents[2] / "examples" / "studies" / "polar_coordinates.toml"
    r = load_study(path).run(trials=4000)
    j = r.to_dict()["joint"]
    assert j["gum"]["method"] == "central-difference"
    expected = [[0.000816, 4.24e-6], [4.24e-6, 1.936e-7]]
    np.testing.assert_allclose(j["gum"]["cov"], expected, rtol=1e-8)
    assert j["gum"]["corr"][0][1] == pytest.approx(
        4.24e-6 / math.sqrt(0.000816 * 1.936e-7), rel=1e-8
    )


BAD_VALUES = ['"junk"', "nan", "-1", "[]", "{}", "true", "1e400", '["a", 1]', '"x[9]"', '"p[0] +"']


def test_every_bad_value_of_the_example_fails_on_its_own_line():
    # each key line of the shipped example with a bad value: an error naming this file
    # and that line (or a file still valid, such as a title of "junk", that loads). A
    # number for the vector input p is a valid constant that the outputs then cannot
    # index: that error is on the line of the output that takes p[0]
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "examples" / "studies" / "polar_coordinates.toml"
    lines = path.read_text(encoding="utf-8").splitlines()
    errors: list[tuple[int, MtmcError]] = []
    for i, raw in enumerate(lines):
        m = re.match(r'^(\s*[A-Za-z_"][A-Za-z0-9_."]*\s*=\s*)(.*)$', raw)
        if not m:
            continue
        for bad in BAD_VALUES:
            text = "\n".join([*lines[:i], m.group(1) + bad, *lines[i + 1 :]]) + "\n"
            try:
                study = loads_study(text, file=path.name)
            except MtmcError as exc:
                errors.append((i + 1, exc))
            else:
                assert study.title
    assert len(errors) > 40
    r_line = next(n for n, t in enumerate(lines, 1) if t.startswith("r = "))
    for line, exc in errors:
        assert exc.file == path.name
        if "p is a scalar input" in exc.message:
            assert (exc.line, exc.field) == (r_line, "outputs.r.model"), exc
        else:
            assert exc.line == line, (line, str(exc))
        assert exc.field
        assert "\n" not in str(exc)
