"""When a response, started at a slot, is met: its obligations and prohibitions, its chosen
clause, ``otherwise`` and ``else`` (for :mod:`cosleec.analysis.encoding`).

An obligation is met by a present occurrence of its event in its window (windows.py), after
the step that raised it, unless a prohibition refuses it (refusals.py); a prohibition by
none. An ``otherwise`` starts at the deadline it follows, at the first occurrence that breaks
its prohibition, or at a refusal, and reads the values of that moment (a
:class:`~cosleec.analysis.slots.Fallback` snapshot, which the relations constrain too).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator

import z3

from cosleec.analysis.priorities import Priorities
from cosleec.analysis.refusals import Owed, Refusal, Refusals
from cosleec.analysis.relations import Relations
from cosleec.analysis.slots import Z3, After, Cut, Fallback, Slot, Step, before
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.analysis.windows import Windows
from cosleec.lang import ast as A


class Obligations:
    """The responses of one encoding's rules over its slots, read as its reading says; the
    snapshots of the ``otherwise`` responses encoded so far are the state's ``fallbacks``."""

    def __init__(
        self,
        state: State,
        terms: Terms,
        windows: Windows,
        relations: Relations,
        refusals: Refusals,
        priorities: Priorities,
    ) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms
        self.windows = windows
        self.relations = relations
        self.refusals = refusals
        self.priorities = priorities

    def rule_holds(self, rule: A.Rule, x: Slot) -> Z3:
        """``rule`` is met at slot ``x``: if ``x`` is present and triggers it, its response holds
        (up to the moment a declared priority cancels that firing)."""
        fires = z3.And(x.present, self.terms.truth(rule.trigger.condition, x.snap))
        self.state.imposed = True  # its prohibitions inside an otherwise refuse (refusals.py)
        try:
            with self.priorities.firing(rule, x, record=True):
                return z3.Implies(fires, self.holds(rule.response, x, guard=fires))
        finally:
            self.state.imposed = False

    def holds(
        self,
        response: A.Response | None,
        x: Slot,
        *,
        untimed: float | str | None = "reading",
        guard: Z3 | None = None,
        situation: bool = False,
        rule: A.Rule | None = None,
    ) -> Z3:
        """``response``, started by slot ``x``, is met (``untimed`` overrides the reading's).
        ``guard`` says when the response is in force (default: when ``x`` is present): an
        ``otherwise`` counts as started only then (:attr:`Fallback.started`). A
        ``situation`` (a concern's or purpose's response) describes what occurs, not what a
        rule owes: no prohibition refuses it. ``rule``: the response is that rule's firing at
        ``x`` (a declared priority may cancel it, and no rule refuses it that a priority orders
        with it)."""
        if rule is not None:
            with self.priorities.firing(rule, x, record=False):
                return self.holds(response, x, untimed=untimed, guard=guard, situation=situation)
        u = self.state.reading.untimed_seconds if untimed == "reading" else untimed
        assert not isinstance(u, str)
        self.state.guard = x.present if guard is None else guard
        self.state.situation = situation
        try:
            return self._response(response, x.t, After(slot=x), x.snap, u)
        finally:
            self.state.situation = False

    @contextlib.contextmanager
    def _fallback_of(self, refusal: Refusal | None) -> Iterator[None]:
        """Encode an ``otherwise`` (of an obligation ``refusal`` may refuse; None: of a prohibition)."""
        self.state.within.append(refusal)
        try:
            yield
        finally:
            self.state.within.pop()

    @contextlib.contextmanager
    def _within(self, condition: Z3) -> Iterator[None]:
        """Encode under ``condition`` too (a clause chosen, a primary missed)."""
        outer = self.state.guard
        self.state.guard = z3.And(outer, condition)
        try:
            yield
        finally:
            self.state.guard = outer

    def _response(
        self,
        resp: A.Response | None,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        if resp is None:
            return z3.BoolVal(True, self.state.ctx)
        if not resp.defeaters:
            items = z3.And(
                *(self._item(it, start, after, snap, untimed) for it in resp.items), self.state.ctx
            )
            known = self.windows.in_range(resp, snap)
            return items if known is None else z3.Or(z3.Not(known), items)
        conds = self.terms.chosen(resp.defeaters, snap)
        parts = []
        for sub, cond in zip([A.Response(resp.items), *(d.response for d in resp.defeaters)], conds):
            self.terms.on_time()  # a rule of thousands of clauses takes seconds to encode
            with self._within(cond):
                parts.append(z3.Implies(cond, self._response(sub, start, after, snap, untimed)))
        return z3.And(*parts, self.state.ctx)

    def _item(
        self,
        it: A.ResponseItem,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        """One item of a response: a prohibition (with its ``otherwise``: the first occurrence
        that breaks it starts the fallback), or an obligation (with its ``else`` and
        ``otherwise``). What this frame holds, and so the order it lets go of it in, is as it
        has always been (state.py says why that order matters)."""
        occ = it.occurrence
        lo, hi = self.windows.window(occ, it.otherwise is not None, start, snap, untimed)
        noted = self.priorities.note(it, lo, hi, start, after)
        cut = None if self.state.situation else self.state.cut
        if occ.negated:
            if self.state.imposed and self.state.within and not self.state.situation:
                self.refusals.raise_in_fallback(it, lo, hi, after.step, snap)  # type: ignore[attr-defined]
            counts = after if cut is None else _BeforeCut(after, cut)
            ok = z3.Not(self.windows.occurs(occ.event, lo, hi, counts))
            if it.otherwise is None:
                return ok
            breaks = [
                (y, z3.And(y.present, lo <= y.t, *([y.t <= hi] if hi is not None else []), counts(y)))
                for y in self.state.by_event.get(occ.event, ())
            ]
            firsts = []
            for y, by in breaks:
                first = z3.And(by, *(z3.Not(z3.And(bz, before(z, y))) for (z, bz) in breaks if z is not y))
                with self._within(first), self._fallback_of(None):
                    fallback = self._response(it.otherwise, y.t, After(slot=y), y.snap, untimed)
                firsts.append(z3.And(first, fallback))
            return z3.Or(ok, *firsts)
        ok = self.windows.occurs(occ.event, lo, hi, after)
        if it.alternative is not None:
            ok = z3.Or(ok, self._branch(it.alternative, start, after, snap, untimed))
        if it.otherwise is None and it.alternative is None and hi is not None and not self.state.situation:
            # refused at once by a prohibition that covers its whole window: a breach, even if
            # the event then occurs (breaking that prohibition, whose own otherwise may be met)
            refusal = self.refusals.refusal(Owed(occ.event, lo, hi, start, after, snap))
            if noted is not None:
                noted.refusal = refusal
            if refusal is not None:
                ok = z3.And(z3.Not(refusal.refused), ok)
            if cut is not None:
                ok = z3.Or(ok, self._saved(cut, lo, hi, refusal))
        elif cut is not None and (it.otherwise is None or hi is None):
            ok = z3.Or(ok, cut.saves(lo, hi))
        if it.otherwise is not None and hi is not None:
            ok, at, refusal, fb = self._fallback_start(it, ok, lo, hi, start, after, snap)
            if noted is not None:
                noted.refusal = refusal
            later = _FallbackStart(at, hi < lo, after, refusal)
            with self._within(z3.Not(ok)), self._fallback_of(refusal):
                fallback = self._response(it.otherwise, at, later, fb.snap, untimed)
            ok = z3.Or(ok, fallback)
        return ok

    def _fallback_start(
        self,
        it: A.ResponseItem,
        ok: Z3,
        lo: Z3,
        hi: Z3,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
    ) -> tuple[Z3, Z3, Refusal | None, Fallback]:
        """Where the ``otherwise`` of an obligation (met when ``ok``) starts: at its deadline,
        or at once when a prohibition refuses the obligation, which ``ok`` then also needs not
        to be -> (ok, the start, the refusal, the snapshot the fallback reads)."""
        terms = self.terms
        at = z3.If(hi < lo, start, hi)
        fresh = {m: terms.var(m, f"o{terms.fresh_number()}") for m in self.state.measures}
        refusal = (
            self.refusals.refusal(Owed(it.occurrence.event, lo, hi, start, after, snap), moment=True)
            if it.alternative is None and not self.state.situation  # an `else` may still meet it
            else None
        )
        if refusal is not None:  # refused: its fallback starts then, not at the deadline
            ok = z3.And(z3.Not(refusal.refused), ok)
            at = z3.If(refusal.refused, refusal.when, at)
            self.refusals.read_into(refusal, fresh)
        if self.state.cut is not None and not self.state.situation:  # cancelled first: no fallback
            ok = z3.Or(ok, self._saved(self.state.cut, lo, hi, refusal))
        return ok, at, refusal, self._fallback(at, z3.And(self.state.guard, z3.Not(ok)), fresh)

    def _saved(self, cut: Cut, lo: Z3, hi: Z3, refusal: Refusal | None) -> Z3:
        """A declared priority cancels the firing while the obligation's window ``[lo, hi]`` is
        open, and no later than a prohibition refuses it (a refusal is a breach already; at the
        same step, the cancellation comes first)."""
        if refusal is None:
            return cut.saves(lo, hi)
        by = cut.by(refusal.when) if refusal.step is None else cut.by_step(refusal.step)
        return z3.And(cut.saves(lo, hi), z3.Or(z3.Not(refusal.refused), by))

    def _fallback(self, at: Z3, started: Z3, snap: dict[str, Z3]) -> Fallback:
        """A new fallback snapshot, read at ``at`` when ``started``: in its measures' domains,
        the same values as any other fallback started at that instant, the relations on it."""
        fb = Fallback(at, started, snap)
        self.terms.domain(fb.snap)
        for other in self.state.fallbacks:
            self.state.solver.add(
                z3.Implies(
                    z3.And(fb.started, other.started, fb.at == other.at),
                    z3.And(*(fb.snap[m] == other.snap[m] for m in self.state.measures), self.state.ctx),
                )
            )
        for lit, rel in zip(self.state.relation_lit, self.state.spec.relations):
            on_fallback = self.relations.on_fallback(rel, fb)
            if on_fallback is not None:
                self.state.solver.add(z3.Implies(lit, on_fallback))
        self.state.fallbacks.append(fb)
        return fb

    def _branch(
        self,
        resp: A.Response,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        """An ``else`` alternative: every item of its chosen clause occurs in its own window."""
        if resp.defeaters:
            conds = self.terms.chosen(resp.defeaters, snap)
            parts = [z3.Implies(conds[0], self._branch(A.Response(resp.items), start, after, snap, untimed))]
            for d, cond in zip(resp.defeaters, conds[1:]):
                sub = d.response
                parts.append(
                    z3.Implies(
                        cond,
                        z3.BoolVal(False, self.state.ctx)
                        if sub is None
                        else self._branch(sub, start, after, snap, untimed),
                    )
                )
            return z3.And(*parts, self.state.ctx)
        out = []
        for it in resp.items:
            if it.occurrence.negated:
                return z3.BoolVal(False, self.state.ctx)
            lo, hi = self.windows.window(it.occurrence, it.otherwise is not None, start, snap, untimed)
            out.append(self.windows.occurs(it.occurrence.event, lo, hi, after))
        return z3.And(*out, self.state.ctx) if out else z3.BoolVal(False, self.state.ctx)


class _BeforeCut:
    """Which occurrences break a prohibition of a firing a priority may cancel: those after
    its raising step (``after``) and not after the cancellation."""

    def __init__(self, after: Callable[[Slot], Z3], cut: Cut) -> None:
        self.after, self.cut = after, cut

    def __call__(self, y: Slot) -> Z3:
        """``y`` can break the prohibition."""
        return z3.And(self.after(y), z3.Not(self.cut.spares(y)))


class _FallbackStart:
    """Which occurrences count for an ``otherwise``: strictly after the deadline it follows;
    after the step that raised the obligation when its window closed at once (a negative
    deadline); after the refusing step when a prohibition refused the obligation (the step
    that raised the later of the two: the reference starts the fallback there)."""

    def __init__(
        self, at: Z3, closed_at_once: Z3, creation: Callable[[Slot], Z3], refusal: Refusal | None
    ) -> None:
        self.at, self.closed_at_once, self.creation = at, closed_at_once, creation
        self.refusal = refusal

    def __call__(self, y: Slot) -> Z3:
        """``y`` comes after the fallback's start."""
        plain = z3.If(self.closed_at_once, self.creation(y), y.t > self.at)
        if self.refusal is None:
            return plain
        assert self.refusal.step is not None  # asked for (Obligations._fallback_start)
        return z3.If(self.refusal.refused, self.refusal.step.follows(y), plain)

    @functools.cached_property
    def step(self) -> Step:
        """The moment the fallback starts (:class:`~cosleec.analysis.slots.Step`)."""
        ctx = self.at.ctx
        deadline = Step(self.at, z3.IntVal(0, ctx), z3.BoolVal(True, ctx))
        plain = Step.choose(self.closed_at_once, self.creation.step, deadline)  # type: ignore[attr-defined]
        if self.refusal is None:
            return plain
        assert self.refusal.step is not None
        return Step.choose(self.refusal.refused, self.refusal.step, plain)


__all__ = ["Obligations"]
