"""Refusals: a prohibition in force that covers an obligation's whole remaining window refuses
the obligation at once, and its ``otherwise`` starts then (for :mod:`cosleec.analysis.encoding`).

The reference semantics refuses at the moment the second of the two is raised. Every
prohibition a firing raises refuses: a clause's own items and those of a braced inner clause,
raised at the trigger (:func:`raised_items`, registered before the rules are encoded:
:meth:`Refusals.register`), and those inside an ``otherwise``, raised when that fallback
starts (:func:`fallback_items`; registered while the rules are encoded,
:meth:`Refusals.raise_in_fallback`). So the refusal of an obligation of an event some
``otherwise`` forbids is completed once every rule is encoded (:meth:`Refusals.settle`).

Such a refusal can depend on another: a prohibition raised by the fallback a refusal started
refuses a second obligation. The reference takes them one at a time; the encoding asks that
every refusal the prohibitions in force make is taken (a case that holds implies the
refusal), and that a refusal taken has a case that holds *after* the refusals it relies on (an
integer rank per refusal, larger than its causes'): so no two refusals justify each other.
A prohibition never refuses the obligation whose own fallback raised it (that obligation is
settled already). Two rules a declared priority orders never refuse each other: the priority
settles their clash (:mod:`cosleec.analysis.priorities`), and a prohibition no longer refuses
once its firing is cancelled.

The moments are the reference's (:class:`~cosleec.analysis.slots.Step`): a fallback that
starts when a deadline ``d`` closes comes after every step at ``d``, and an item whose window
ends at ``d`` is over by then. Known simplification: the reference closes the windows that end
at ``d`` in rounds (an item raised by a fallback started at ``d`` whose window also ends at
``d`` is closed in the next round); the encoding takes every fallback started at ``d`` as one
moment, after every window that ends at ``d``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import z3

from cosleec.analysis.priorities import Priorities
from cosleec.analysis.slots import Z3, After, Ban, Cut, FallbackBan, Slot, Step
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms
from cosleec.analysis.windows import Windows
from cosleec.lang import ast as A

Case = tuple[Z3, Z3, Callable[[], dict[str, Z3]], Step | None]
"""A way a prohibition refuses an obligation: (condition, time, the values the ``otherwise``
then reads -- built when one is asked for --, refusing step)."""


@dataclass(eq=False)
class Refusal:
    """An obligation's refusal: whether (``refused``), when, at which step (``step``, when it
    was asked for: what its ``otherwise`` counts from), and the values its ``otherwise`` reads
    (the ``cases``). ``owner`` is what :meth:`Refusals.settle` still completes (an event some
    ``otherwise`` forbids), with the obligation's window and the rule it belongs to."""

    refused: Z3
    when: Z3
    step: Step | None
    cases: list[Case]
    owner: _Owner | None = None
    completed: bool = False  # the owner's cases are all in


@dataclass(frozen=True)
class Owed:
    """An obligation a prohibition may refuse: its event, its window ``[lo, hi]``, the time its
    response started, which occurrences come after the step that raised it (``after``, which
    says that step: ``after.step``), and the values it was raised with."""

    event: str
    lo: Z3
    hi: Z3
    start: Z3
    after: Callable[[Slot], Z3]
    snap: dict[str, Z3]


@dataclass(eq=False)
class _Owner:
    """What a refusal that prohibitions inside an ``otherwise`` can make still needs."""

    owed: Owed
    rule: str | None
    late: Z3  # refused by a prohibition inside an otherwise
    rank: Z3
    readers: list[dict[str, Z3]] = field(default_factory=list)  # the otherwise snapshots to constrain


