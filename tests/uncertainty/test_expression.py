"""Expression models: values against NumPy, names, text round trip, and refusal of
anything outside the whitelist (including random text, which must never execute)."""

from __future__ import annotations

import builtins
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mtmc import ExpressionError, expression

RNG = np.random.default_rng(np.random.SeedSequence(20260101))
A = RNG.uniform(0.1, 0.9, 50)
B = RNG.uniform(0.1, 0.9, 50)


@pytest.mark.parametrize(
    ("text", "reference"),
    [
        ("a + b", A + B),
        ("a - b", A - B),
        ("a * b", A * B),
        ("a / b", A / B),
        ("a ** b", A**B),
        ("-a + +b", -A + B),
        ("(a + b) * (a - b)", (A + B) * (A - B)),
        ("2 ** -1 * a", 0.5 * A),
        ("sqrt(a)", np.sqrt(A)),
        ("sin(a) + cos(b) + tan(a)", np.sin(A) + np.cos(B) + np.tan(A)),
        ("arcsin(a) + arccos(b) + arctan(a)", np.arcsin(A) + np.arccos(B) + np.arctan(A)),
        ("arctan2(a, -b)", np.arctan2(A, -B)),
        ("exp(a) + log(b) + log10(a)", np.exp(A) + np.log(B) + np.log10(A)),
        ("abs(a - b)", np.abs(A - B)),
        ("hypot(a, b)", np.hypot(A, B)),
        ("pi * a + e * b", np.pi * A + np.e * B),
        ("1e-3 * a", 1e-3 * A),
    ],
)
def test_values_match_numpy(text, reference):
    expr = expression(text)
    got = expr(**{n: {"a": A, "b": B}[n] for n in expr.names})
    np.testing.assert_allclose(got, reference, rtol=1e-15, atol=0)
    assert got.shape == (50,)


def test_mass_calibration_formula_and_names():
    expr = expression("(m_rc + dm_rc) * (1 + (rho_a - 1.2) * (1 / rho_w - 1 / rho_r)) - 100000")
    assert expr.names == ("m_rc", "dm_rc", "rho_a", "rho_w", "rho_r")
    m, dm, ra, rw, rr = (
        np.array([100000.0]),
        np.array([1.234]),
        np.array([1.3]),
        np.array([7000.0]),
        np.array([8050.0]),
    )
    ref = (m + dm) * (1 + (ra - 1.2) * (1 / rw - 1 / rr)) - 100000
    np.testing.assert_allclose(
        expr(m_rc=m, dm_rc=dm, rho_a=ra, rho_w=rw, rho_r=rr), ref, rtol=1e-15
    )


def test_names_in_order_of_appearance_without_constants_or_functions():
    expr = expression("z * sin(y) + pi * x + z + e")
    assert expr.names == ("z", "y", "x")
    assert expr.functions == ("sin",)


def test_str_gives_the_text_back():
    text = "m_rc + dm_rc"
    assert str(expression(text)) == text
    assert str(expression("  a*b ")) == "a*b"


def test_complex_safety_flag():
    assert expression("sqrt(a) * exp(b)").complex_safe
    assert not expression("abs(a)").complex_safe
    assert not expression("hypot(a, b)").complex_safe
    assert not expression("arctan2(a, b)").complex_safe


def test_complex_input_is_carried_through():
    expr = expression("a**2 * sin(b)")
    h = 1e-20
    got = expr(a=np.array([0.3 + 1j * h]), b=np.array([0.7]))
    # complex-step derivative: d/da (a^2 sin b) = 2 a sin b
    assert got.imag[0] / h == pytest.approx(2 * 0.3 * np.sin(0.7), rel=1e-14)


def test_broadcasting_vector_inputs():
    expr = expression("a * b")
    got = expr(a=np.ones((4, 3)), b=np.arange(3.0))
    assert got.shape == (4, 3)


@pytest.mark.parametrize(
    ("text", "fragment", "column"),
    [
        ("x.real", "attribute access", 1),
        ("a + x[0][1]", "subscripts of anything but a variable name", 5),
        ("lambda: 1", "lambda", 1),
        ("__import__('os')", "'__import__'", 1),
        ("a + open('f')", "the function 'open'", 5),
        ("a if b else c", "conditional expressions", 1),
        ("a < b", "comparisons", 1),
        ("a and b", "boolean operators", 1),
        ("'text'", "the constant 'text'", 1),
        ("1j * a", "the constant 1j", 1),
        ("True + a", "the constant True", 1),
        ("a // b", "the operator FloorDiv", 1),
        ("a % b", "the operator Mod", 1),
        ("~a", "the operator Invert", 1),
        ("[a, b]", "lists", 1),
        ("sqrt(x=a)", "keyword arguments", 1),
        ("a + sqrt", "the function name 'sqrt' used as a value", 5),
        ("_secret * 2", "names starting with '_'", 1),
        ("(a).__class__", "attribute access", 1),
    ],
)
def test_rejects_unsafe_input_with_column(text, fragment, column):
    with pytest.raises(ExpressionError) as info:
        expression(text)
    msg = str(info.value)
    assert fragment in msg
    assert f"column {column}:" in msg
    assert "allowed: numbers, variable names" in msg
    assert "sqrt" in msg
    assert "hypot" in msg
    assert info.value.column == column


