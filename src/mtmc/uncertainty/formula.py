"""Measurement models written as text: a safe, vectorised expression language.

``expression("m_rc + dm_rc")`` parses a formula with Python's :mod:`ast` module and
accepts only a whitelist of node types: numbers, variable names, components of vector
variables by a whole-number index (``x[0]``, ``x[1]``), the binary operators
``+ - * / **``, unary ``+``/``-``, parentheses, and calls of a fixed set of NumPy
functions. Nothing is ever passed to :func:`eval`: the tree is walked by
:class:`Expression` itself, so a formula can do arithmetic on arrays and nothing else.

Examples
--------
>>> import numpy as np
>>> f = expression("m_rc + dm_rc")
>>> f.names
('m_rc', 'dm_rc')
>>> f(m_rc=np.array([1.0, 2.0]), dm_rc=np.array([0.5, 0.25]))
array([1.5 , 2.25])
>>> str(expression("sqrt(x**2 + y**2)"))
'sqrt(x**2 + y**2)'
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, cast

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from mtmc.document import read_number
from mtmc.errors import ExpressionError, MtmcError

__all__ = [
    "Expression",
    "expression",
    "check_variables",
    "check_components",
    "ALLOWED_FUNCTIONS",
    "ALLOWED_CONSTANTS",
]

#: Functions an expression may call, by name, with the number of arguments each takes.
ALLOWED_FUNCTIONS: Mapping[str, tuple[Callable[..., Any], int]] = MappingProxyType(
    {
        "sqrt": (np.sqrt, 1),
        "sin": (np.sin, 1),
        "cos": (np.cos, 1),
        "tan": (np.tan, 1),
        "arcsin": (np.arcsin, 1),
        "arccos": (np.arccos, 1),
        "arctan": (np.arctan, 1),
        "arctan2": (np.arctan2, 2),
        "exp": (np.exp, 1),
        "log": (np.log, 1),
        "log10": (np.log10, 1),
        "abs": (np.abs, 1),
        "hypot": (np.hypot, 2),
    }
)

#: Named constants an expression may use.
ALLOWED_CONSTANTS: Mapping[str, float] = MappingProxyType({"pi": float(np.pi), "e": float(np.e)})

# Functions that do not carry the imaginary part of a complex argument through as an
# analytic continuation (or refuse complex input): a model using them is not
# complex-step safe, and GUM sensitivities fall back to central differences.
_NOT_COMPLEX_SAFE = frozenset({"abs", "arctan2", "hypot"})

_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: np.power,
}
#: The text of each binary operator, for :meth:`Expression.fold`.
_SYMBOLS: dict[type[ast.operator], str] = {
    ast.Add: "+",
    ast.Sub: "-",
    ast.Mult: "*",
    ast.Div: "/",
    ast.Pow: "**",
}

_UNARY: dict[type[ast.unaryop], Callable[[Any], Any]] = {
    ast.USub: np.negative,
    ast.UAdd: np.positive,
}

_ALLOWED_TEXT = (
    "numbers, variable names, components x[0], x[1], ... of vector variables, + - * / **, "
    "unary -, parentheses, the constants pi and e, and calls to " + ", ".join(ALLOWED_FUNCTIONS)
)

_MAX_LENGTH = 10_000


def _describe(node: ast.AST) -> str:
    names = {
        ast.Attribute: "attribute access",
        ast.Subscript: "subscripts",
        ast.Lambda: "lambda",
        ast.Compare: "comparisons",
        ast.BoolOp: "boolean operators",
        ast.IfExp: "conditional expressions",
        ast.List: "lists",
        ast.Tuple: "tuples",
        ast.Dict: "dicts",
        ast.Set: "sets",
        ast.ListComp: "comprehensions",
        ast.GeneratorExp: "generators",
        ast.Starred: "starred arguments",
        ast.NamedExpr: "assignment expressions",
        ast.JoinedStr: "f-strings",
        ast.Await: "await",
    }
    for kind, text in names.items():
        if isinstance(node, kind):
            return text
    return type(node).__name__


def check_variables(model: Any, given: Iterable[str], *, what: str = "input") -> None:
    """Refuse names that do not match a model's variables, naming both sides.

    The one check of a model's variables against the names given for them (the inputs of
    :func:`mtmc.uncertainty.gum`, the values passed to an :class:`Expression`, the
    ``[inputs]`` of a study file).

    Parameters
    ----------
    model : Expression or object with ``names``
        The model; one without a ``names`` attribute (a plain function) is not checked.
    given : iterable of str
        The names given.
    what : str
        What a given name is, for the message (``"input"``, ``"value"``).

    Raises
    ------
    ExpressionError
        ``"the model's variable(s) a, b have no <what>"`` and/or ``"<what> c is not a
        variable of the model 'x + y' (its variables: x, y)"``; ``field`` is the first
        name missing, else the first one too many.

    Examples
    --------
    >>> check_variables(expression("a * b"), ["a", "c"])
    Traceback (most recent call last):
    ...
    mtmc.errors.ExpressionError: field b: the model's variable(s) b have no input; input c ...
    """
    names = getattr(model, "names", None)
    if names is None:
        return
    given = list(given)
    missing = [n for n in names if n not in given]
    extra = [n for n in given if n not in names]
    parts = []
    if missing:
        parts.append(f"the model's variable(s) {', '.join(missing)} have no {what}")
    if extra:
        text = getattr(model, "text", None)
        of = f"the model {text!r}" if text is not None else "the model"
        parts.append(
            f"{what} {', '.join(extra)} is not a variable of {of} "
            f"(its variables: {', '.join(names) or 'none'})"
        )
    if parts:
        raise ExpressionError("; ".join(parts), field=(missing or extra)[0])


def check_components(model: Any, dims: Mapping[str, int]) -> None:
    """Refuse a component index that the given input cannot serve, naming the expression.

    A variable taken by components in the model (``x[0]``, ``x[2]``) must be a vector
    input with more components than its largest index; a model that is not an
    :class:`Expression` (or takes no components) is not checked.

    Parameters
    ----------
    model : Expression or object with ``components``
        The model.
    dims : mapping of str to int
        Each input's number of components: ``0`` for a scalar input, ``k`` for a
        ``k``-variate one (the ``dim`` of its distribution).

    Raises
    ------
    ExpressionError
        ``"x[2] in 'x[0] + x[2]' is out of range: x has 2 component(s), x[0] to x[1]"``,
        or ``"... x is a scalar input"``; ``field`` is the variable.

    Examples
    --------
    >>> check_components(expression("x[0] + x[2]"), {"x": 2})
    Traceback (most recent call last):
    ...
    mtmc.errors.ExpressionError: field x: x[2] in 'x[0] + x[2]' is out of range: x has 2 ...
    """
    components: Mapping[str, int] = getattr(model, "components", {})
    text = getattr(model, "text", None)
    where = f" in {text!r}" if text is not None else ""
    for name, need in components.items():
        if name not in dims:
            continue  # a missing input is check_variables' to report
        k = int(dims[name])
        if k == 0:
            raise ExpressionError(
                f"{name}[{need - 1}]{where} takes a component of {name}, but {name} is a "
                "scalar input; give it a k-variate distribution (mvnormal(...), "
                "iid(..., k)) or write it without an index",
                field=name,
            )
        if need > k:
            raise ExpressionError(
                f"{name}[{need - 1}]{where} is out of range: {name} has {k} component(s), "
                f"{name}[0] to {name}[{k - 1}]",
                field=name,
            )


@dataclass(frozen=True)
class Expression:
    """A parsed model expression, callable on arrays.

    Build it with :func:`expression`. Calling it, ``expr(**arrays)``, evaluates the
    formula element-wise with NumPy broadcasting: give each variable as an array whose
    leading axis is the trial, ``(M,)``, and get ``(M,)`` back (a formula without
    variables gives an array broadcast to the inputs' shape, or a 0-d array).

    A variable taken by components, ``x[i]``, is a vector input: its value has the trial
    axis first and the components last, ``(M, k)`` (as :func:`mtmc.monte_carlo` and
    :func:`mtmc.gum` pass a ``k``-variate input), and ``x[i]`` is ``x[..., i]``, the
    ``(M,)`` array of component ``i`` of every trial. Indices are whole numbers from 0
    (``x[0]`` to ``x[k-1]``); a negative index is refused rather than counted from the
    end, so that every component a model uses is named by one number only. A variable is
    used either by components or whole, not both.

    Attributes
    ----------
    text : str
        The formula as written; ``str(expr)`` gives it back.
    names : tuple of str
        The variables, in order of first appearance in the text (constants ``pi``
        and ``e`` and function names are not variables).
    functions : tuple of str
        The functions called, in order of first appearance.
    complex_safe : bool
        True if every function used is analytic in its arguments, so the complex-step
        derivative of :func:`mtmc.gum` is exact; False for ``abs``, ``arctan2`` and
        ``hypot``.
    components : mapping of str to int
        For each variable taken by components, the number of components its largest
        index needs (``{"x": 3}`` for ``x[0] + x[2]``); read-only, empty for a model of
        scalar variables.
    """

    text: str
    names: tuple[str, ...]
    functions: tuple[str, ...]
    complex_safe: bool
    _tree: ast.Expression = field(repr=False, compare=False)
    _components: tuple[tuple[str, int], ...] = field(default=(), repr=False)

    def __str__(self) -> str:
        return self.text

    @property
    def components(self) -> Mapping[str, int]:
        """For each variable taken by components, the number its largest index needs."""
        return MappingProxyType(dict(self._components))

    def __call__(self, **arrays: npt.ArrayLike) -> NDArray[Any]:
        """Evaluate the formula.

        Parameters
        ----------
        **arrays : array_like
            One value per variable in :attr:`names`, e.g. shape ``(M,)`` with the trial
            axis first; real or complex.

        Returns
        -------
        ndarray
            The formula's value, broadcast over the inputs (float64, or complex128 for
            complex input).

        Raises
        ------
        ExpressionError
            If a variable of the formula is missing, or an argument is not one of its
            variables, or a variable taken by components is not an array ``(M, k)`` with
            ``k`` greater than its largest index.
        """
        check_variables(self, arrays, what="value")
        values = {}
        for name, value in arrays.items():
            arr = np.asarray(value)
            if not np.iscomplexobj(arr):
                arr = arr.astype(np.float64, copy=False)
            need = self.components.get(name)
            if need is not None and (arr.ndim < 2 or arr.shape[-1] < need):
                raise ExpressionError(
                    f"{name}[{need - 1}] in {self.text!r} needs {name} as an array "
                    f"(M, k) of k >= {need} components, trial axis first; got shape "
                    f"{arr.shape}",
                    field=name,
                )
            values[name] = arr
        # NaN and inf are the engine's to report, once (nan_policy), on any executor: a
        # Dask or process worker has no errstate of the caller's to keep NumPy quiet
        with np.errstate(all="ignore"):
            return np.asarray(self._eval(self._tree.body, values))

    def fold(
        self,
        leaf: Callable[[str, int | None], Any],
        number: Callable[[float], Any],
        operator: Callable[[str, Any, Any], Any],
        call: Callable[[str, list[Any]], Any],
    ) -> Any:
        """The formula's tree folded bottom-up by the given functions, not by arithmetic.

        For a reading of the formula other than its value: its units and dimension
        (:mod:`mtmc.study.units`), say.

        Parameters
        ----------
        leaf : callable
            ``leaf(name, index)`` of a variable (``index`` None, or the component of
            ``x[i]``) or of a constant (``pi``, ``e``).
        number : callable
            ``number(value)`` of a number literal.
        operator : callable
            ``operator(op, a, b)`` with ``op`` one of ``+ - * / **``, and ``op`` ``neg``
            or ``pos`` (``b`` None) for the unary ones.
        call : callable
            ``call(function_name, arguments)``.

        Examples
        --------
        >>> expression("2 * sqrt(x[0])").fold(
        ...     lambda n, i: f"{n}{i}", str, lambda o, a, b: f"({a}{o}{b})",
        ...     lambda f, args: f"{f}{args}")
        "(2.0*sqrt['x0'])"
        """

        def walk(node: ast.AST) -> Any:
            if isinstance(node, ast.Constant):
                return number(float(cast(float, node.value)))
            if isinstance(node, ast.Name):
                return leaf(node.id, None)
            if isinstance(node, ast.Subscript):
                base = cast(ast.Name, node.value)
                return leaf(base.id, cast(int, cast(ast.Constant, node.slice).value))
            if isinstance(node, ast.BinOp):
                return operator(_SYMBOLS[type(node.op)], walk(node.left), walk(node.right))
            if isinstance(node, ast.UnaryOp):
                op = "neg" if isinstance(node.op, ast.USub) else "pos"
                return operator(op, walk(node.operand), None)
            if isinstance(node, ast.Call):
                return call(node.func.id, [walk(a) for a in node.args])  # type: ignore[attr-defined]
            raise AssertionError(f"unchecked node {type(node).__name__}")  # pragma: no cover

        return walk(self._tree.body)

    def _eval(self, node: ast.AST, values: dict[str, NDArray[Any]]) -> Any:
        if isinstance(node, ast.Constant):
            return float(cast(float, node.value))
        if isinstance(node, ast.Name):
            if node.id in values:
                return values[node.id]
            return ALLOWED_CONSTANTS[node.id]
        if isinstance(node, ast.Subscript):
            # checked: a variable name and a whole-number index >= 0; the components
            # are the last axis, the trials the leading ones
            base = cast(ast.Name, node.value)
            index = cast(int, cast(ast.Constant, node.slice).value)
            return values[base.id][..., index]
        if isinstance(node, ast.BinOp):
            left = self._eval(node.left, values)
            right = self._eval(node.right, values)
            return _BINARY[type(node.op)](left, right)
        if isinstance(node, ast.UnaryOp):
            return _UNARY[type(node.op)](self._eval(node.operand, values))
        if isinstance(node, ast.Call):
            func, _ = ALLOWED_FUNCTIONS[node.func.id]  # type: ignore[attr-defined]
            return func(*(self._eval(a, values) for a in node.args))
        raise AssertionError(f"unchecked node {type(node).__name__}")  # pragma: no cover


def _mixed(name: str, index: int) -> str:
    return (
        f"using {name} both whole and by components ({name}[{index}]) (a vector variable "
        f"is used by components only: {name}[0], {name}[1], ...)"
    )


class _Checker(ast.NodeVisitor):
    """Walk a parsed tree, refuse every node outside the whitelist, collect names."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.names: list[str] = []
        self.functions: list[str] = []
        self.components: dict[str, int] = {}
        self.whole: set[str] = set()

    def _fail(self, node: ast.AST, what: str) -> None:
        col = getattr(node, "col_offset", 0) + 1
        raise ExpressionError(
            f"{what} not allowed in {self.text!r}; allowed: {_ALLOWED_TEXT}",
            line=getattr(node, "lineno", 1),
            column=col,
        )

    def generic_visit(self, node: ast.AST) -> None:
        self._fail(node, _describe(node))

    def visit_Expression(self, node: ast.Expression) -> None:
        self.visit(node.body)

    def visit_Constant(self, node: ast.Constant) -> None:
        value = node.value
        if isinstance(value, bool) or not isinstance(value, int | float):
            self._fail(node, f"the constant {value!r} (only real numbers are)")
        written = ast.get_source_segment(self.text, node) or ""  # 1_0, 0x10: Python's forms

        def error(message: str) -> ExpressionError:
            return ExpressionError(
                f"{message} in {self.text!r}", line=node.lineno, column=node.col_offset + 1
            )

        read_number(written, error)

    def visit_Name(self, node: ast.Name) -> None:
        if node.id.startswith("_"):
            self._fail(node, f"the name {node.id!r} (names starting with '_' are)")
        if node.id in ALLOWED_FUNCTIONS:
            self._fail(node, f"the function name {node.id!r} used as a value")
        if node.id not in ALLOWED_CONSTANTS:
            if node.id in self.components:
                self._fail(node, _mixed(node.id, self.components[node.id] - 1))
            self.whole.add(node.id)
            if node.id not in self.names:
                self.names.append(node.id)

    def visit_Subscript(self, node: ast.Subscript) -> None:
        base = node.value
        if not isinstance(base, ast.Name):
            self._fail(node, "subscripts of anything but a variable name (x[0])")
            return
        name = base.id
        if name.startswith("_"):
            self._fail(base, f"the name {name!r} (names starting with '_' are)")
        if name in ALLOWED_FUNCTIONS or name in ALLOWED_CONSTANTS:
            self._fail(node, f"subscripts of {name!r} (only of a variable)")
        index = node.slice
        if isinstance(index, ast.Slice):
            self._fail(index, f"slices in subscripts of {name} (one component at a time)")
        if (
            isinstance(index, ast.UnaryOp)
            and isinstance(index.op, ast.USub)
            and isinstance(index.operand, ast.Constant)
        ):
            self._fail(
                index,
                f"the negative index in {name}[-{index.operand.value!r}] (components are "
                f"numbered from 0: {name}[0], {name}[1], ...)",
            )
        if not (
            isinstance(index, ast.Constant)
            and isinstance(index.value, int)
            and not isinstance(index.value, bool)
        ):
            shown = ast.get_source_segment(self.text, index) or type(index).__name__
            self._fail(
                index,
                f"the index {shown} of {name} in subscripts (an index is a whole number: "
                f"{name}[0], {name}[1], ...)",
            )
            return
        if name in self.whole:
            self._fail(node, _mixed(name, index.value))
        self.components[name] = max(self.components.get(name, 0), index.value + 1)
        if name not in self.names:
            self.names.append(name)

    def visit_BinOp(self, node: ast.BinOp) -> None:
        if type(node.op) not in _BINARY:
            self._fail(node, f"the operator {type(node.op).__name__}")
        self.visit(node.left)
        self.visit(node.right)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> None:
        if type(node.op) not in _UNARY:
            self._fail(node, f"the operator {type(node.op).__name__}")
        self.visit(node.operand)

    def visit_Call(self, node: ast.Call) -> None:
        if not isinstance(node.func, ast.Name):
            self._fail(node, "calling anything but a function name")
            return
        name = node.func.id
        if name not in ALLOWED_FUNCTIONS:
            self._fail(node, f"the function {name!r}")
        if node.keywords:
            self._fail(node, f"keyword arguments to {name}")
        _, arity = ALLOWED_FUNCTIONS[name]
        if len(node.args) != arity:
            col = node.col_offset + 1
            raise ExpressionError(
                f"{name} takes {arity} argument(s), got {len(node.args)} in {self.text!r}",
                line=node.lineno,
                column=col,
            )
        if name not in self.functions:
            self.functions.append(name)
        for arg in node.args:
            self.visit(arg)


