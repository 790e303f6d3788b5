"""The checks of conditions and numbers (docs/reference/sleec-language.md §5): kinds, types, operators.

:class:`Expressions` gives every expression a :data:`Type` and reports what does not fit:
a measure where a constant is meant, a truth value ordered, a scale compared with what is not
one of its literals (read as LEGOS-SLEEC does under ``legos_compat``, compat.py), ``and``
and ``or`` mixed without parentheses.

May import: errors, and the lang modules ast, compat, diagnostics and scope.
"""

from __future__ import annotations

from cosleec.errors import closest
from cosleec.lang import ast as A
from cosleec.lang.compat import LegosReader, mirrored
from cosleec.lang.diagnostics import QUOTE_LIMIT, clip
from cosleec.lang.scope import Scope

BOOL = "bool"
NUM = "num"

# An expression's type: BOOL, NUM, ("scale", measure) or ("lit", literal) -- a bare name
# that is no measure or constant and can only be a scale literal -- or None after an error.
Type = str | tuple[str, str] | None

_OPERATORS: dict[type, frozenset[str]] = {A.BinOp: A.BOOL_OPS | A.ARITH_OPS, A.Compare: A.REL_OPS}


def type_word(ty: Type) -> str:
    """``ty`` as a message says it: ``"a truth value"``, ``"the scale of `lvl`"``, ..."""
    if ty == BOOL:
        return "a truth value"
    if ty == NUM:
        return "a number"
    if isinstance(ty, tuple):
        return f"the scale of `{clip(ty[1])}`" if ty[0] == "scale" else f"scale literal `{clip(ty[1])}`"
    return "an unknown value"


