"""``mtmc propagate`` with components of a vector input: ``x[0] + x[1]``."""

from __future__ import annotations

import json
import math

import pytest

from mtmc import expression, gum, monte_carlo, parse_distribution
from mtmc.cli.main import main

X = "mvnormal([1, 2], [[0.01, 0.002], [0.002, 0.04]])"


def test_components_in_the_expression_equal_the_library_result(capsys):
    args = ["propagate", "x[0] + x[1]", "-i", f"x={X}", "-n", "5000", "--seed", "3"]
    code = main([*args, "--gum", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    got = json.loads(out)
    # a second route: the library with the same seed, bit for bit
    inputs = {"x": parse_distribution(X)}
    mc = monte_carlo(expression("x[0] + x[1]"), inputs, trials=5000, seed=3)
    assert got["estimate"] == mc.estimate
    assert got["u"] == mc.u
    # closed form of the GUM: u² = 0.01 + 0.04 + 2 · 0.002
    assert got["gum"]["u"] == gum(expression("x[0] + x[1]"), inputs).u
    assert abs(got["gum"]["u"] ** 2 - 0.054) <= 1e-15  # rounding of the sum


def test_a_component_out_of_range_is_a_one_line_error(capsys):
    code = main(["propagate", "x[0] + x[2]", "-i", f"x={X}", "-n", "100"])
    _, err = capsys.readouterr()
    assert code == 2
    assert err.strip().splitlines() == [
        "mtmc: error: field x: x[2] in 'x[0] + x[2]' is out of range: x has 2 component(s), "
        "x[0] to x[1]"
    ]


def test_an_unsafe_subscript_is_refused(capsys):
    code = main(["propagate", "x[__import__('os')]", "-i", f"x={X}", "-n", "100"])
    _, err = capsys.readouterr()
    assert code == 2
    assert "the index __import__('os') of x" in err


def test_several_outputs_print_each_output_and_their_correlation(capsys):
    # y1 = x0 + x1, y2 = x0 - x1: closed form U_y = [[0.054, -0.03], [-0.03, 0.046]]
    args = ["propagate", "y1 = x[0] + x[1]; y2 = x[0] - x[1]", "-i", f"x={X}"]
    code = main([*args, "-n", "4000", "--seed", "8", "--gum", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    got = json.loads(out)
    assert list(got["outputs"]) == ["y1", "y2"]
    # a second route: the library run of y1 alone, same seed, bit for bit
    y1 = monte_carlo(expression("x[0] + x[1]"), {"x": parse_distribution(X)}, trials=4000, seed=8)
    assert got["outputs"]["y1"]["u"] == y1.u
    assert got["outputs"]["y1"]["symmetric"] == list(y1.coverage_interval(0.95))
    cov = got["joint"]["gum"]["cov"]
    expected = [[0.054, -0.03], [-0.03, 0.046]]
    for row, want in zip(cov, expected, strict=True):
        for a, b in zip(row, want, strict=True):
            assert abs(a - b) <= 1e-16  # sums of products of exact sensitivities (±1)
    assert set(got["outputs"]["y2"]["validation"]) == {
        "d_low",
        "d_high",
        "delta",
        "passed",
        "verdict",
    }
    assert got["joint"]["region"]["gum"]["k"] ** 2 == pytest.approx(-2 * math.log(0.05), rel=1e-12)


def test_several_outputs_refuse_a_name_given_twice(capsys):
    code = main(["propagate", "y = x[0]; y = x[1]", "-i", f"x={X}", "-n", "100"])
    _, err = capsys.readouterr()
    assert code == 2
    assert "output y is given twice" in err
