"""Declared priorities: when a firing of a higher rule cancels one of a lower rule (for
:mod:`cosleec.analysis.encoding`).

The meaning is the reference semantics' (:mod:`cosleec.semantics.reference`, language
reference, docs/reference/sleec-language.md §13): with ``H > L`` (closed transitively), an *instance* -- one firing of a rule --
is active while one of its items (``otherwise`` included) is pending.

cancel
    when an instance of H and one of L are active together, the L instance is cancelled at
    once. An instance's activity has no gaps (an ``otherwise`` starts when its item is
    settled), so that happens at the later of the two firings: at H's firing when L's
    instance is still active then (cancelling an instance with nothing pending changes
    nothing, so the encoding need not ask), at L's firing when H's is.
conflict-aware
    L is kept as long as possible: it is cancelled at the deadline ``d`` of an obligation that
    one of the two owes and the other's prohibition forbids at ``d`` (minus the reading's
    ``priority_lead``, no earlier than the two windows allow), both still pending then, before
    anything else happens at that instant -- or, when the later of the two is raised at that
    instant, right after the step that raises it. An obligation a third rule's prohibition
    refused before then (blocked: no longer pending) forces nothing.

Each lower rule's firing at a slot has a :class:`~cosleec.analysis.slots.Cut`: the earliest
moment some higher firing cancels it. :class:`~cosleec.analysis.obligations.Obligations`
reads the cut while it encodes the firing (an occurrence after it breaks no prohibition; an
obligation whose window is open then is not broken; no ``otherwise`` starts after it), and
records what each firing of an ordered rule raises (:class:`~cosleec.analysis.slots.Raised`);
:meth:`Priorities.settle` then defines each cut from those records. The unfolding offers,
for each firing of a lower rule, an occurrence that triggers each higher rule (what may
cancel it). Known simplifications: an item with an ``else`` counts as pending by its own
window only, and under cancel a refused obligation as pending until its deadline (under
conflict-aware, an obligation refused before its clash is forced forces nothing:
``_refused_first``); under cancel, when a higher firing is itself cancelled at the moment it
fires, it is still taken to cancel the lower one; under conflict-aware, a cancellation forced
at the very instant the later of its two items was raised is judged after that step (what
came before it at that instant settles the two items first, as in the reference), but it
spares the instance's other prohibitions from the start of that instant, where the reference
lets steps before the raising one break them; and firings at one step are taken together,
where the reference fires them in file order (a lower rule's prohibition that refuses an
obligation before a higher rule later in the file cancels it is taken as cancelled first).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

import z3

from cosleec.analysis.slots import Z3, After, Cut, Raised, Slot, before
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.lang import CONFLICT_AWARE
from cosleec.lang import ast as A

Case = tuple[Z3, Z3, Z3 | None]
"""A way a firing can be cancelled: (condition, time, position of the cancelling step)."""


class Priorities:
    """The cancellations of one encoding's firings (nothing when no priority is declared)."""

    def __init__(self, state: State, terms: Terms) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms

    @property
    def aware(self) -> bool:
        """Conflict-aware semantics (else cancel)."""
        return self.state.reading.priority_semantics == CONFLICT_AWARE

    def ordered(self, a: str, b: str) -> bool:
        """A declared priority orders rules ``a`` and ``b`` (either way)."""
        return (a, b) in self.state.above or (b, a) in self.state.above

    def higher(self, rule: str) -> list[A.Rule]:
        """The rules above ``rule``, in file order."""
        if not self.state.above:
            return []
        return [r for r in self.state.spec.rules if (r.name, rule) in self.state.above]

    def prepare(self, slots: list[Slot]) -> None:
        """A cut for every firing of a lower rule the slots can make (before any rule is encoded)."""
        if not self.state.above:
            return
        lows = {low for _, low in self.state.above}
        for x in slots:
            for r in self.state.rules_by_event.get(x.event, ()):
                if r.name in lows:
                    n = self.terms.fresh_number()
                    self.state.cuts[(r.name, x.id)] = Cut(
                        z3.Bool(f"cancelled{n}", self.state.ctx),
                        z3.Real(f"cancelled_at{n}", self.state.ctx),
                        None if self.aware else z3.Int(f"cancelled_pos{n}", self.state.ctx),
                    )

    @contextlib.contextmanager
    def firing(self, rule: A.Rule, x: Slot, *, record: bool) -> Iterator[None]:
        """Encode ``rule``'s firing at ``x``: its cut applies, and (``record``) what it raises is
        recorded when a priority orders the rule."""
        outer = (self.state.rule, self.state.firing, self.state.cut)
        self.state.rule = rule.name
        self.state.cut = self.state.cuts.get((rule.name, x.id))
        ordered = any(rule.name in pair for pair in self.state.above)
        self.state.firing = (rule.name, x.id) if record and ordered else None
        try:
            yield
        finally:
            self.state.rule, self.state.firing, self.state.cut = outer

    def note(self, it: A.ResponseItem, lo: Z3, hi: Z3 | None, start: Z3, after: object) -> Raised | None:
        """Record an item the firing being encoded raises (when a priority orders its rule);
        the record, for its refusal to be added once asked for."""
        if self.state.firing is None:
            return None
        raised = Raised(it.occurrence, lo, hi, start, after, self.state.guard, it.alternative is None)
        self.state.raised.setdefault(self.state.firing, []).append(raised)
        return raised

    # ------------------------------------------------------------------ the cuts
    def settle(self) -> None:
        """Define every cut: cancelled exactly when some case holds, at the earliest one."""
        by_id = {s.id: s for s in self.state.slots}
        for (low, xid), cut in self.state.cuts.items():
            self.terms.on_time()
            x = by_id[xid]
            cases = list(self._aware_cases(low, x) if self.aware else self._cancel_cases(low, x))
            self._define(cut, cases)

    def _define(self, cut: Cut, cases: list[Case]) -> None:
        solver = self.state.solver
        if not cases:
            solver.add(z3.Not(cut.cancelled))
            return
        solver.add(cut.cancelled == z3.Or(*(c for c, _, _ in cases)))
        for c, t, pos in cases:
            solver.add(z3.Implies(c, cut.by(t, pos)))
        solver.add(
            z3.Implies(
                cut.cancelled,
                z3.Or(
                    *(
                        z3.And(c, cut.at == t, *([cut.pos == pos] if cut.pos is not None else []))
                        for c, t, pos in cases
                    )
                ),
            )
        )

    def _cancel_cases(self, low: str, x: Slot) -> Iterator[Case]:
        """Cancel semantics: a higher firing at the same step, or before ``x`` and still active
        then (``x`` is cancelled at once), or after ``x`` (``x`` cancelled then)."""
        for high in self.higher(low):
            for y in self.state.by_event.get(high.trigger.event, ()):
                fires = self._has_items(high.name, y)
                if y is x:
                    if high.name != low:
                        yield fires, x.t, x.pos
                    continue
                yield z3.And(fires, before(y, x), self._active(high.name, y, x)), x.t, x.pos
                yield z3.And(fires, before(x, y)), y.t, y.pos

    def _has_items(self, rule: str, y: Slot) -> Z3:
        """``rule`` fires at ``y`` with an item pending (a window that does not close before it opens)."""
        top = [
            z3.And(r.guard, *([r.lo <= r.hi] if r.hi is not None else []))
            for r in self.state.raised.get((rule, y.id), ())
            if isinstance(r.after, After) and r.after.slot is y
        ]
        return z3.Or(*top, self.state.ctx)

    def _active(self, rule: str, y: Slot, x: Slot) -> Z3:
        """``rule``'s firing at ``y`` still has an item pending at the step of ``x`` (after what
        ``x``'s occurrence settles), and no cancellation came first."""
        pending = []
        for r in self.state.raised.get((rule, y.id), ()):
            settled = self._settled(r, lambda z: z3.Or(z3.BoolVal(z is x, self.state.ctx), before(z, x)))
            still = [x.t <= r.hi, r.lo <= r.hi] if r.hi is not None else []
            pending.append(z3.And(r.guard, r.after(x), *still, z3.Not(settled)))
        cut = self.state.cuts.get((rule, y.id))
        alive = [z3.Not(cut.by(x.t, x.pos))] if cut is not None else []
        return z3.And(*alive, z3.Or(*pending, self.state.ctx))

    def _settled(self, r: Raised, first: Callable[[Slot], Z3]) -> Z3:
        """An occurrence in ``r``'s window after its raising step, and ``first(occurrence)``:
        fulfils ``r`` (an obligation) or breaks it (a prohibition)."""
        return z3.Or(
            *(
                z3.And(
                    z.present,
                    r.lo <= z.t,
                    *([z.t <= r.hi] if r.hi is not None else []),
                    r.after(z),
                    first(z),
                )
                for z in self.state.by_event.get(r.occurrence.event, ())
            ),
            self.state.ctx,
        )

    def _aware_cases(self, low: str, x: Slot) -> Iterator[Case]:
        """Conflict-aware semantics: an obligation of one of the two firings that the other's
        prohibition forbids at its deadline, both pending until then."""
        mine = self.state.raised.get((low, x.id), [])
        for high in self.higher(low):
            for y in self.state.by_event.get(high.trigger.event, ()):
                if y is x and high.name == low:
                    continue
                theirs = self.state.raised.get((high.name, y.id), [])
                other = self.state.cuts.get((high.name, y.id))
                for owes, bans in ((theirs, mine), (mine, theirs)):
                    for o in owes:
                        for p in bans:
                            if self._clash(o, p):
                                yield self._forced(o, p, other)

    @staticmethod
    def _clash(o: Raised, p: Raised) -> bool:
        """``o`` is an obligation with a deadline and no ``else``, ``p`` a prohibition of its event."""
        return (
            not o.occurrence.negated
            and o.plain
            and o.hi is not None
            and p.occurrence.negated
            and p.occurrence.event == o.occurrence.event
        )

    @staticmethod
    def _precedes(at: Z3, other: Raised) -> Callable[[Slot], Z3]:
        """Which occurrences come before a cancellation at ``at`` forced by a clash with
        ``other``: those before ``at``, and those at ``at`` not after the step that raised
        ``other`` -- when the later of the two items is raised at ``at`` itself, the reference
        finds the clash once that step is over, so what came before it at that instant (an
        obligation met, a prohibition broken) counts first."""
        return lambda z: z3.Or(z.t < at, z3.And(z.t == at, z3.Not(other.after(z))))

    @staticmethod
    def _open(r: Raised, other: Raised, at: Z3) -> Z3:
        """``r``'s window has not closed when its clash with ``other`` is forced at ``at``: it
        has, when ``r``'s window ends at ``at`` and ``other`` is an ``otherwise`` that starts
        there once time has passed a deadline -- the reference closes every window that ends
        at an instant before the fallbacks of those misses start."""
        if r.hi is None:
            return z3.BoolVal(True, at.ctx)
        step = other.after.step  # the moment the firing or fallback raising ``other`` starts
        return z3.Not(z3.And(step.late, step.t == at, r.hi == at))

    @staticmethod
    def _refused_first(o: Raised, p: Raised, at: Z3) -> Z3:
        """A third rule's prohibition refused ``o`` before its clash with ``p`` is forced at
        ``at``: the reference then holds ``o`` blocked (no longer pending), so nothing is
        cancelled for it. Before: at an earlier time, or at ``at`` at a step not after both
        raising steps (the clash is found once the later of the two is raised, a refusal at
        that step or before it comes first; raised earlier, the cancellation comes first)."""
        r = o.refusal
        if r is None:
            return z3.BoolVal(False, at.ctx)
        assert r.step is not None  # always said when priorities are declared (Refusals.refusal)
        later = z3.And(r.step.after(o.after.step), r.step.after(p.after.step))
        return z3.And(r.refused, z3.Or(r.when < at, z3.And(r.when == at, z3.Not(later))))

    def _forced(self, o: Raised, p: Raised, other: Cut | None) -> Case:
        """The cancellation ``p`` forbidding ``o`` at its deadline forces, and when."""
        d = o.hi
        assert d is not None  # _clash: an obligation with a deadline
        at = d - self.state.reading.priority_lead
        at = z3.If(at >= o.start, at, o.start)
        at = z3.If(at >= p.lo, at, p.lo)
        cond = z3.And(
            o.guard,
            p.guard,
            o.lo <= d,
            p.lo <= d,
            *([d <= p.hi] if p.hi is not None else []),
            z3.Not(self._settled(o, self._precedes(at, p))),
            z3.Not(self._settled(p, self._precedes(at, o))),
            z3.Not(self._refused_first(o, p, at)),
            self._open(o, p, at),
            self._open(p, o, at),
            *([z3.Not(z3.And(other.cancelled, other.at < at))] if other is not None else []),
        )
        return cond, at, None


__all__ = ["Priorities"]