class Expressions:
    """Types and kinds of the expressions of one specification (the declarations checked)."""

    def __init__(self, scope: Scope, legos: LegosReader) -> None:
        self.scope = scope
        self.sink = scope.sink
        self.opt = scope.opt
        self.legos = legos

    def condition(self, e: A.Expr) -> None:
        """``e`` where a truth value is needed (a trigger's or clause's condition, say)."""
        ty = self.expr(e)
        if ty is not None and ty != BOOL:
            self.sink.error("not-boolean", f"a condition must be true or false, not {type_word(ty)}", e.span)

    def expr(self, e: A.Expr) -> Type:
        """``e``'s type, every problem in it reported (None: a problem left it unknown)."""
        if isinstance(e, A.Name):
            return self._name(e)
        if isinstance(e, A.BoolLit):
            return BOOL
        if isinstance(e, A.IntLit):
            return NUM
        if isinstance(e, A.DecimalLit):
            self.sink.error(
                "decimal",
                f"`{clip(e.text)}`: SLEEC numbers are integers (no decimal literals)",
                e.span,
                hint="scale the measure, e.g. tenths of a degree",
            )
            return NUM
        if isinstance(e, A.Not):
            ty = self.expr(e.operand)
            if ty is not None and ty != BOOL:
                self.sink.error("type", f"`not` needs a truth value, not {type_word(ty)}", e.span)
            return BOOL
        if isinstance(e, A.BinOp | A.Compare) and e.op not in _OPERATORS[type(e)]:
            self.sink.error(  # only a Specification built in Python can hold one
                "malformed-expr",
                f"`{e.op}` is not a SLEEC operator; expected one of {', '.join(sorted(_OPERATORS[type(e)]))}",
                e.span,
            )
            return None
        if isinstance(e, A.BinOp):
            if e.op in A.BOOL_OPS:
                self._mixed(e)
                for side in (e.left, e.right):
                    ty = self.expr(side)
                    if ty is not None and ty != BOOL:
                        self.sink.error(
                            "type", f"`{e.op}` needs truth values, not {type_word(ty)}", side.span
                        )
                return BOOL
            for side in (e.left, e.right):
                ty = self.expr(side)
                if ty is not None and ty != NUM:
                    self.sink.error(
                        "arith-type", f"arithmetic `{e.op}` needs numbers, not {type_word(ty)}", side.span
                    )
            return NUM
        return self._compare(e)

    def const_eval(self, e: A.Expr) -> int | None:
        """``e``'s value when it is constant (numbers, constants and arithmetic on them)."""
        if isinstance(e, A.IntLit):
            return e.value
        if isinstance(e, A.Name):
            return self.scope.table.constant_values.get(e.name)
        if isinstance(e, A.BinOp) and e.op in A.ARITH_OPS:
            a, b = self.const_eval(e.left), self.const_eval(e.right)
            if a is None or b is None:
                return None
            return a + b if e.op == "+" else a - b if e.op == "-" else a * b
        return None

    def _mixed(self, e: A.BinOp) -> None:
        left = e.left
        if isinstance(left, A.BinOp) and left.op in A.BOOL_OPS and left.op != e.op and not left.parenthesized:
            msg = (
                f"`{left.op}` and `{e.op}` mixed without parentheses: read left to right as "
                f"`(... {left.op} ...) {e.op} ...`"
            )
            hint = "add parentheses to say which you mean"
            if self.opt.strict_precedence:
                self.sink.error("mixed-and-or", msg, e.span, hint=hint)
            else:
                self.sink.warning("mixed-and-or", msg, e.span, hint=hint)

    def _name(self, n: A.Name) -> Type:
        t = self.scope.table
        m = t.measures.get(n.name)
        if m is not None:
            if n.arrow:
                self.sink.error(
                    "kind",
                    f"`->{clip(n.name)}` refers to a constant, but `{clip(n.name)}` is a measure",
                    n.span,
                )
            if isinstance(m.type, A.BooleanType):
                return BOOL
            if isinstance(m.type, A.NumericType):
                return NUM
            return ("scale", n.name)
        if n.name in t.constants:
            if n.braced:
                self.sink.error(
                    "kind",
                    f"`{{{clip(n.name)}}}`: `{clip(n.name)}` is a constant; braces mark measures",
                    n.span,
                )
            return NUM
        if n.name in t.events:
            self.sink.error("not-a-measure", f"`{clip(n.name)}` is an event, not a measure", n.span)
            return None
        if n.name in self.scope.scale_literals and not n.braced and not n.arrow:
            return ("lit", n.name)
        what = "constant" if n.arrow else "measure"
        self.sink.error(
            "undeclared",
            f"`{clip(n.name)}` is not declared (expected a {what})",
            n.span,
            hint=self.scope.did_you_mean(n.name, "values", "undeclared"),
        )
        return None

    def _compare(self, e: A.Compare) -> Type:
        if self._unknown_literal(e):
            return BOOL
        lt, rt = self.expr(e.left), self.expr(e.right)
        if lt is None or rt is None:
            return BOOL
        # a scale literal takes the scale of the other side
        if isinstance(lt, tuple) and lt[0] == "lit":
            lt, rt = rt, lt
            lit_side = e.left
        else:
            lit_side = e.right
        if isinstance(rt, tuple) and rt[0] == "lit":
            self._with_literal(e, lt, rt[1], lit_side)
            return BOOL
        if lt == BOOL or rt == BOOL:
            if e.op in ("=", "<>") and lt == rt == BOOL:
                return BOOL
            self.sink.error(
                "bool-relop",
                f"`{e.op}` cannot order truth values"
                if e.op not in ("=", "<>")
                else f"`{e.op}` compares a truth value with {type_word(rt if lt == BOOL else lt)}",
                e.span,
            )
            return BOOL
        if lt != rt:
            if self.opt.legos_compat and self._scale_number(e, lt, rt):
                return BOOL
            self.sink.error("type", f"`{e.op}` compares {type_word(lt)} with {type_word(rt)}", e.span)
        return BOOL

    def _with_literal(self, e: A.Compare, lt: Type, lit: str, lit_side: A.Expr) -> None:
        """``e`` compares scale literal ``lit`` (the expression ``lit_side``) with a value of
        type ``lt``: only a measure of a scale that has ``lit`` fits."""
        if isinstance(lt, tuple) and lt[0] == "scale":
            m = self.scope.table.measures[lt[1]]
            assert isinstance(m.type, A.ScaleType)
            if lit not in m.type.literals:
                if self.opt.legos_compat and self.legos.literal(e, lit_side, lit, m.name, m.type):
                    return
                self.sink.error(
                    "scale-literal",
                    f"`{clip(lit)}` is not in the scale of `{clip(lt[1])}` "
                    f"({clip(', '.join(m.type.literals), 4 * QUOTE_LIMIT)}); "
                    f"it is a literal of `{self.scope.owners(lit)}`",
                    lit_side.span,
                    hint="scale literals belong to their measure (LEGOS-SLEEC's global "
                    "literal table lets such cross-scale comparisons through)",
                )
            return
        if isinstance(lt, tuple) and lt[0] == "lit":
            self.sink.error(
                "type", f"`{e.op}` compares two scale literals; one side must be a measure", e.span
            )
            return
        if self.opt.legos_compat and lt == NUM and self.legos.number(lit_side, lit):
            return
        self.sink.error(
            "type",
            f"scale literal `{clip(lit)}` (of `{self.scope.owners(lit)}`) compared with {type_word(lt)}",
            lit_side.span,
        )

    def _scale_number(self, e: A.Compare, lt: Type, rt: Type) -> bool:
        """A scale measure compared with a constant number: LEGOS-SLEEC's reading of it
        (:meth:`LegosReader.scale_number`); False when ``e`` is no such comparison."""
        if isinstance(lt, tuple) and lt[0] == "scale" and rt == NUM:
            measure, number, op = lt[1], e.right, e.op
        elif isinstance(rt, tuple) and rt[0] == "scale" and lt == NUM:
            measure, number, op = rt[1], e.left, mirrored(e.op)
        else:
            return False
        c = self.const_eval(number)
        if c is None:
            return False
        return self.legos.scale_number(e, measure, number, op, c)

    def _unknown_literal(self, e: A.Compare) -> bool:
        """``m op x`` with ``m`` a scale measure and ``x`` a bare name declared nowhere, not
        even as a literal of another scale: ``x`` can only be a literal of ``m``'s scale, so
        report it as one that is not, listing that scale (and the closest literal)."""
        t = self.scope.table
        for side, other in ((e.left, e.right), (e.right, e.left)):
            if not (isinstance(side, A.Name) and isinstance(other, A.Name)):
                continue
            m = t.measures.get(side.name)
            if m is None or not isinstance(m.type, A.ScaleType) or other.braced or other.arrow:
                continue
            lit = other.name
            if lit in self.scope.scale_literals or t.kind(lit) is not None:
                continue
            self.expr(side)  # the measure's own checks (`->m`)
            literals = m.type.literals
            close = closest(lit, literals)
            shown = ", ".join(literals)
            self.sink.error(
                "scale-literal",
                f"`{clip(lit)}` is not in the scale of `{clip(m.name)}` ({clip(shown, 4 * QUOTE_LIMIT)})",
                other.span,
                hint=f"did you mean `{clip(close)}`?"
                if close
                else f"compare `{clip(m.name)}` with one of its literals: {clip(shown, 4 * QUOTE_LIMIT)}",
            )
            return True
        return False


__all__ = ["BOOL", "NUM", "Expressions", "Type", "type_word"]
