"""What the relation block (LEGOS-SLEEC's assumptions about the world) says of a trace, in z3.

Relations hold in every question, each guarded by its own literal so that an unsat core can
name it (``relation N``). Event relations tie occurrences together (``witness``, ``equal``,
``mutualExclusive``, ``happenBefore``); measure relations constrain every snapshot, and so
the values an ``otherwise`` reads; ``causation``, ``includes`` and ``forbid`` tie an event to
a condition; ``until`` and ``for`` keep a condition true after a trigger
(docs/reference/sleec-language.md §9.2).
"""

from __future__ import annotations

from collections.abc import Iterator

import z3

from cosleec.analysis.slots import Z3, After, Fallback, Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.lang import ast as A


class Relations:
    """The relations of one encoding over its slots, each guarded by its relation literal."""

    def __init__(self, state: State, terms: Terms) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms

    def holds(self, rel: A.Relation) -> Z3:
        """``rel`` holds of every slot (the unfolding done)."""
        if isinstance(rel, A.EventRelation):
            return self._events(rel)
        if isinstance(rel, A.MeasureRelation):
            return z3.And(
                *(z3.Implies(s.present, self.on_snapshot(rel, s.snap)) for s in self.state.slots),
                self.state.ctx,
            )
        if isinstance(rel, A.EventMeasureRelation):
            return self._event_condition(rel)
        if isinstance(rel, A.UntilRelation):
            return self._until(rel)
        if isinstance(rel, A.ForRelation):
            return self._for(rel)
        raise AssertionError(f"unknown relation {rel!r}")

    def demands(self, event: str) -> Iterator[tuple[str, str]]:
        """The events the relations can need beside an occurrence of ``event``, with why:
        its witness or equal event, the event that must happen before it, what a causation
        brings about, what may end an ``until`` it starts (slots the unfolding creates)."""
        for rel in self.state.spec.relations:
            if isinstance(rel, A.EventRelation):
                if rel.kind == "witness" and event == rel.first:
                    yield rel.second, f"witness {rel.first} {rel.second}"
                elif rel.kind == "equal" and event in (rel.first, rel.second):
                    other = rel.second if event == rel.first else rel.first
                    yield other, f"equal {rel.first} {rel.second}"
                elif rel.kind == "happenBefore" and event == rel.second:
                    yield rel.first, f"happenBefore {rel.first} {rel.second}"
            elif isinstance(rel, A.EventMeasureRelation) and rel.kind == "causation" and event != rel.event:
                yield rel.event, f"causation {rel.event}"
            elif isinstance(rel, A.UntilRelation) and event == rel.trigger.event:
                yield rel.until_event, f"until {rel.until_event}"  # what may end it

    def assumptions(self, snap: dict[str, Z3]) -> Z3:
        """The measure relations on one snapshot, each guarded by its relation literal."""
        return z3.And(
            *(
                z3.Implies(lit, self.on_snapshot(rel, snap))
                for lit, rel in zip(self.state.relation_lit, self.state.spec.relations)
                if isinstance(rel, A.MeasureRelation)
            ),
            self.state.ctx,
        )

    def on_snapshot(self, rel: A.MeasureRelation, snap: dict[str, Z3]) -> Z3:
        """Measure relation ``rel`` on one snapshot."""
        truth = self.terms.truth
        p = truth(rel.first, snap)
        if rel.kind == "invariant" or rel.second is None:
            return p
        q = truth(rel.second, snap)
        if rel.kind == "imply":
            return z3.Implies(p, q)
        if rel.kind == "iff":
            return p == q
        return z3.Implies(p, z3.Not(q))  # mutualExclusive, opposite (docs/reference/sleec-language.md §9.2)

    def on_fallback(self, rel: A.Relation, fb: Fallback) -> Z3 | None:
        """What ``rel`` says of the values an ``otherwise`` reads (a snapshot at ``fb.at``,
        after every occurrence at that instant); None: nothing."""
        truth = self.terms.truth
        if isinstance(rel, A.MeasureRelation):
            return self.on_snapshot(rel, fb.snap)
        if isinstance(rel, A.EventMeasureRelation) and rel.kind == "causation":
            happens = z3.Or(
                *(z3.And(y.present, y.t == fb.at) for y in self.state.by_event.get(rel.event, ())),
                self.state.ctx,
            )
            return z3.Implies(z3.And(fb.started, truth(rel.condition, fb.snap)), happens)
        if isinstance(rel, A.ForRelation | A.UntilRelation):
            parts = []
            for a_ in self.state.by_event.get(rel.trigger.event, ()):
                on = z3.And(a_.present, truth(rel.trigger.condition, a_.snap), fb.started, a_.t <= fb.at)
                if isinstance(rel, A.ForRelation):
                    inside = fb.at <= a_.t + self.terms.seconds(rel.duration, a_.snap)
                else:
                    inside = z3.Not(
                        z3.Or(
                            *(
                                z3.And(
                                    b.present,
                                    truth(rel.until_condition, b.snap),
                                    After(slot=a_)(b),
                                    b.t <= fb.at,
                                )
                                for b in self.state.by_event.get(rel.until_event, ())
                            ),
                            self.state.ctx,
                        )
                    )
                parts.append(z3.Implies(z3.And(on, inside), truth(rel.condition, fb.snap)))
            return z3.And(*parts, self.state.ctx)
        return None

    def _events(self, rel: A.EventRelation) -> Z3:
        """An event relation: which occurrences of its two events go together."""
        a, b = self.state.by_event.get(rel.first, []), self.state.by_event.get(rel.second, [])

        def with_(xs: list[Slot], ys: list[Slot]) -> Z3:
            return z3.And(
                *(
                    z3.Implies(x.present, z3.Or(*(z3.And(y.present, y.t == x.t) for y in ys), self.state.ctx))
                    for x in xs
                ),
                self.state.ctx,
            )

        if rel.kind == "witness":
            return with_(a, b)
        if rel.kind == "equal":
            return z3.And(with_(a, b), with_(b, a))
        if rel.kind in ("mutualExclusive", "isContradictoryWith"):
            return z3.And(
                *(z3.Not(z3.And(x.present, y.present, x.t == y.t)) for x in a for y in b if x is not y),
                self.state.ctx,
            )
        if rel.kind == "happenBefore":
            return z3.And(
                *(
                    z3.Implies(y.present, z3.Or(*(z3.And(x.present, x.t < y.t) for x in a), self.state.ctx))
                    for y in b
                ),
                self.state.ctx,
            )
        raise AssertionError(f"unknown relation {rel.kind}")

    def _event_condition(self, rel: A.EventMeasureRelation) -> Z3:
        """``causation`` (the condition brings the event about, at once), ``includes`` and
        ``forbid`` (the event's snapshot meets the condition, or does not)."""
        truth = self.terms.truth
        es = self.state.by_event.get(rel.event, [])
        if rel.kind == "causation":
            return z3.And(
                *(
                    z3.Implies(
                        z3.And(s.present, truth(rel.condition, s.snap)),
                        z3.Or(*(z3.And(y.present, y.t == s.t) for y in es), self.state.ctx),
                    )
                    for s in self.state.slots
                ),
                self.state.ctx,
            )
        want = truth if rel.kind == "includes" else (lambda c, s: z3.Not(truth(c, s)))
        return z3.And(*(z3.Implies(s.present, want(rel.condition, s.snap)) for s in es), self.state.ctx)

    def _until(self, rel: A.UntilRelation) -> Z3:
        """After each trigger, the condition holds at every occurrence until the ``until``
        event (with its condition) stops it."""
        truth = self.terms.truth
        ends = self.state.by_event.get(rel.until_event, [])
        parts = []
        for a_ in self.state.by_event.get(rel.trigger.event, []):
            on = z3.And(a_.present, truth(rel.trigger.condition, a_.snap))
            for y in self.state.slots:
                after_a = z3.BoolVal(True, self.state.ctx) if y is a_ else After(slot=a_)(y)  # A's own too
                stopped = z3.Or(
                    *(
                        z3.And(
                            b.present,
                            truth(rel.until_condition, b.snap),
                            After(slot=a_)(b),
                            z3.Not(After(slot=y)(b)),
                        )
                        for b in ends
                    ),
                    self.state.ctx,
                )
                parts.append(
                    z3.Implies(z3.And(on, y.present, after_a, z3.Not(stopped)), truth(rel.condition, y.snap))
                )
        return z3.And(*parts, self.state.ctx)

    def _for(self, rel: A.ForRelation) -> Z3:
        """After each trigger, the condition holds at every occurrence for the duration."""
        truth = self.terms.truth
        parts = []
        for a_ in self.state.by_event.get(rel.trigger.event, []):
            on = z3.And(a_.present, truth(rel.trigger.condition, a_.snap))
            end = a_.t + self.terms.seconds(rel.duration, a_.snap)
            for y in self.state.slots:
                parts.append(
                    z3.Implies(
                        z3.And(
                            on,
                            y.present,
                            z3.BoolVal(True, self.state.ctx) if y is a_ else After(slot=a_)(y),
                            y.t <= end,
                        ),
                        truth(rel.condition, y.snap),
                    )
                )
        return z3.And(*parts, self.state.ctx)


__all__ = ["Relations"]
