"""SLEEC expressions -> Python functions over the context's value dict.

A condition is compiled once, to Python source evaluated by CPython itself: the fastest
evaluation available and exactly the operators' mathematical meaning (numbers compare
exactly; scale literals compare by position; booleans by equality). A missing value
raises KeyError, which the caller turns into an *unknown measure*.
"""

from __future__ import annotations

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


def _true(v: Values) -> bool:
    return True


def text(e: A.Expr | None) -> str:
    """A condition as SLEEC text, for explanations."""
    if e is None:
        return "true"
    return Printer(A.Specification((), ()), A.Dialect.TK).expr(e)
