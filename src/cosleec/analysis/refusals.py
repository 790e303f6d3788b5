"""Refusals: a prohibition in force that covers an obligation's whole remaining window refuses
the obligation at once, and its ``otherwise`` starts then (for :mod:`cosleec.analysis.encoding`).

The reference semantics refuses at the moment the second of the two is raised. Every
prohibition a firing raises refuses: a clause's own items and those of a braced inner clause,
raised at the trigger (:func:`raised_items`, registered before the rules are encoded), and
those inside an ``otherwise``, raised when it starts (registered while the rules are encoded,
so a refusal that one may make is settled once every rule is: :meth:`Refusals.settle`). Two
rules a declared priority orders never refuse each other: the priority settles their clash
(:mod:`cosleec.analysis.priorities`), and a prohibition no longer refuses once its firing is
cancelled.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import z3

from cosleec.analysis.priorities import Priorities
from cosleec.analysis.slots import Z3, After, Ban, Cut, Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.analysis.windows import Windows
from cosleec.lang import ast as A


class Refusals:
    """The prohibitions one encoding's slots can raise, and when they refuse an obligation."""

    def __init__(self, state: State, terms: Terms, windows: Windows, priorities: Priorities) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms
        self.windows = windows
        self.priorities = priorities
        self.steps: dict[int, tuple[Z3, Z3]] = {}  # id(when) -> (when, the refusing step's position)

    def register(self, slots: list[Slot]) -> None:
        """The prohibitions each slot's rules raise at the trigger, for refusals."""
        for x in slots:
            for r in self.state.rules_by_event.get(x.event, ()):
                self.terms.on_time()
                cut = self.state.cuts.get((r.name, x.id))
                for k, it in clause_items(r.response):
                    if it.occurrence.negated:
                        self._ban(r, x, it, self.terms.chosen_at(r.response, k, x.snap), cut)
                for path, it in raised_items(r.response, braced_only=True):
                    if it.occurrence.negated:
                        chosen = [self.terms.chosen_at(resp, k, x.snap) for resp, k in path]
                        self._ban(r, x, it, z3.And(*chosen, self.state.ctx), cut)

    def _ban(self, r: A.Rule, x: Slot, it: A.ResponseItem, chosen: Z3, cut: Cut | None) -> None:
        """Register prohibition ``it`` of ``r``, raised at ``x`` when ``chosen``."""
        occ = it.occurrence
        lo, hi = self.windows.window(
            occ, it.otherwise is not None, x.t, x.snap, self.state.reading.untimed_seconds
        )
        # an unreadable window forbids nothing
        known = self.windows.in_range(A.Response((it,)), x.snap)
        active = z3.And(
            self.state.rule_lit[r.name],
            self.terms.fires(r, x),
            chosen,
            *([known] if known is not None else []),
        )
        self.state.bans.setdefault(occ.event, []).append(Ban(x, active, lo, hi, r.name, cut))

    def refusal(
        self, event: str, lo: Z3, hi: Z3, start: Z3, after: Callable[[Slot], Z3], snap: dict[str, Z3]
    ) -> tuple[Z3 | None, Z3, list[tuple[Z3, dict[str, Z3]]]]:
        """When a prohibition in force covers an obligation's whole remaining window, the
        reference semantics refuses it at once (the moment the second of the two is raised)
        and starts its ``otherwise`` then. Returns (refused, when, [(case, values read)]);
        prohibitions inside an ``otherwise`` are not counted (only a rule's own clauses)."""
        cases = []
        raising = after.slot if isinstance(after, After) else None  # the step that raised the obligation
        steps: list[Z3 | None] = []  # each case's refusing step (its position), when priorities need it
        for b in self.state.bans.get(event, ()):
            if self.state.rule is not None and b.rule and self.priorities.ordered(self.state.rule, b.rule):
                continue  # a declared priority settles this clash, not a refusal
            b_later = after(b.slot)  # the prohibition is raised after the obligation
            now = z3.If(b_later, b.slot.t, start)
            remaining = z3.If(lo >= now, lo, now)
            covers = z3.And(b.lo <= remaining, *([hi <= b.hi] if b.hi is not None else []))
            in_force = z3.And(b.active, now <= hi, *([now <= b.hi] if b.hi is not None else []))
            # a prohibition already broken before the obligation was raised is no longer in force
            broken = [
                z3.And(
                    y.present,
                    b.lo <= y.t,
                    *([y.t <= b.hi] if b.hi is not None else []),
                    After(slot=b.slot)(y),
                    z3.Not(after(y)),
                )
                for y in self.state.by_event.get(event, ())
            ]
            in_force = z3.And(in_force, z3.Not(z3.And(z3.Not(b_later), z3.Or(*broken, self.state.ctx))))
            step = None if raising is None else z3.If(b_later, b.slot.pos, raising.pos)
            if b.cut is not None:  # a prohibition whose firing a priority cancelled forbids nothing more
                in_force = z3.And(in_force, z3.Not(b.cut.by(now, step)))

            def before_refusal(y: Slot, b_later: Z3 = b_later, now: Z3 = now, b: Ban = b) -> Z3:
                return z3.And(after(y), z3.Or(y.t < now, z3.And(y.t == now, b_later, y.pos < b.slot.pos)))

            met_before = self.windows.occurs(event, lo, hi, before_refusal)
            cond = z3.And(in_force, covers, z3.Not(met_before))
            values = {m: z3.If(b_later, b.slot.snap[m], snap[m]) for m in snap}
            cases.append((cond, now, values))
            steps.append(step)
        if not cases:
            return None, None, []
        refused = z3.Or(*(c for c, _, _ in cases))
        when = z3.Real(f"refused{self.terms.fresh_number()}", self.state.ctx)
        self.state.solver.add(z3.Implies(refused, z3.Or(*(z3.And(c, when == n) for c, n, _ in cases))))
        for c, n, _ in cases:
            self.state.solver.add(z3.Implies(c, when <= n))
        reads = [(z3.And(c, when == n), v) for c, n, v in cases]
        if self.state.above and all(p is not None for p in steps):  # which step refuses, for a cut
            pos = z3.Int(f"refused_pos{self.terms.fresh_number()}", self.state.ctx)
            self.state.solver.add(
                z3.Implies(
                    refused, z3.Or(*(z3.And(c, when == n, pos == p) for (c, n, _), p in zip(cases, steps)))
                )
            )
            self.steps[id(when)] = (when, pos)
        return refused, when, reads