def parse_tree(
    text: str, error: Callable[..., MtmcError], *, shown: str | None = None
) -> ast.Expression:
    """The syntax tree of ``text`` as one Python expression, by :mod:`ast`; nothing is evaluated.

    The one parser of the formulas mtmc reads: model expressions (:func:`expression`) and
    the text of distributions (:func:`~mtmc.uncertainty.distributions.parse_distribution`),
    each of which then walks the tree and refuses every node it has no use for.

    Parameters
    ----------
    text : str
        The text, without leading white space.
    error : callable
        The error class to raise: ``error(message, line=..., column=...)``.
    shown : str, optional
        The text the messages quote (default ``text``).

    Returns
    -------
    ast.Expression

    Raises
    ------
    MtmcError
        ``error("syntax error in 'text': <what Python says>", line, column)``, or
        ``error("cannot parse 'text': ...")`` for a text nested too deeply.

    Examples
    --------
    >>> ast.dump(parse_tree("f(1)", ExpressionError).body)
    "Call(func=Name(id='f', ctx=Load()), args=[Constant(value=1)], keywords=[])"
    >>> parse_tree("f(1", ExpressionError)
    Traceback (most recent call last):
    ...
    mtmc.errors.ExpressionError: line 1, column 2: syntax error in 'f(1': '(' was never closed
    """
    quoted = repr(text if shown is None else shown)
    try:
        return ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise error(
            f"syntax error in {quoted}: {exc.msg}", line=exc.lineno, column=max(1, exc.offset or 1)
        ) from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise error(f"cannot parse {quoted}: {exc}") from None


