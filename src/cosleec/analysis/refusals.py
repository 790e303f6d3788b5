"""Refusals: a prohibition in force that covers an obligation's whole remaining window refuses
the obligation at once, and its ``otherwise`` starts then (for :mod:`cosleec.analysis.encoding`).

The reference semantics refuses at the moment the second of the two is raised. Only a rule's
own clause items refuse (:func:`clause_items`); a prohibition inside an ``otherwise`` or a
braced clause does not, where the reference's does: the encoding's known limit.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import z3

from cosleec.analysis.slots import Z3, After, Ban, Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.analysis.windows import Windows
from cosleec.lang import ast as A


class Refusals:
    """The prohibitions one encoding's slots can raise, and when they refuse an obligation."""

    def __init__(self, state: State, terms: Terms, windows: Windows) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms
        self.windows = windows

    def register(self, slots: list[Slot]) -> None:
        """The prohibitions each slot's rules can raise (a clause's own items), for refusals."""
        for x in slots:
            for r in self.state.rules_by_event.get(x.event, ()):
                self.terms.on_time()
                for k, it in clause_items(r.response):
                    occ = it.occurrence
                    if not occ.negated:
                        continue
                    lo, hi = self.windows.window(
                        occ, it.otherwise is not None, x.t, x.snap, self.state.reading.untimed_seconds
                    )
                    # an unreadable window forbids nothing
                    known = self.windows.in_range(A.Response((it,)), x.snap)
                    active = z3.And(
                        self.state.rule_lit[r.name],
                        self.terms.fires(r, x),
                        self.terms.chosen_at(r.response, k, x.snap),
                        *([known] if known is not None else []),
                    )
                    self.state.bans.setdefault(occ.event, []).append(Ban(x, active, lo, hi))

    def refusal(
        self, event: str, lo: Z3, hi: Z3, start: Z3, after: Callable[[Slot], Z3], snap: dict[str, Z3]
    ) -> tuple[Z3 | None, Z3, list[tuple[Z3, dict[str, Z3]]]]:
        """When a prohibition in force covers an obligation's whole remaining window, the
        reference semantics refuses it at once (the moment the second of the two is raised)
        and starts its ``otherwise`` then. Returns (refused, when, [(case, values read)]);
        prohibitions inside an ``otherwise`` are not counted (only a rule's own clauses)."""
        cases = []
        for b in self.state.bans.get(event, ()):
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

            def before_refusal(y: Slot, b_later: Z3 = b_later, now: Z3 = now, b: Ban = b) -> Z3:
                return z3.And(after(y), z3.Or(y.t < now, z3.And(y.t == now, b_later, y.pos < b.slot.pos)))

            met_before = self.windows.occurs(event, lo, hi, before_refusal)
            cond = z3.And(in_force, covers, z3.Not(met_before))
            values = {m: z3.If(b_later, b.slot.snap[m], snap[m]) for m in snap}
            cases.append((cond, now, values))
        if not cases:
            return None, None, []
        refused = z3.Or(*(c for c, _, _ in cases))
        when = z3.Real(f"refused{self.terms.fresh_number()}", self.state.ctx)
        self.state.solver.add(z3.Implies(refused, z3.Or(*(z3.And(c, when == n) for c, n, _ in cases))))
        for c, n, _ in cases:
            self.state.solver.add(z3.Implies(c, when <= n))
        reads = [(z3.And(c, when == n), v) for c, n, v in cases]
        return refused, when, reads


def clause_items(resp: A.Response) -> Iterator[tuple[int, A.ResponseItem]]:
    """The top-level items of each clause of a rule's response: (clause, item)."""
    for it in resp.items:
        yield 0, it
    for k, d in enumerate(resp.defeaters, 1):
        if d.response is not None and not d.response.defeaters:
            for it in d.response.items:
                yield k, it


__all__ = ["Refusals", "clause_items"]
