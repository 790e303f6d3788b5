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

import functools
import operator
from collections.abc import Callable
from typing import Any

from cosleec.lang import Printer, SymbolTable, deeply
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

        The source stays shallow whatever the depth of ``e``, for CPython's parser (200
        nested parentheses) and compiler (its recursion limit): a chain of one ``and`` or
        ``or`` is one flat Python chain (the same value), ``not not x`` is ``bool(x)``, a
        long ``+``/``-`` chain is a ``sum`` and a long ``*`` chain a ``prod``, both taken left
        to right as written. What is still more than :data:`MAX_NEST` levels deep (operators
        alternating thousands of times) becomes a call to an evaluator that uses no recursion.
        """
        try:
            return self._source(e, reads, scale, 0)
        except _TooDeep:
            pass
        fn = _Program(self, e).strict
        key = len(_DEEP)
        _DEEP[key] = fn
        reads.update(fn.reads)
        return f"__import__({__name__!r}, fromlist=['_DEEP'])._DEEP[{key}](v)"

    def _source(self, e: A.Expr, reads: set[str], scale: str | None, level: int) -> str:
        if level > MAX_NEST:
            raise _TooDeep
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
            operand, odd = _nots(e)
            inner = self._source(operand, reads, None, level + 1)
            return f"(not {inner})" if odd else f"bool({inner})"
        if isinstance(e, A.BinOp):
            if e.op in A.BOOL_OPS:
                parts = [self._source(x, reads, None, level + 1) for x in _chain(e)]
                return "(" + f" {e.op} ".join(parts) + ")"
            first, rest = _arith_chain(e)
            head = self._source(first, reads, None, level + 1)
            tail = [(op, self._source(x, reads, None, level + 1)) for op, x in rest]
            if len(tail) <= MAX_NEST:
                return "(" + head + "".join(f" {op} {x}" for op, x in tail) + ")"
            # a fold, left to right as written (a - b is exactly a + -b, in floats too)
            fold = "mul" if e.op == "*" else "add"
            terms = ", ".join(x if op != "-" else f"-{x}" for op, x in tail)
            return f"__import__('functools').reduce(__import__('operator').{fold}, ({head}, {terms}))"
        scale = self._scale_of(e.left) or self._scale_of(e.right)
        left = self._source(e.left, reads, scale, level + 1)
        right = self._source(e.right, reads, scale, level + 1)
        return f"({left} {PYOP[e.op]} {right})"

    def _scale_of(self, e: A.Expr) -> str | None:
        if isinstance(e, A.Name):
            m = self.symbols.measures.get(e.name)
            if m is not None and isinstance(m.type, A.ScaleType):
                return e.name
        return None

    def function(self, e: A.Expr | None) -> tuple[Callable[[Values], Any], frozenset[str], str]:
        """``(fn, measures read, source)``; ``None`` (no condition) compiles to True."""
        if e is None:
            return always, frozenset(), "True"
        reads: set[str] = set()
        src = self.source(e, reads)
        return self.lambda_(src, "<sleec condition>"), frozenset(reads), src

    def lambda_(self, body: str, filename: str) -> Callable[[Values], Any]:
        """``lambda v: body``, compiled once per rule set for each distinct ``body`` (the
        same condition, deadline or clause tuple in many rules shares one function: a
        10,000-rule build would otherwise spend most of its time in ``compile``)."""
        fn = self._cache.get(body)
        if fn is None:
            fn = eval(compile(f"lambda v: {body}", filename, "eval"))
            self._cache[body] = fn
        return fn

    def kleene(self, e: A.Expr | None) -> Callable[[Values], Any]:
        """The three-valued form of ``e``: True, False, a number, or None when unknown.

        Slower than :meth:`function` (no short-circuit, one closure per node): call it only
        when the fast form raised KeyError.
        """
        if e is None:
            return always
        return self._kleene(e, None)

    def _kleene(self, e: A.Expr, scale: str | None) -> Callable[[Values], Any]:
        try:
            return self._kleene_at(e, scale, 0)
        except _TooDeep:
            return _Program(self, e, scale).kleene

    def _kleene_at(self, e: A.Expr, scale: str | None, level: int) -> Callable[[Values], Any]:
        if level > MAX_NEST:
            raise _TooDeep
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
            operand, odd = _nots(e)
            inner = self._kleene_at(operand, None, level + 1)
            if odd:
                return lambda v: None if (x := inner(v)) is None else not x
            return lambda v: None if (x := inner(v)) is None else bool(x)
        if isinstance(e, A.BinOp):
            if e.op in A.BOOL_OPS:
                parts = [self._kleene_at(x, None, level + 1) for x in _chain(e)]
                return _all_of(_and if e.op == "and" else _or, parts)
            first, rest = _arith_chain(e)
            fn = self._kleene_at(first, None, level + 1)
            for op, x in rest:  # each step a closure over the last: no deeper than MAX_NEST
                if len(rest) > MAX_NEST:
                    raise _TooDeep
                fn = _strict(_ARITH[op], fn, self._kleene_at(x, None, level + 1))
            return fn
        scale = self._scale_of(e.left) or self._scale_of(e.right)
        return _strict(
            _COMPARE[e.op],
            self._kleene_at(e.left, scale, level + 1),
            self._kleene_at(e.right, scale, level + 1),
        )


MAX_NEST = 100
"""How deep the compiled form of an expression may nest (CPython's parser allows 200 nested
parentheses); a deeper expression is evaluated by a :class:`_Program`."""

_DEEP: dict[int, Callable[[Values], Any]] = {}
"""The evaluators of expressions too deep for Python source, which the source calls by key
(the source is compiled where this module's names are unknown: a rule's clauses are joined
into one function elsewhere)."""


class _TooDeep(Exception):
    """An expression nests deeper than :data:`MAX_NEST` even in its flattened form."""


def _nots(e: A.Not) -> tuple[A.Expr, bool]:
    """The operand under a run of ``not``s, and whether their number is odd."""
    n = 0
    x: A.Expr = e
    while isinstance(x, A.Not):
        x, n = x.operand, n + 1
    return x, n % 2 == 1


def _chain(e: A.BinOp) -> list[A.Expr]:
    """The operands of ``e``'s chain of its own ``and`` (or ``or``), left to right, however
    parenthesised: ``(a and b) and c`` and ``a and (b and c)`` are both ``[a, b, c]``."""
    out: list[A.Expr] = []
    todo: list[A.Expr] = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, A.BinOp) and x.op == e.op:
            todo += (x.right, x.left)
        else:
            out.append(x)
    return out


def _arith_chain(e: A.BinOp) -> tuple[A.Expr, list[tuple[str, A.Expr]]]:
    """A left-associated chain ``t0 op1 t1 op2 t2 ...`` of ``+``/``-`` (or of ``*``):
    ``t0`` and the ``(op, t)`` after it, left to right."""
    ops = ("*",) if e.op == "*" else ("+", "-")
    rest: list[tuple[str, A.Expr]] = []
    x: A.Expr = e
    while isinstance(x, A.BinOp) and x.op in ops:
        rest.append((x.op, x.right))
        x = x.left
    rest.reverse()
    return x, rest


def _all_of(op: Callable[[Any, Any], Any], parts: list[Callable[[Values], Any]]) -> Callable[[Values], Any]:
    """The Kleene ``and`` (``or``) of every part: each is evaluated (no short-circuit)."""
    if len(parts) == 2:
        left, right = parts
        return lambda v: op(left(v), right(v))

    def apply(v: Values) -> Any:
        acc = parts[0](v)
        for p in parts[1:]:
            acc = op(acc, p(v))
        return acc

    return apply


class _Program:
    """An expression as a postfix program run on a stack: no recursion, whatever its depth.

    :attr:`kleene` is its three-valued form; :attr:`strict` its fast form (KeyError when a
    measure it reads has no value, like the compiled source). Built for the expressions
    too deep for :meth:`Compiler.source`, so it favours simplicity over speed.
    """

    def __init__(self, compiler: Compiler, e: A.Expr, scale: str | None = None) -> None:
        code: list[tuple[str, Any]] = []  # ("load", name) / ("const", x) / (op, arity)
        reads: set[str] = set()
        s = compiler.symbols
        todo: list[tuple[A.Expr, str | None, bool]] = [(e, scale, False)]
        while todo:
            x, sc, done = todo.pop()
            if done:
                code.append(("not", 1) if isinstance(x, A.Not) else (x.op, 2))  # type: ignore[union-attr]
                continue
            if isinstance(x, A.BoolLit | A.IntLit):
                code.append(("const", x.value))
            elif isinstance(x, A.DecimalLit):
                code.append(("const", float(x.text)))
            elif isinstance(x, A.Name):
                if x.name in s.measures:
                    reads.add(x.name)
                    code.append(("load", x.name))
                elif x.name in s.constant_values:
                    code.append(("const", s.constant_values[x.name]))
                elif sc is not None:
                    m = s.measures[sc]
                    assert isinstance(m.type, A.ScaleType)
                    code.append(("const", m.type.literals.index(x.name)))
                else:
                    raise ValueError(f"cannot evaluate {x.name!r} here")
            elif isinstance(x, A.Not):
                todo += ((x, None, True), (x.operand, None, False))
            elif isinstance(x, A.BinOp):
                todo += ((x, None, True), (x.right, None, False), (x.left, None, False))
            else:
                sc = compiler._scale_of(x.left) or compiler._scale_of(x.right)
                todo += ((x, None, True), (x.right, sc, False), (x.left, sc, False))
        self.code = code
        self.reads = frozenset(reads)
        self.strict = _Strict(self)

    def kleene(self, v: Values) -> Any:
        stack: list[Any] = []
        push, pop = stack.append, stack.pop
        for op, arg in self.code:
            if op == "const":
                push(arg)
            elif op == "load":
                push(v.get(arg))
            elif op == "not":
                x = pop()
                push(None if x is None else not x)
            else:
                b, a = pop(), pop()
                if op == "and":
                    push(_and(a, b))
                elif op == "or":
                    push(_or(a, b))
                elif a is None or b is None:
                    push(None)
                else:
                    push((_ARITH.get(op) or _COMPARE[op])(a, b))
        return stack[0]


class _Strict:
    """A :class:`_Program`'s fast form: KeyError for a measure without a value, else its value."""

    def __init__(self, program: _Program) -> None:
        self.program = program
        self.reads = program.reads

    def __call__(self, v: Values) -> Any:
        for name in self.reads:
            v[name]  # KeyError, as the compiled source raises it
        return self.program.kleene(v)


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


def always(v: Values) -> bool:
    """The condition of a rule without one (a hot path need not call it: ``is always``)."""
    return True


def text(e: A.Expr | None) -> str:
    """A condition as SLEEC text, for explanations."""
    if e is None:
        return "true"
    printer = _printer()
    return deeply(lambda: printer.expr(e))  # the printer recurses once per level


@functools.cache
def _printer() -> Printer:
    """One printer of expressions for every :func:`text` (making one per condition cost a
    10,000-rule build a tenth of its time); it keeps no state between expressions."""
    return Printer(A.Specification((), ()), A.Dialect.TK)