def expression(text: str) -> Expression:
    """Parse a model formula into a vectorised callable.

    Parameters
    ----------
    text : str
        A formula in Python syntax restricted to: numbers, variable names, components
        of vector variables by a whole-number index from 0 (``x[0]``, ``x[1]``; see
        :class:`Expression`), the binary operators ``+ - * / **``, unary ``-`` and
        ``+``, parentheses, the constants ``pi`` and ``e``, and calls to ``sqrt, sin,
        cos, tan, arcsin, arccos, arctan, arctan2, exp, log, log10, abs, hypot`` (angles
        in rad). Variable names must not start with ``_``.

    Returns
    -------
    Expression
        The parsed formula, with ``.names`` (its variables in order of appearance).

    Raises
    ------
    ExpressionError
        If the text is empty, does not parse, or uses anything outside the whitelist
        (attribute access, slices, negative or computed indices, lambdas, unknown
        functions, ``__import__``, strings, comparisons, ...). The message gives the
        column and what is allowed.

    Examples
    --------
    >>> expression("x.real")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mtmc.errors.ExpressionError: line 1, column 1: attribute access not allowed in 'x.real'; ...
    """
    if not isinstance(text, str):
        raise ExpressionError(f"an expression must be a string, got {type(text).__name__}")
    if len(text) > _MAX_LENGTH:
        raise ExpressionError(f"expression longer than {_MAX_LENGTH} characters")
    if "\x00" in text:
        raise ExpressionError("expression contains a NUL character", column=text.index("\x00") + 1)
    stripped = text.strip()
    if not stripped:
        raise ExpressionError("empty expression; expected a formula such as 'a + b'")
    tree = parse_tree(stripped, ExpressionError)
    checker = _Checker(stripped)
    try:
        checker.visit(tree)
    except RecursionError:
        raise ExpressionError(f"expression nested too deeply: {stripped[:40]!r}...") from None
    return Expression(
        text=stripped,
        names=tuple(checker.names),
        functions=tuple(checker.functions),
        complex_safe=not (_NOT_COMPLEX_SAFE & set(checker.functions)),
        _tree=tree,
        _components=tuple(checker.components.items()),
    )
