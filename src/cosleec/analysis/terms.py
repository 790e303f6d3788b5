"""Conditions, numbers and clause choices as z3 terms over one snapshot (for :mod:`cosleec.analysis.encoding`).

A snapshot is the measure values one occurrence reads, a variable per measure: a truth value
for a boolean measure, a real for a numeric one (as at run time), an integer position for a
scale one. :class:`Terms` builds each condition and clause choice on a snapshot once (a
question asks a trigger's condition several times), and hands out the encoding's fresh names.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import z3

from cosleec.analysis.slots import Z3, Slot
from cosleec.analysis.state import State
from cosleec.lang import HedgeSemantics, visit
from cosleec.lang import ast as A


class Terms:
    """The z3 terms of one encoding, in its context and solver: the measures' variables,
    conditions and numbers on a snapshot, the clause an ``unless`` chain chooses (under the
    reading's semantics, by default), whether a slot triggers a rule, and fresh names."""

    def __init__(self, state: State) -> None:
        self.state = state  # all it holds (state.py says why)

    # ------------------------------------------------------------------ names and variables
    def fresh(self, name: str) -> Z3:
        """A new assumption literal."""
        return z3.Bool(f"{name}!{self.fresh_number()}", self.state.ctx)

    def fresh_number(self) -> int:
        """The next number of the encoding's fresh names (literals, snapshots, instants)."""
        return next(self.state.fresh)

    def on_time(self) -> None:
        """Stop building once the run's deadline has passed (:class:`OutOfTime`)."""
        if self.state.deadline is not None:
            self.state.deadline.check()

    def var(self, measure: str, prefix: str) -> Z3:
        """A variable for ``measure`` in the snapshot named ``prefix``."""
        t = self.state.measures[measure]
        name = f"{prefix}!{measure}"
        if isinstance(t, A.BooleanType):
            return z3.Bool(name, self.state.ctx)
        if isinstance(t, A.ScaleType):
            return z3.Int(name, self.state.ctx)
        return z3.Real(name, self.state.ctx)

    def domain(self, snap: dict[str, Z3]) -> None:
        """Bound each scale measure of ``snap`` to the positions of its scale."""
        for m, v in snap.items():
            t = self.state.measures[m]
            if isinstance(t, A.ScaleType):
                self.state.solver.add(v >= 0, v < len(t.literals))

    # ------------------------------------------------------------------ expressions
    def truth(self, e: A.Expr | None, snap: dict[str, Z3]) -> Z3:
        """The condition ``e`` on a snapshot (None: true); built once per condition and
        snapshot (a question asks a trigger's condition several times)."""
        if e is None:
            return z3.BoolVal(True, self.state.ctx)
        key = (id(e), id(snap))
        known = self.state.truths.get(key)
        if known is None:
            known = self.state.truths[key] = (e, snap, self._truth(e, snap))  # the keys' objects kept alive
        return known[2]

    def _truth(self, e: A.Expr, snap: dict[str, Z3]) -> Z3:
        if isinstance(e, A.BoolLit):
            return z3.BoolVal(e.value, self.state.ctx)
        if isinstance(e, A.Name):
            return snap[e.name]
        if isinstance(e, A.Not):
            return z3.Not(self.truth(e.operand, snap))
        if isinstance(e, A.BinOp) and e.op in ("and", "or"):
            # a chain read as one n-ary term, without recursion: a generated condition of
            # 50,000 terms is as deep (issue 28), and so would the z3 term be
            parts = [self.truth(t, snap) for t in visit.terms(e)]
            return z3.And(*parts) if e.op == "and" else z3.Or(*parts)
        if isinstance(e, A.Compare):
            if self._boolean(e.left) or self._boolean(e.right):
                a, b = self.truth(e.left, snap), self.truth(e.right, snap)
            else:
                scale = self._scale(e.left) or self._scale(e.right)
                a, b = self.value(e.left, snap, scale), self.value(e.right, snap, scale)
            return {
                "<": lambda: a < b,
                "<=": lambda: a <= b,
                ">": lambda: a > b,
                ">=": lambda: a >= b,
                "=": lambda: a == b,
                "<>": lambda: a != b,
            }[e.op]()
        raise AssertionError(f"not a condition: {e!r}")

    def value(self, e: A.Expr, snap: dict[str, Z3], scale: A.ScaleType | None = None) -> Z3:
        """A numeric (or scale position) expression on a snapshot."""
        if isinstance(e, A.IntLit):
            return (
                z3.IntVal(e.value, self.state.ctx)
                if scale is not None
                else z3.RealVal(e.value, self.state.ctx)
            )
        if isinstance(e, A.Name):
            if e.name in self.state.measures:
                return snap[e.name]
            if e.name in self.state.constants:
                v = self.state.constants[e.name]
                return z3.IntVal(v, self.state.ctx) if scale is not None else z3.RealVal(v, self.state.ctx)
            if scale is not None and e.name in scale.literals:
                return z3.IntVal(scale.literals.index(e.name), self.state.ctx)
            raise AssertionError(f"unresolved name {e.name!r}")
        if isinstance(e, A.BinOp) and e.op in ("+", "-", "*"):
            a, b = self.value(e.left, snap, scale), self.value(e.right, snap, scale)
            return a + b if e.op == "+" else a - b if e.op == "-" else a * b
        raise AssertionError(f"not a number: {e!r}")

    def _boolean(self, e: A.Expr) -> bool:
        if isinstance(e, A.BoolLit | A.Not | A.Compare):
            return True
        if isinstance(e, A.BinOp):
            return e.op in ("and", "or")
        return isinstance(e, A.Name) and isinstance(self.state.measures.get(e.name), A.BooleanType)

    def _scale(self, e: A.Expr) -> A.ScaleType | None:
        if isinstance(e, A.Name):
            t = self.state.measures.get(e.name)
            if isinstance(t, A.ScaleType):
                return t
        return None

    def fires(self, rule: A.Rule, x: Slot) -> Z3:
        """``x`` is present and triggers ``rule``."""
        return z3.And(x.present, self.truth(rule.trigger.condition, x.snap))

    def seconds(self, d: A.Duration, snap: dict[str, Z3]) -> Z3:
        """A duration in seconds."""
        return self.value(d.value, snap) * A.TIME_UNITS.get(d.unit.lower(), 1)

    # ------------------------------------------------------------------ clause choice
    def chosen(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], semantics: HedgeSemantics | None = None
    ) -> list[Z3]:
        """For each clause (0: the default), the condition under which it applies (under
        ``semantics``, by default the reading's); built once per clause list and snapshot.

        Linear in the clauses (issue 28): what clause ``i`` needs besides its own condition --
        that no later condition holds (last-wins), or that every earlier one does (nested) --
        is one literal per clause, defined from its neighbour's (:meth:`_chain`), where
        spelling each out made the choice among ``k`` clauses ``k**2`` terms."""
        sem = semantics or self.state.reading.semantics
        key = (id(defeaters), id(snap), sem)
        known = self.state.choices.get(key)
        if known is not None:
            return known[2]
        c = [self.truth(d.condition, snap) for d in defeaters]
        k = len(c)
        if sem == HedgeSemantics.LAST_WINS:
            none_from = self._chain([z3.Not(x) for x in c], "none")  # no condition i.. holds
            out = [none_from[0]] + [z3.And(c[i], none_from[i + 1]) for i in range(k)]
        else:
            every = self._chain(c[::-1], "all")[::-1]  # every[i]: conditions 0..i-1 all hold
            out = [z3.Not(c[0])] if c else [z3.BoolVal(True, self.state.ctx)]
            out += [z3.And(every[i + 1], z3.Not(c[i + 1])) if i + 1 < k else every[k] for i in range(k)]
        self.state.choices[key] = (defeaters, snap, out)  # the keys' objects kept alive: ids stay theirs
        return out

    def _chain(self, parts: list[Z3], name: str) -> list[Z3]:
        """``v`` with ``v[i]`` equivalent to ``And(parts[i:])`` (``v[len(parts)]`` true): each a
        fresh literal defined as its part and the next one, so the chain is linear in size and
        one level deep in z3 whatever its length."""
        v = [z3.BoolVal(True, self.state.ctx)]
        for p in reversed(parts):
            self.on_time()
            lit = self.fresh(name)
            self.state.solver.add(lit == z3.And(p, v[-1]))
            v.append(lit)
        return v[::-1]

    def chosen_at(self, response: A.Response, clause: int, snap: dict[str, Z3]) -> Z3:
        """Clause ``clause`` of ``response`` applies on ``snap``."""
        return self.chosen(response.defeaters, snap)[clause]

    def each_clause(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], ask: Callable[[int, Z3], None]
    ) -> None:
        """``ask(k, applies)`` for every clause ``k`` (0: the default), where ``applies`` is,
        while ``ask`` runs, what it takes for clause ``k`` to apply on ``snap`` under the
        reading's semantics. One question per clause in linear time (issue 28): what the
        other clauses must not do is asserted as the walk goes, in a solver scope closed
        after -- from the last clause back under last-wins (its condition does not hold),
        from the first on under nested (it does) -- rather than spelled out per question.
        ``ask`` asks and builds nothing that adds to the solver (:meth:`chosen` does): what it
        added would go with the scope."""
        c = [self.truth(d.condition, snap) for d in defeaters]
        true = z3.BoolVal(True, self.state.ctx)
        self.state.solver.push()
        try:
            if self.state.reading.semantics == HedgeSemantics.LAST_WINS:
                for k in range(len(c), -1, -1):
                    ask(k, c[k - 1] if k else true)
                    if k:
                        self.state.solver.add(z3.Not(c[k - 1]))
            else:
                for k in range(len(c) + 1):
                    ask(k, z3.Not(c[k]) if k < len(c) else true)
                    if k < len(c):
                        self.state.solver.add(c[k])
        finally:
            self.state.solver.pop()


def as_float(v: Z3) -> float:
    """A z3 numeral (integer, rational, or an algebraic number rounded) as a float: the one
    reading of a model's numbers, for witnesses, situations and range checks."""
    if z3.is_int_value(v):
        return float(v.as_long())
    if z3.is_rational_value(v):
        return float(v.numerator_as_long()) / float(v.denominator_as_long())
    if z3.is_algebraic_value(v):
        return float(v.approx(12).as_decimal(12).rstrip("?"))
    raise ValueError(f"not a number: {v}")


__all__ = ["Terms", "as_float"]