def raised_items(
    resp: A.Response, *, braced_only: bool = False
) -> Iterator[tuple[tuple[tuple[A.Response, int], ...], A.ResponseItem]]:
    """The items a rule's response raises at the trigger, each with the clause choices that
    raise it ((response, clause) pairs, outermost first): a clause's own items and, at any
    depth, a braced inner clause's. ``braced_only``: only those :func:`clause_items` leaves out."""

    def walk(
        r: A.Response, path: tuple[tuple[A.Response, int], ...], braced: bool
    ) -> Iterator[tuple[tuple[tuple[A.Response, int], ...], A.ResponseItem]]:
        if braced or not braced_only:
            for it in r.items:
                yield ((*path, (r, 0)) if r.defeaters else path), it
        for k, d in enumerate(r.defeaters, 1):
            if d.response is not None:
                yield from walk(d.response, (*path, (r, k)), braced or bool(d.response.defeaters))

    yield from walk(resp, (), False)


def clause_items(resp: A.Response) -> Iterator[tuple[int, A.ResponseItem]]:
    """The top-level items of each clause of a rule's response: (clause, item)."""
    for it in resp.items:
        yield 0, it
    for k, d in enumerate(resp.defeaters, 1):
        if d.response is not None and not d.response.defeaters:
            for it in d.response.items:
                yield k, it


__all__ = ["Refusals", "clause_items", "raised_items"]