class Refusals:
    """The prohibitions one encoding's slots can raise, and when they refuse an obligation."""

    def __init__(self, state: State, terms: Terms, windows: Windows, priorities: Priorities) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms
        self.windows = windows
        self.priorities = priorities
        self.settled = False  # every rule is encoded: a refusal asked now is completed at once

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

    def raise_in_fallback(
        self, it: A.ResponseItem, lo: Z3, hi: Z3 | None, step: Step, snap: dict[str, Z3]
    ) -> None:
        """Register prohibition ``it`` inside an ``otherwise`` of the rule being encoded, raised
        at ``step`` when the fallback starts (the state's guard: the rule fires, the clauses are
        chosen, the fallback started), reading ``snap``."""
        assert self.state.rule is not None
        known = self.windows.in_range(A.Response((it,)), snap)
        active = z3.And(
            self.state.rule_lit[self.state.rule], self.state.guard, *([known] if known is not None else [])
        )
        ban = FallbackBan(
            step, snap, active, lo, hi, self.state.rule, self.state.cut, tuple(self.state.within)
        )
        self.state.fallback_bans.setdefault(it.occurrence.event, []).append(ban)

    def refusal(self, o: Owed, *, moment: bool = False) -> Refusal | None:
        """When a prohibition in force covers an obligation's whole remaining window, the
        reference semantics refuses it at once (the moment the second of the two is raised)
        and starts its ``otherwise`` then. None: nothing can refuse it. ``moment``: say at
        which step (:attr:`Refusal.step`; always said when priorities are declared)."""
        moment = moment or bool(self.state.above)
        step_of = getattr(o.after, "step", None) if moment else None
        cases = [self._case(b, o, step_of) for b in self._bans(o.event)]
        owed = o.event in self.state.deferred
        if not cases and not owed:
            return None
        n = self.terms.fresh_number()
        late = z3.Bool(f"refused_late{n}", self.state.ctx) if owed else None
        refused = z3.Or(*(c for c, _, _, _ in cases), *([late] if late is not None else []), self.state.ctx)
        when = z3.Real(f"refused{n}", self.state.ctx)
        step = None
        if step_of is not None:
            flags = [s.late for _, _, _, s in cases if s is not None]
            fixed = not owed and all(z3.is_false(f) for f in flags)
            step = Step(
                when,
                z3.Int(f"refused_pos{n}", self.state.ctx),
                z3.BoolVal(False, self.state.ctx) if fixed else z3.Bool(f"refused_at_end{n}", self.state.ctx),
            )
        out = Refusal(refused, when, step, cases)
        if late is None:
            self._when(out, cases)
            return out
        out.owner = _Owner(o, self.state.rule, late, z3.Int(f"refused_rank{n}", self.state.ctx))
        self.state.owed.append(out)
        if self.settled:  # asked by a question: every prohibition is known already
            self._complete(out)
        return out

    def _bans(self, event: str) -> Iterator[Ban]:
        """The prohibitions raised at a trigger that may refuse an obligation of ``event`` of
        the rule being encoded (none of a rule a declared priority orders with it)."""
        for b in self.state.bans.get(event, ()):
            if self.state.rule is not None and b.rule and self.priorities.ordered(self.state.rule, b.rule):
                continue  # a declared priority settles this clash, not a refusal
            yield b

    def _case(self, b: Ban, o: Owed, step_of: Step | None) -> Case:
        """How prohibition ``b``, raised at a trigger, refuses the obligation ``o``."""
        lo, hi, start, after, snap = o.lo, o.hi, o.start, o.after, o.snap
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
            for y in self.state.by_event.get(o.event, ())
        ]
        in_force = z3.And(in_force, z3.Not(z3.And(z3.Not(b_later), z3.Or(*broken, self.state.ctx))))
        step = None
        if step_of is not None:
            late = step_of.late if z3.is_false(step_of.late) else z3.And(z3.Not(b_later), step_of.late)
            step = Step(now, z3.If(b_later, b.slot.pos, step_of.pos), late)
        if b.cut is not None:  # a prohibition whose firing a priority cancelled forbids nothing more
            in_force = z3.And(in_force, z3.Not(b.cut.by(now) if step is None else b.cut.by_step(step)))

        def before_refusal(y: Slot) -> Z3:
            return z3.And(after(y), z3.Or(y.t < now, z3.And(y.t == now, b_later, y.pos < b.slot.pos)))

        met_before = self.windows.occurs(o.event, lo, hi, before_refusal)
        values = {m: z3.If(b_later, b.slot.snap[m], snap[m]) for m in snap}
        return z3.And(in_force, covers, z3.Not(met_before)), now, lambda: values, step

    def _when(self, out: Refusal, cases: list[Case], ranked: list[Z3] | None = None) -> None:
        """When a refusal happens: at the earliest case that holds, and at its step (``ranked``:
        what a case that refuses needs, by default that it holds)."""
        solver = self.state.solver
        picks = []
        needs = ranked if ranked is not None else [c for c, _, _, _ in cases]
        for (_, n, _, s), need in zip(cases, needs):
            at = [out.when == n]
            if out.step is not None and s is not None:
                at.append(out.step.pos == s.pos)
                if not out.step.late.eq(s.late):
                    at.append(out.step.late == s.late)
            picks.append(z3.And(need, *at))
        solver.add(z3.Implies(out.refused, z3.Or(*picks, self.state.ctx)))
        for c, n, _, _ in cases:
            solver.add(z3.Implies(c, out.when <= n))

    def settle(self) -> None:
        """Complete the refusals that a prohibition inside an ``otherwise`` can make, now that
        every rule (and so every such prohibition) is encoded."""
        self.settled = True
        for out in self.state.owed:
            self.terms.on_time()
            if not out.completed:
                self._complete(out)

    def _complete(self, out: Refusal) -> None:
        """The cases of ``out`` that prohibitions inside an ``otherwise`` make: each one that
        holds refuses; a refusal needs a case after the refusals it relies on (module docstring)."""
        owner = out.owner
        assert owner is not None
        late, ranked = [], []
        for b in self.state.fallback_bans.get(owner.owed.event, ()):
            if out in b.within:
                continue  # raised by this obligation's own fallback: settled already
            if owner.rule is not None and self.priorities.ordered(owner.rule, b.rule):
                continue  # a declared priority settles this clash, not a refusal
            case = self._fallback_case(b, owner.owed, out.step is not None)
            late.append(case)
            causes = [z3.Implies(w.refused, owner.rank > w.owner.rank) for w in b.within if _ranked(w)]
            ranked.append(z3.And(case[0], *causes))
        solver = self.state.solver
        solver.add(z3.Implies(owner.late, z3.Or(*ranked, self.state.ctx)))
        for c, _, _, _ in late:
            solver.add(z3.Implies(c, out.refused))
        self._when(out, [*out.cases, *late], [c for c, _, _, _ in out.cases] + ranked)
        out.cases = [*out.cases, *late]
        out.completed = True
        for fresh in owner.readers:
            self._read(out, fresh)
        owner.readers.clear()

    def _fallback_case(self, b: FallbackBan, o: Owed, moment: bool) -> Case:
        """How prohibition ``b``, raised when a fallback starts, refuses the obligation ``o``."""
        mine: Step = o.after.step  # type: ignore[attr-defined]
        b_later = b.step.after(mine)
        now = z3.If(b_later, b.step.t, o.start)
        remaining = z3.If(o.lo >= now, o.lo, now)
        covers = z3.And(b.lo <= remaining, *([o.hi <= b.hi] if b.hi is not None else []))
        # pending then (not closed at once); a window ending at a deadline that closed is over
        pending = z3.And(o.lo <= o.hi, z3.If(z3.And(b_later, b.step.late), now < o.hi, now <= o.hi))
        ban_open = (
            [] if b.hi is None else [z3.If(z3.And(z3.Not(b_later), mine.late), now < b.hi, now <= b.hi)]
        )
        in_force = z3.And(b.active, pending, *ban_open)
        broken = [  # broken before the obligation was raised: no longer in force
            z3.And(
                y.present,
                b.lo <= y.t,
                *([y.t <= b.hi] if b.hi is not None else []),
                b.step.follows(y),
                z3.Not(o.after(y)),
            )
            for y in self.state.by_event.get(o.event, ())
        ]
        in_force = z3.And(in_force, z3.Not(z3.And(z3.Not(b_later), z3.Or(*broken, self.state.ctx))))
        step = Step.choose(b_later, b.step, mine) if moment else None
        if b.cut is not None:
            in_force = z3.And(in_force, z3.Not(b.cut.by(now) if step is None else b.cut.by_step(step)))

        def before_refusal(y: Slot) -> Z3:
            at_now = z3.And(y.t == now, b_later, z3.Not(b.step.follows(y)))
            return z3.And(o.after(y), z3.Or(y.t < now, at_now))

        met_before = self.windows.occurs(o.event, o.lo, o.hi, before_refusal)

        def values() -> dict[str, Z3]:
            return {m: z3.If(b_later, b.snap[m], o.snap[m]) for m in o.snap}

        return z3.And(in_force, covers, z3.Not(met_before)), now, values, step

    def read_into(self, out: Refusal, fresh: dict[str, Z3]) -> None:
        """The snapshot ``fresh`` of the ``otherwise`` a refusal starts reads the values of
        the case that refused (the cases still to come: once :meth:`settle` adds them)."""
        if out.owner is not None and not out.completed:
            out.owner.readers.append(fresh)
        else:
            self._read(out, fresh)

    def _read(self, out: Refusal, fresh: dict[str, Z3]) -> None:
        for c, n, read, _ in out.cases:
            values = read()
            self.state.solver.add(
                z3.Implies(
                    z3.And(c, out.when == n),
                    z3.And(*(fresh[m] == values[m] for m in fresh), self.state.ctx),
                )
            )


def _ranked(w: object) -> bool:
    """``w`` (an enclosing fallback's refusal) has a rank: prohibitions inside an otherwise can make it."""
    return isinstance(w, Refusal) and w.owner is not None


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


def fallback_items(resp: A.Response | None, *, inside: bool = False) -> Iterator[A.ResponseItem]:
    """The items a rule's response raises when one of its ``otherwise`` starts, at any depth
    (its braced clauses too; not an ``else``: the reference never raises those)."""
    if resp is None:
        return
    for it in resp.items:
        if inside:
            yield it
        yield from fallback_items(it.otherwise, inside=True)
    for d in resp.defeaters:
        yield from fallback_items(d.response, inside=inside)


__all__ = ["Owed", "Refusal", "Refusals", "clause_items", "fallback_items", "raised_items"]
