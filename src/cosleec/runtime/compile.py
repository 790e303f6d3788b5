"""SLEEC expressions -> Python functions over the context's value dict.

A condition is compiled once, to Python source evaluated by CPython itself: the fastest
evaluation available and exactly the operators' mathematical meaning (numbers compare
exactly; scale literals compare by position; booleans by equality). A missing value
raises KeyError.

Unknown values follow Kleene's three-valued logic, independent of operand order:
``true or unknown`` is true, ``false and unknown`` is false, ``not unknown``, a comparison
or arithmetic with an unknown operand, and anything else that depends on it is unknown
(``None``). Each condition therefore has two compiled forms: the fast one, which raises
KeyError as soon as it reads a missing measure (and, when it does not raise, already
agrees with Kleene: a short-circuit only skips an operand that cannot change the
result), and :meth:`Compiler.kleene`, used only after that KeyError, which evaluates
every operand and returns True, False or None.
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from typing import Any

from cosleec.lang import Printer, SymbolTable
from cosleec.lang import ast as A

Values = dict[str, Any]
PYOP = {
    "and": "and",
    "or": "or",
    "+": "+",
    "-": "-",
    "*": "*",
    "<": "<",
    "<=": "<=",
    ">": ">",
    ">=": ">=",
    "=": "==",
    "<>": "!=",
}


class Compiler:
    """Compiles the conditions and deadlines of one checked specification to Python functions.

    It needs the checker's symbol table to tell measures, constants and scale literals
    apart, so there is one per :class:`~cosleec.runtime.RuleSet`, used while the rule set
    is built; identical conditions share one compiled function.
    """

    def __init__(self, symbols: SymbolTable) -> None:
        self.symbols = symbols
        self._cache: dict[str, Callable[[Values], Any]] = {}

    def source(self, e: A.Expr, reads: set[str], scale: str | None = None) -> str:
        """Python source for ``e``; ``scale`` is the measure whose literals bare names denote.

        Adds every measure ``e`` reads to ``reads``. ValueError for a name that is neither a
        measure, a constant nor (with ``scale``) a literal -- the checker rules that out.
        """
        if isinstance(e, A.BoolLit):
            return "True" if e.value else "False"
        if isinstance(e, A.IntLit):
            return str(e.value)
        if isinstance(e, A.DecimalLit):
            return e.text
        if isinstance(e, A.Name):
            s = self.symbols
            if e.name in s.measures:
                reads.add(e.name)
                return f"v[{e.name!r}]"
            if e.name in s.constant_values:
                return str(s.constant_values[e.name])
            if scale is not None:
                m = s.measures[scale]
                assert isinstance(m.type, A.ScaleType)
                return str(m.type.literals.index(e.name))
            raise ValueError(f"cannot evaluate {e.name!r} here")
        if isinstance(e, A.Not):
            return f"(not {self.source(e.operand, reads)})"
        if isinstance(e, A.BinOp):
            return f"({self.source(e.left, reads)} {PYOP[e.op]} {self.source(e.right, reads)})"
        scale = self._scale_of(e.left) or self._scale_of(e.right)
        return f"({self.source(e.left, reads, scale)} {PYOP[e.op]} {self.source(e.right, reads, scale)})"

    def _scale_of(self, e: A.Expr) -> str | None:
        if isinstance(e, A.Name):
            m = self.symbols.measures.get(e.name)
            if m is not None and isinstance(m.type, A.ScaleType):
                return e.name
        return None

    def function(self, e: A.Expr | None) -> tuple[Callable[[Values], Any], frozenset[str], str]:
        """``(fn, measures read, source)``; ``None`` (no condition) compiles to True."""
        if e is None:
            return _true, frozenset(), "True"
        reads: set[str] = set()
        src = self.source(e, reads)
        fn = self._cache.get(src)
        if fn is None:
            fn = eval(compile(f"lambda v: {src}", "<sleec condition>", "eval"))
            self._cache[src] = fn
        return fn, frozenset(reads), src

    def kleene(self, e: A.Expr | None) -> Callable[[Values], Any]:
        """The three-valued form of ``e``: True, False, a number, or None when unknown.

        Slower than :meth:`function` (no short-circuit, one closure per node): call it only
        when the fast form raised KeyError.
        """
        if e is None:
            return _true
        return self._kleene(e, None)

    def _kleene(self, e: A.Expr, scale: str | None) -> Callable[[Values], Any]:
        if isinstance(e, A.BoolLit | A.IntLit):
            return _const(e.value)
        if isinstance(e, A.DecimalLit):
            return _const(float(e.text))
        if isinstance(e, A.Name):
            s = self.symbols
            if e.name in s.measures:
                name = e.name
                return lambda v: v.get(name)
            if e.name in s.constant_values:
                return _const(s.constant_values[e.name])
            if scale is not None:
                m = s.measures[scale]
                assert isinstance(m.type, A.ScaleType)
                return _const(m.type.literals.index(e.name))
            raise ValueError(f"cannot evaluate {e.name!r} here")
        if isinstance(e, A.Not):
            inner = self._kleene(e.operand, None)
            return lambda v: None if (x := inner(v)) is None else not x
        if isinstance(e, A.BinOp):
            left, right = self._kleene(e.left, None), self._kleene(e.right, None)
            if e.op == "and":
                return lambda v: _and(left(v), right(v))
            if e.op == "or":
                return lambda v: _or(left(v), right(v))
            return _strict(_ARITH[e.op], left, right)
        scale = self._scale_of(e.left) or self._scale_of(e.right)
        return _strict(_COMPARE[e.op], self._kleene(e.left, scale), self._kleene(e.right, scale))


_ARITH: dict[str, Callable[[Any, Any], Any]] = {"+": operator.add, "-": operator.sub, "*": operator.mul}
_COMPARE: dict[str, Callable[[Any, Any], Any]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "=": operator.eq,
    "<>": operator.ne,
}


def _const(x: Any) -> Callable[[Values], Any]:
    return lambda v: x


def _and(a: Any, b: Any) -> bool | None:
    """Kleene conjunction: false if either side is false, unknown if either is unknown."""
    if (a is not None and not a) or (b is not None and not b):
        return False
    return None if a is None or b is None else True


def _or(a: Any, b: Any) -> bool | None:
    """Kleene disjunction: true if either side is true, unknown if either is unknown."""
    if (a is not None and a) or (b is not None and b):
        return True
    return None if a is None or b is None else False


def _strict(
    op: Callable[[Any, Any], Any], left: Callable[[Values], Any], right: Callable[[Values], Any]
) -> Callable[[Values], Any]:
    """An operator that is unknown when either operand is (comparison, arithmetic)."""

    def apply(v: Values) -> Any:
        a, b = left(v), right(v)
        return None if a is None or b is None else op(a, b)

    return apply


def _true(v: Values) -> bool:
    return True


def text(e: A.Expr | None) -> str:
    """A condition as SLEEC text, for explanations."""
    if e is None:
        return "true"
    return Printer(A.Specification((), ()), A.Dialect.TK).expr(e)