def test_wrong_arity_and_syntax_errors():
    with pytest.raises(ExpressionError, match=r"arctan2 takes 2 argument\(s\), got 1"):
        expression("arctan2(a)")
    with pytest.raises(ExpressionError, match="syntax error") as info:
        expression("a + * b")
    assert info.value.column is not None
    with pytest.raises(ExpressionError, match="empty expression"):
        expression("   ")
    with pytest.raises(ExpressionError, match="must be a string"):
        expression(3)  # type: ignore[arg-type]


def test_call_with_missing_or_unknown_variable():
    expr = expression("a + b")
    with pytest.raises(ExpressionError, match=r"variable\(s\) b have no value") as info:
        expr(a=A)
    assert info.value.field == "b"
    with pytest.raises(ExpressionError, match="c is not a variable") as info:
        expr(a=A, b=B, c=A)
    assert info.value.field == "c"


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=40))
def test_random_text_never_executes(text):
    """Any string either parses into an Expression or raises ExpressionError; nothing
    outside NumPy arithmetic can run (the builtins that could import or open are
    replaced by traps for the duration of the parse)."""
    called = []

    def trap(*args, **_kwargs):
        called.append(args)
        raise AssertionError("executed")

    saved = {n: getattr(builtins, n) for n in ("__import__", "open", "exec", "eval")}
    try:
        for name in ("open", "exec", "eval"):
            setattr(builtins, name, trap)
        try:
            expr = expression(text)
        except ExpressionError:
            pass
        else:
            assert isinstance(expr.names, tuple)
            assert all(not n.startswith("_") for n in expr.names)
            assert set(expr.functions) <= {
                "sqrt",
                "sin",
                "cos",
                "tan",
                "arcsin",
                "arccos",
                "arctan",
                "arctan2",
                "exp",
                "log",
                "log10",
                "abs",
                "hypot",
            }
    finally:
        for name, value in saved.items():
            setattr(builtins, name, value)
    assert not called


ALPHABET = st.sampled_from(
    ["a", "b", "x", "(", ")", "+", "-", "*", "/", "**", "sqrt", "sin", ".", "[", "]", "_", " ", "1"]
)


@settings(max_examples=300, deadline=None)
@given(st.lists(ALPHABET, max_size=12).map("".join))
def test_formula_like_text_parses_or_raises_and_evaluates_finite_shape(text):
    try:
        expr = expression(text)
    except ExpressionError:
        return
    values = {n: np.full(3, 0.5) for n in expr.names}
    with np.errstate(all="ignore"):
        out = np.broadcast_to(expr(**values), (3,))
    assert out.shape == (3,)


@pytest.mark.parametrize(
    ("text", "column", "words"),
    [
        ("a + 1_0", 5, "got '1_0'"),  # Python reads 10
        ("a * 0x10", 5, "got '0x10'"),  # Python reads 16
        ("a + 1" + "0" * 400, 5, "(401 characters); at most 100 characters"),  # OverflowError
        ("a + 1e400", 5, "expected a finite number at most 1.8e+308 in size, got '1e400'"),
    ],
)
def test_a_literal_is_read_as_a_number_of_a_file(text, column, words):
    with pytest.raises(ExpressionError) as info:
        expression(text)
    assert info.value.column == column
    assert words in info.value.message


def test_a_literal_written_in_other_digits_is_refused_with_its_column():
    for text in ("a + \u0661\u0660", "a + \uff11\uff10"):  # Arabic-Indic, fullwidth 10
        with pytest.raises(ExpressionError) as info:
            expression(text)
        assert info.value.column == 5


def test_evaluation_leaves_nan_to_the_engine_without_a_warning():
    # a Dask worker printed "RuntimeWarning: invalid value encountered in sqrt" before
    # the run's one-line error: the worker has no errstate of the command line's
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        y = expression("sqrt(a) + log(a) / a")(a=np.array([-1.0, 0.0, 4.0]))
    assert np.isnan(y[0])
    assert not np.isfinite(y[1])  # log(0) / 0: -inf, no warning
    assert y[2] == pytest.approx(2.0 + math.log(4.0) / 4.0, rel=1e-15)  # libm vs NumPy: 1 ulp
