"""Generic deterministic design constraints ``g(x) <= 0``: Python callables or safe expressions.

A :class:`DesignConstraint` is a name and a vectorised callable ``g(x (P, d)) -> (P,)``, feasible
where ``g <= 0``. :meth:`DesignConstraint.from_expression` builds one from a text such as
``"L / D <= 12"`` over the design variable names, for configuration files: the text is parsed
with :mod:`ast` and only numbers, the variable names, ``+ - * / **``, unary signs, one comparison
(``<=``, ``>=``, ``<``, ``>``) and the functions of :data:`FUNCTIONS` (and constants ``pi``,
``e``) are allowed — never ``eval`` of arbitrary code. ``lhs <= rhs`` becomes
``g = lhs − rhs``, ``lhs >= rhs`` becomes ``g = rhs − lhs``; an expression without a comparison
is ``g`` itself. An optional ``scale`` divides ``g`` (so that violations of different constraints
are comparable when an optimiser sums them).

>>> c = DesignConstraint.from_expression("slender", "L / D <= 12", ("F", "L", "D"))
>>> c(np.array([[2000.0, 600.0, 60.0], [2000.0, 750.0, 50.0]])).tolist()
[-2.0, 3.0]
>>> try:
...     DesignConstraint.from_expression("bad", "__import__('os')", ("x",))
... except ValueError as exc:
...     print(str(exc).split(" (")[0])
constraint 'bad': expression "__import__('os')" is not allowed: call of '__import__'
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_positive

#: functions an expression may call (element-wise; ``min``/``max`` of two or more arguments)
FUNCTIONS: dict[str, Callable[..., np.ndarray]] = {
    "abs": np.abs, "cos": np.cos, "exp": np.exp, "log": np.log, "log10": np.log10,
    "max": lambda *a: np.maximum.reduce(np.broadcast_arrays(*a)),
    "min": lambda *a: np.minimum.reduce(np.broadcast_arrays(*a)),
    "sin": np.sin, "sqrt": np.sqrt, "tan": np.tan, "tanh": np.tanh,
}
CONSTANTS = {"pi": np.pi, "e": np.e}
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow}
_UNARY = {ast.UAdd: operator.pos, ast.USub: operator.neg}
_LE, _GE = (ast.LtE, ast.Lt), (ast.GtE, ast.Gt)


class _Compiled:
    """An expression tree checked against the whitelist, evaluated on design columns."""

    def __init__(self, name: str, text: str, variables: Sequence[str]) -> None:
        self.name, self.text, self.variables = name, text, tuple(variables)
        try:
            tree = ast.parse(text, mode="eval").body
        except SyntaxError as exc:
            raise self._error(f"syntax error ({exc.msg})") from None
        if isinstance(tree, ast.Compare):
            if len(tree.ops) != 1:
                raise self._error("at most one comparison (<=, >=, <, >)")
            op = tree.ops[0]
            if isinstance(op, _LE):
                tree = ast.BinOp(tree.left, ast.Sub(), tree.comparators[0])
            elif isinstance(op, _GE):
                tree = ast.BinOp(tree.comparators[0], ast.Sub(), tree.left)
            else:
                raise self._error(f"comparison {type(op).__name__} (use <=, >=, <, >)")
        self._check(tree)
        self.tree = tree

    def _error(self, what: str) -> ValueError:
        return ValueError(f"constraint {self.name!r}: expression {self.text!r} is not allowed: "
                          f"{what}")

    def _check(self, node: ast.AST) -> None:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise self._error(f"constant {node.value!r} (numbers only)")
        elif isinstance(node, ast.Name):
            if node.id not in self.variables and node.id not in CONSTANTS:
                raise self._error(f"unknown name {node.id!r} (design variables: "
                                  f"{', '.join(self.variables)}; constants: pi, e)")
        elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            self._check(node.operand)
        elif isinstance(node, ast.Call):
            fname = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
            if fname not in FUNCTIONS or node.keywords or not node.args:
                raise self._error(f"call of {fname!r} (allowed functions: "
                                  f"{', '.join(sorted(FUNCTIONS))})")
            for a in node.args:
                self._check(a)
        else:
            raise self._error(f"{type(node).__name__} (numbers, design variables, + - * / **, "
                              "one comparison and whitelisted functions only)")

    def __call__(self, x: np.ndarray) -> np.ndarray:
        cols = {n: x[:, i] for i, n in enumerate(self.variables)}
        return np.broadcast_to(np.asarray(self._eval(self.tree, cols), dtype=float),
                               (x.shape[0],)).copy()

    def _eval(self, node: ast.AST, cols: dict[str, np.ndarray]):
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            return cols[node.id] if node.id in cols else CONSTANTS[node.id]
        if isinstance(node, ast.BinOp):
            return _BINARY[type(node.op)](self._eval(node.left, cols),
                                          self._eval(node.right, cols))
        if isinstance(node, ast.UnaryOp):
            return _UNARY[type(node.op)](self._eval(node.operand, cols))
        return FUNCTIONS[node.func.id](*(self._eval(a, cols) for a in node.args))


@dataclass(frozen=True, eq=False)
class DesignConstraint:
    """A deterministic design constraint ``func(x (P, d)) / scale <= 0``.

    Parameters
    ----------
    name : str
        Column name (``constraint_names`` of the formulation).
    func : callable
        Vectorised ``x (P, d) -> (P,)``.
    scale : float
        Positive divisor of ``func`` (1 by default).
    """

    name: str
    func: Callable[[np.ndarray], np.ndarray]
    scale: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name = {self.name!r} is not allowed: must be a non-empty string")
        if not callable(self.func):
            raise ValueError(f"constraint {self.name!r}: func = {self.func!r} is not allowed: "
                             "must be callable x (P, d) -> (P,)")
        check_positive(f"constraint {self.name!r}: scale", self.scale)

    @classmethod
    def from_expression(cls, name: str, expression: str, variables: Sequence[str],
                        scale: float = 1.0) -> DesignConstraint:
        """Parse ``expression`` over the design ``variables`` (in the columns' order)."""
        if not isinstance(expression, str):
            raise ValueError(f"constraint {name!r}: expression = {expression!r} is not allowed:"
                             " must be a string")
        return cls(name, _Compiled(name, expression, variables), scale)

    @property
    def expression(self) -> str | None:
        """The text it was parsed from (``None`` for a Python callable)."""
        return self.func.text if isinstance(self.func, _Compiled) else None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        g = np.asarray(self.func(x), dtype=float).reshape(-1)
        if g.shape != (x.shape[0],):
            raise ValueError(f"constraint {self.name!r} returned shape {g.shape}, expected "
                             f"({x.shape[0]},)")
        return g / self.scale


class _Block:
    """``func(X (P, d)) -> (P, k)`` evaluated once per distinct design row and kept (the
    columns of one block share the evaluation; an expensive check, e.g. exact critical
    speeds, is never repeated for a design already seen)."""

    def __init__(self, func: Callable[[np.ndarray], np.ndarray], k: int) -> None:
        self.func, self.k = func, k
        self._cache: dict[bytes, np.ndarray] = {}

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        keys = [row.tobytes() for row in x]
        todo: dict[bytes, int] = {}
        for i, key in enumerate(keys):
            if key not in self._cache and key not in todo:
                todo[key] = i
        if todo:
            rows = list(todo.values())
            g = np.asarray(self.func(x[rows]), dtype=float).reshape(len(rows), self.k)
            self._cache.update(zip(todo, g, strict=True))
        return np.array([self._cache[key] for key in keys]).reshape(len(keys), self.k)


@dataclass(frozen=True, eq=False)
class _Column:
    block: _Block
    j: int

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return self.block(x)[:, self.j]


def block_constraints(names: Sequence[str], func: Callable[[np.ndarray], np.ndarray], *,
                      scale: float = 1.0) -> tuple[DesignConstraint, ...]:
    """One :class:`DesignConstraint` per column of a vectorised ``func(x (P, d)) -> (P, k)``
    (``names`` in column order); the columns share one evaluation per distinct design.

    >>> calls = []
    >>> def g(x):
    ...     calls.append(len(x))
    ...     return np.column_stack([x[:, 0] - 1.0, x[:, 1] - 2.0])
    >>> a, b = block_constraints(("a", "b"), g)
    >>> x = np.array([[0.0, 3.0], [2.0, 0.0]])
    >>> a(x).tolist(), b(x).tolist(), a(x[::-1]).tolist(), calls
    ([-1.0, 1.0], [1.0, -2.0], [1.0, -1.0], [2])
    """
    names = tuple(names)
    if not names:
        raise ValueError("names = () is not allowed: give one name per column")
    block = _Block(func, len(names))
    return tuple(DesignConstraint(n, _Column(block, j), scale) for j, n in enumerate(names))


def constraint_matrix(constraints: Sequence[DesignConstraint], x: np.ndarray) -> np.ndarray:
    """``(P, n)`` values of ``constraints`` at the designs ``x`` (``(P, 0)`` for none)."""
    if not constraints:
        return np.empty((x.shape[0], 0))
    return np.column_stack([c(x) for c in constraints])


__all__ = ["CONSTANTS", "FUNCTIONS", "DesignConstraint", "block_constraints", "constraint_matrix"]
