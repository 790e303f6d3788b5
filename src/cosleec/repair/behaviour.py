"""What else a patch changes: the situations in which the patched rules judge the robot's
behaviour differently from the original ones, found by the solver.

A *situation* is an occurrence of a trigger event (the probe) with the truth values of the
atomic conditions -- comparisons and boolean measures -- that the rules the patch touches
read there: their trigger conditions and ``unless`` conditions (not an ``otherwise``'s,
which read a later moment), and those of the rules a declared priority puts above them that
the event triggers too (whether those fire decides whether the rules are cancelled). Behaviour differs in a situation when some trace

- meets every rule of ``before`` (and its relations) while, at the probe, a rule of
  ``after`` that differs (edited or added) fires and its response is broken: ``after``
  newly forbids that trace; or
- meets every rule of ``after`` while a rule of ``before`` that differs (edited or
  removed) fires at the probe and is broken: ``after`` newly allows it.

Each is one satisfiability question on the analysis' encoding of both versions at once
(:mod:`cosleec.repair.sides`), per trigger event of a rule that differs, asked at growing
bounds as :meth:`cosleec.analysis.session.Session.deepen` asks; the situations are counted
by enumerating models projected onto the atoms' truth values, each found one blocked. A
count found at a bound where the unfolding completed is exact for all traces; otherwise it
is exact up to that bound (:attr:`BehaviourChange.up_to_bound`). The counts are of situations,
not traces: "``after`` forbids DeployDrone when damages holds" is one situation however many
traces show it.

A few situations become scenarios: the solver's trace (made small), judged by the reference
semantics (:func:`cosleec.semantics.judge`) under both versions, and told as a sentence.
A scenario the reference semantics does not judge differently is said to be unconfirmed
(it would be a bug in the encoding), never silently shown.

Declared priorities are each version's (:mod:`cosleec.repair.sides`): a patch that declares
one changes behaviour where the lower rule is now cancelled. A refusal is judged with the
prohibitions of the version whose rules the trace meets, and the encoding's own limits are
the diff's (a prohibition inside an ``otherwise`` refuses no obligation).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import z3

from cosleec.analysis import (
    Deadline,
    Encoding,
    OutOfTime,
    Settings,
    Slot,
    as_float,
    smallest,
    snapshot,
    steps,
)
from cosleec.lang import Specification, visit
from cosleec.lang import ast as A
from cosleec.repair.scenario import tell
from cosleec.repair.sides import Sides, merge, original
from cosleec.semantics import Step

FORBIDDEN = "forbidden"
"""The direction of a situation in which ``after`` forbids a trace ``before`` allows."""
ALLOWED = "allowed"
"""The direction of a situation in which ``after`` allows a trace ``before`` forbids."""


@dataclass(frozen=True)
class Region:
    """Where a finding lives: occurrences of ``event`` with ``condition`` (None: any values)."""

    event: str
    condition: A.Expr | None = None


@dataclass(frozen=True)
class BehaviourChange:
    """How a patch changes the robot's behaviour.

    ``situations``: how many situations (a trigger event with the truth values of the
    conditions the rules read there) now judge some behaviour differently, counted by the
    solver up to ``limit`` (``exact`` False: there are more); ``outside``: how many of them
    lie outside the finding's regions; ``scenarios``: a few of them, each a sentence a
    person reads; ``computed`` False (with ``reason``): the diff could not be computed.
    ``witnesses``: each scenario's trace; ``up_to_bound``: None when the counts hold for
    every trace, else the bound (occurrences per event) up to which no other situation
    exists (an unfolding that did not complete, as the analysis' "up to bound").
    """

    situations: int
    outside: int
    exact: bool
    scenarios: tuple[str, ...] = ()
    computed: bool = True
    reason: str = ""
    witnesses: tuple[tuple[Step, ...], ...] = ()
    up_to_bound: int | None = None


class _Undecided(Exception):
    """The solver gave up on a question (the message says why)."""


def behaviour_change(
    before: A.Specification,
    after: A.Specification,
    constants_before: dict[str, int],
    constants_after: dict[str, int],
    settings: Settings,
    regions: tuple[Region, ...],
    *,
    limit: int = 64,
    scenarios: int = 3,
    deadline: Deadline | None = None,
) -> BehaviourChange:
    """The situations in which ``after`` judges behaviour differently from ``before``.

    ``before`` and ``after`` are checked specifications of one file, ``after`` with a patch
    applied; a rule with the same name in both is the same rule, maybe edited. ``regions``
    are where the finding the patch repairs lives. ``deadline`` bounds the whole diff (as
    ``analyse --deadline``); ``settings.timeout`` each solver question.
    """
    sides = merge(before, after, constants_before, constants_after, settings.priorities)
    if isinstance(sides, str):
        return BehaviourChange(0, 0, False, computed=False, reason=sides)
    if not sides.removed and not sides.added:
        return BehaviourChange(0, 0, True)
    count = _Count(sides, before, after, settings, regions, limit, scenarios, deadline)
    try:
        return count.run()
    except _Undecided as u:
        return BehaviourChange(0, 0, False, computed=False, reason=str(u))
    except OutOfTime:
        return BehaviourChange(
            0, 0, False, computed=False, reason="the deadline passed before the diff was computed"
        )


def atoms(rules: Sequence[A.Rule]) -> tuple[A.Expr, ...]:
    """The atomic conditions (comparisons, boolean measures) ``rules`` read when they fire:
    their trigger conditions and the ``unless`` conditions chosen then, each once."""
    out: list[A.Expr] = []
    for r in rules:
        for cond in (r.trigger.condition, *_clause_conditions(r.response)):
            for a in _atomic(cond):
                if a not in out:
                    out.append(a)
    return tuple(out)


def _above(spec: Specification, event: str, rules: Sequence[A.Rule]) -> tuple[A.Rule, ...]:
    """The rules ``event`` triggers that a declared priority puts above one of ``rules``:
    whether they fire there decides whether those are cancelled."""
    lower = {r.name for r in rules}
    higher = {p.higher for p in spec.priorities if p.lower in lower}
    return tuple(r for r in spec.rules if r.name in higher and r.trigger.event == event)


def _clause_conditions(resp: A.Response | None) -> Iterator[A.Expr]:
    """The ``unless`` conditions read when ``resp`` starts (an ``else`` starts with it; an
    ``otherwise`` starts later, on other values)."""
    if resp is None:
        return
    for d in resp.defeaters:
        yield d.condition
        yield from _clause_conditions(d.response)
    for it in resp.items:
        yield from _clause_conditions(it.alternative)


def _atomic(e: A.Expr | None) -> Iterator[A.Expr]:
    """The comparisons and boolean measures ``e`` combines with ``and``, ``or``, ``not``."""
    todo = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, A.Not):
            todo.append(x.operand)
        elif isinstance(x, A.BinOp) and x.op in A.BOOL_OPS:
            todo += reversed(list(visit.terms(x)))
        elif isinstance(x, A.Compare | A.Name):
            yield x


@dataclass
class _Question:
    """One trigger event's questions at one bound: the encoding with its probe, the atoms'
    terms on the probe, and per direction the goal literal, the rule set it assumes and the
    rules whose breach it asks about."""

    enc: Encoding
    probe: Slot
    atoms: tuple[A.Expr, ...]
    terms: list[Any]
    asks: list[tuple[str, list[Any], list[tuple[A.Rule, Any]]]]
    outside: Any  # a literal: the probe lies outside every region
    blocked_outside: Any  # a literal: the situations known outside are blocked
    blocked: Any  # a literal: every situation known is blocked


@dataclass
class _Count:
    """The enumeration of one diff: situations found (key: event and the atoms' values; value:
    whether one of its traces lies outside the regions), scenarios told, and how exact."""

    sides: Sides
    before: Specification
    after: Specification
    settings: Settings
    regions: tuple[Region, ...]
    limit: int
    wanted: int
    deadline: Deadline | None
    found: dict[tuple[str, tuple[bool, ...]], bool] = field(default_factory=dict)
    told: list[tuple[str, tuple[Step, ...]]] = field(default_factory=list)
    exact: bool = True
    bounded: int | None = None
    ctx: z3.Context = field(default_factory=z3.Context)

    def run(self) -> BehaviourChange:
        """Every event's situations, then the change."""
        for event in self.sides.events:
            if not self._event(event):
                break
        return BehaviourChange(
            len(self.found),
            sum(self.found.values()),
            self.exact,
            tuple(s for s, _ in self.told),
            witnesses=tuple(w for _, w in self.told),
            up_to_bound=self.bounded,
        )

    def _event(self, event: str) -> bool:
        """The situations of ``event`` at bound 2, 4, then the full one, until an unfolding
        completes; False once the limit is passed. A bound the solver gives up on leaves the
        answer of the bound before (up to it), as the analysis does."""
        full = self.settings.bound
        done: int | None = None
        for bound in sorted({min(2, full), min(4, full), full}):
            q = self._question(event, bound)
            try:
                more = self._enumerate(event, q)
            except _Undecided:
                if done is None:
                    raise
                self.bounded = min(done, self.bounded or done)
                return True
            if not more:
                return False
            done = bound
            if q.enc.complete:
                return True
        assert done is not None
        self.bounded = min(done, self.bounded or done)
        return True

    def _question(self, event: str, bound: int) -> _Question:
        """The encoding of both versions around a probe occurrence of ``event``, with the
        goals of both directions, and the situations already found blocked."""
        s = self.sides
        enc = Encoding(
            s.spec,
            s.constants,
            dataclasses.replace(self.settings.reading, priorities=()),  # each version's are in s.spec
            bound,
            timeout_ms=int(self.settings.timeout * 1000),
            ctx=self.ctx,
            deadline=self.deadline,
        )
        x = enc.probe(event)
        removed, added = s.changed(event)
        for r in (*removed, *added):
            enc.demand(x, r.response, breaches=True)
        enc.unfold()
        found = atoms((*removed, *added, *_above(s.spec, event, (*removed, *added))))
        q = _Question(
            enc,
            x,
            found,
            [enc.truth(a, x.snap) for a in found],
            [],
            enc.fresh("outside"),
            enc.fresh("blocked_outside"),
            enc.fresh("blocked"),
        )
        inside = [enc.truth(r.condition, x.snap) for r in self.regions if r.event == event]
        enc.solver.add(z3.Implies(q.outside, z3.Not(z3.Or(*inside, enc.ctx))))
        for direction, rules, keep in ((FORBIDDEN, added, s.before), (ALLOWED, removed, s.after)):
            if rules:
                q.asks.append((direction, *self._goal(enc, x, rules, keep)))
        for (e, values), out in self.found.items():
            if e == event:
                self._block(q, values, out)
        return q

    def _goal(
        self, enc: Encoding, x: Slot, rules: Sequence[A.Rule], keep: Sequence[str]
    ) -> tuple[list[Any], list[tuple[A.Rule, Any]]]:
        """The assumptions of a question -- a goal literal (one of ``rules`` fires at ``x``
        and is broken), the rules ``keep`` names and the relations of that version (and no
        other) -- and each rule of ``rules`` with its own breach literal."""
        s = self.sides
        broken = []
        for r in rules:
            lit = enc.fresh("broken")
            fires = enc.fires(r, x)  # broken as rule_holds reads it: a priority may cancel the firing
            enc.solver.add(
                lit == z3.And(fires, z3.Not(enc.obligations.holds(r.response, x, guard=fires, rule=r)))
            )
            broken.append((r, lit))
        goal = enc.fresh("differs")
        enc.solver.add(z3.Implies(goal, z3.Or(*(lit for _, lit in broken))))
        kept = set(keep)
        rels = set(s.relations_before if keep is s.before else s.relations_after)
        assume = [goal]
        assume += [lit if name in kept else z3.Not(lit) for name, lit in enc.rule_lit.items()]
        assume += [lit if i in rels else z3.Not(lit) for i, lit in enumerate(enc.relation_lit)]
        return assume, broken

    def _block(self, q: _Question, values: tuple[bool, ...], outside: bool) -> None:
        """No more models in the situation ``values`` (nor, when ``outside``, outside the regions)."""
        other = z3.Or(*(t != v for t, v in zip(q.terms, values, strict=True)), q.enc.ctx)
        q.enc.solver.add(z3.Implies(q.blocked, other))
        if outside:
            q.enc.solver.add(z3.Implies(q.blocked_outside, other))

    def _enumerate(self, event: str, q: _Question) -> bool:
        """Find ``event``'s situations in ``q``: first those with a trace outside the regions
        (a situation found inside at a smaller bound may turn out to have one), then the
        rest. False once the limit is passed (``exact`` is then False)."""
        for outside in (True, False):
            if not outside and not any(r.event == event for r in self.regions):
                break  # without a region here, every situation is outside
            for direction, assume, broken in q.asks:
                lits = [*assume, q.outside, q.blocked_outside] if outside else [*assume, q.blocked]
                while self._check(q.enc, lits) == z3.sat:
                    model = q.enc.solver.model()
                    values = tuple(z3.is_true(model.eval(t, model_completion=True)) for t in q.terms)
                    key = (event, values)
                    if key not in self.found and len(self.found) >= self.limit:
                        self.exact = False
                        return False
                    if key not in self.found and len(self.told) < self.wanted:
                        self._tell(q, direction, values, lits, broken)
                    self.found[key] = self.found.get(key, False) or outside
                    self._block(q, values, outside)
        return True

    def _check(self, enc: Encoding, lits: list[Any]) -> z3.CheckSatResult:
        answer = enc.check(lits)
        if answer == z3.unknown:
            raise _Undecided(f"the solver gave up ({enc.solver.reason_unknown()})")
        return answer

    def _tell(
        self,
        q: _Question,
        direction: str,
        values: tuple[bool, ...],
        lits: list[Any],
        broken: list[tuple[A.Rule, Any]],
    ) -> None:
        """The scenario of a situation just found (the solver's last model): its smallest
        trace with these values, told as the reference semantics judges it."""
        enc = q.enc
        pinned = enc.fresh("situation")
        enc.solver.add(
            z3.Implies(pinned, z3.And(*(t == v for t, v in zip(q.terms, values, strict=True)), enc.ctx))
        )
        model = smallest(enc, [*lits, pinned])
        trace = steps(enc, model)
        shown = {n.name for a in q.atoms for n in visit.names(a) if n.name in enc.measures}
        where = snapshot(enc, model, q.probe.snap, shown)
        rule = next(
            (r for r, lit in broken if z3.is_true(model.eval(lit, model_completion=True))), broken[0][0]
        )
        sentence = tell(
            self.before,
            self.after,
            trace,
            self.settings.reading,
            forbidden=direction == FORBIDDEN,
            event=q.probe.event,
            where=where,
            rule=original(rule.name),
            at=as_float(model.eval(q.probe.t, model_completion=True)),
        )
        self.told.append((sentence, tuple(trace)))


__all__ = ["ALLOWED", "FORBIDDEN", "BehaviourChange", "Region", "atoms", "behaviour_change"]
