"""Which repairs to try for a finding, derived from its cause and its situation.

Each finding says what is wrong and why: a redundancy names the rules that imply the
redundant one, a conflict the minimal set of rules that clash (and, for a runtime conflict,
the clauses), a blocked purpose the rules that block it, a raised concern the situation the
rules allow. One function per kind of finding (:data:`BY_CODE`) turns that into patches
(operators.py), the most specific first; deadline moves ask the solver for their value
while they are derived (deadlines.py), everything else is verified afterwards.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from dataclasses import replace
from itertools import permutations

from cosleec.analysis import Finding
from cosleec.lang import ast as A
from cosleec.repair import deadlines
from cosleec.repair.operators import Operators, only, opposite, requiring
from cosleec.repair.patch import Patch

Gone = Callable[[A.Specification, Finding], bool]
"""Whether a finding is no longer reported for a changed specification: its own check's
question to the solver (what a deadline search asks), not the whole verification."""


class Candidates:
    """The candidate repairs of the findings of one checked file; ``gone`` answers the solver
    questions a deadline search asks (without it, deadlines are not moved)."""

    def __init__(
        self, source: str, spec: A.Specification, gone: Gone | None = None, untimed: float | None = None
    ) -> None:
        self.ops = Operators(source, spec)
        self.spec = spec
        self.gone = gone
        self.untimed = untimed  # the reading's deadline of an untimed obligation (None: none)

    def of(self, f: Finding) -> list[Patch]:
        """Every candidate repair of ``f``, each once (none for a kind no operator repairs)."""
        make = BY_CODE.get(f.code)
        seen: set[tuple[tuple[int, int, str], ...]] = set()
        out = []
        for p in make(self, f) if make is not None else ():
            edits = tuple((e.start, e.end, e.text) for e in p.edits)
            if edits not in seen:
                seen.add(edits)
                out.append(p)
        return out

    def unrepairable(self, f: Finding) -> str:
        """Why no rule edit can repair ``f`` ('' when one may): a concern that only says an
        event can happen in some state (``exists``) is about the world, which rules do not
        forbid; the concern itself, or a relation about the world, has to change."""
        s = next((x for x in self.spec.concerns if x.name == f.subject), None)
        if f.code == "concern-raised" and s is not None and s.kind == "exists" and not s.responses:
            return (
                f"concern {s.name} says only that {s.trigger.event} can happen in that state; no rule "
                "can forbid what the world does: change the concern (what should the robot then do?) "
                "or declare a relation that rules the state out"
            )
        return ""

    def cause(self, f: Finding) -> list[A.Rule]:
        """The rules of ``f``'s cause (relations left out), in file order."""
        return [self.ops.rules[n] for n in f.rules if n in self.ops.rules]

    def judged(self, f: Finding, rule: A.Rule, i: int, unit: str, n: int) -> bool:
        """Whether ``f`` is gone once item ``i`` of ``rule`` is due within ``n`` ``unit``."""
        assert self.gone is not None
        new = deadlines.with_deadline(rule, i, n, unit)
        return self.gone(replace(self.spec, rules=tuple(new if r is rule else r for r in self.spec.rules)), f)

    def moved(
        self, f: Finding, rule: A.Rule, i: int, unit: str, hint: int, ceiling: int | None, *, later: bool
    ) -> Patch | None:
        """change-deadline of item ``i`` of ``rule``: the smallest value that removes ``f``
        (``later``: an obligation that must wait) or the largest (a deadline or window that
        must shrink), in ``unit``, from ``hint``; None when no value does."""
        if self.gone is None:
            return None
        works = functools.partial(self.judged, f, rule, i, unit)
        n = (deadlines.smallest if later else deadlines.largest)(works, hint, ceiling)
        if n is None:
            return None
        which = "smallest" if later else "largest"
        return self.ops.deadline(
            rule, i, n, unit, f"the {which} that removes {f.subject}, found by the solver"
        )


# ---------------------------------------------------------------------- per kind of finding
def redundant(c: Candidates, f: Finding) -> Iterator[Patch]:
    """A rule the others imply: remove it, or merge it into the rule that implies it."""
    rule = c.ops.rules.get(f.subject)
    if rule is None:
        return
    yield c.ops.remove(rule, f"implied by {', '.join(f.rules)}" if f.rules else "it can never be broken")
    for other in c.cause(f):
        merged = c.ops.merge(other, rule, f"{other.name} already implies it")
        if merged is not None:
            yield merged


def dead(c: Candidates, f: Finding) -> Iterator[Patch]:
    """A rule whose trigger can never hold: remove it."""
    rule = c.ops.rules.get(f.subject)
    if rule is not None:
        yield c.ops.remove(rule, "its trigger condition can never hold")


def unselectable(c: Candidates, f: Finding) -> Iterator[Patch]:
    """An unless clause never selected: remove the clause."""
    name, _, k = f.subject.rpartition(".")
    rule = c.ops.rules.get(name)
    if rule is not None and k.isdigit() and 0 < int(k) <= len(rule.response.defeaters):
        yield c.ops.remove_clause(rule, int(k), "it is never selected")


def conflict(c: Candidates, f: Finding) -> Iterator[Patch]:
    """Rules that clash (a vacuous, situational or runtime conflict): one takes precedence
    (a priority), one yields where the other applies (a narrower clause or trigger, an unless
    clause), a deadline moves so the windows no longer meet, two merge, or one goes."""
    rules = c.cause(f)
    subject = c.ops.rules.get(f.subject)
    if subject is not None and subject not in rules:
        rules.insert(0, subject)
    for high, low in permutations(rules, 2):
        yield c.ops.priority(high.name, low.name, f"{low.name} gives way where the two clash")
    yield from _narrowed_clauses(c, f, rules)
    for keep, give in permutations(rules, 2):
        where = keep.trigger.condition
        if where is not None and give.trigger.event == keep.trigger.event:
            why = f"{give.name} gives way to {keep.name} where {keep.name} applies"
            yield c.ops.add_unless(give, where, None, why)
            yield c.ops.refine_trigger(give, where, why)
    for owes, forbids in permutations(rules, 2):
        yield from _windows_apart(c, f, owes, forbids)
    for first, second in permutations(rules, 2):
        merged = c.ops.merge(first, second, f"they share trigger and response ({f.code})")
        if merged is not None:
            yield merged
    for rule in rules:
        yield c.ops.remove(rule, f"it takes part in the {f.code.replace('-', ' ')}")


def _narrowed_clauses(c: Candidates, f: Finding, rules: list[A.Rule]) -> Iterator[Patch]:
    """For a clash that names a clause (``R4.1/R13``): that clause stops where the other
    rule applies."""
    named = [part.partition(".") for part in f.subject.split("/")]
    for name, dot, k in named:
        rule = c.ops.rules.get(name)
        if rule is None or not dot or not k.isdigit() or not 0 < int(k) <= len(rule.response.defeaters):
            continue
        for other in rules:
            where = other.trigger.condition
            if other is not rule and where is not None and other.trigger.event == rule.trigger.event:
                why = f"it gives way to {other.name} where {other.name} applies"
                yield c.ops.refine_unless(rule, int(k), where, why)


def _windows_apart(c: Candidates, f: Finding, owes: A.Rule, forbids: A.Rule) -> Iterator[Patch]:
    """``owes`` requires, within a deadline, an event ``forbids`` forbids for a while: the
    prohibition's window shrinks below the deadline, or the obligation waits it out."""
    for j, due in deadlines.timed_obligations(owes):
        event = owes.response.items[j].occurrence.event
        own = _unit(owes, j)
        for k, window in deadlines.timed(forbids, event, True):
            unit = _unit(forbids, k)
            assert window is not None and unit is not None and own is not None
            step = A.TIME_UNITS[unit]
            shrink = c.moved(f, forbids, k, unit, max(due // step - 1, 1), window // step - 1, later=False)
            if shrink is not None:
                yield shrink
            wait = c.moved(f, owes, j, own, window // A.TIME_UNITS[own] + 1, None, later=True)
            if wait is not None:
                yield wait


def _unit(rule: A.Rule, i: int) -> str | None:
    """The time unit of item ``i``'s deadline (None: it has none)."""
    limit = rule.response.items[i].occurrence.limit
    return None if limit is None else limit.hi.unit


def concern(c: Candidates, f: Finding) -> Iterator[Patch]:
    """An undesirable situation the rules allow: rule it out where it starts -- a deadline
    moved, a new rule, an unless clause, an extra obligation, or a rule split at the
    concern's condition."""
    s = next((x for x in c.spec.concerns if x.name == f.subject), None)
    if s is None or s.kind != "when" or s.meanwhile is not None or len(s.responses) != 1:
        return
    (shown_item,) = s.responses[0].items if len(s.responses[0].items) == 1 else (None,)
    if shown_item is None or s.responses[0].defeaters:
        return
    shown = shown_item.occurrence
    wanted = opposite(shown, c.untimed)
    why = f"so that concern {s.name} cannot happen"
    yield from _tightened(c, f, s.trigger.event, shown)
    yield c.ops.add_rule(f"R_{s.name}", s.trigger, only(wanted), why)
    where = s.trigger.condition
    for rule in c.spec.rules:
        if rule.trigger.event != s.trigger.event:
            continue
        if where is not None:
            yield c.ops.add_unless(rule, where, requiring(rule.response, wanted), why)
        stronger = c.ops.strengthen(rule, wanted, why)
        if stronger is not None:
            yield stronger
        if where is not None and not rule.response.defeaters:
            yield c.ops.split(rule, where, requiring(rule.response, wanted), why)


def _tightened(c: Candidates, f: Finding, event: str, shown: A.Occurrence) -> Iterator[Patch]:
    """A concern that an obligation comes too late (``not X within d``): each rule with the
    concern's trigger that owes ``X`` later, or with no deadline, gets the largest deadline
    that removes the concern. A concern about the instant itself (``not X``, no deadline)
    leaves one value: ``within 0 seconds``."""
    limit = shown.limit
    if not shown.negated or shown.eventually or (limit is not None and limit.lo is not None):
        return
    bound = 0 if limit is None else deadlines.seconds(limit.hi)
    if bound is None:
        return
    unit = "seconds" if limit is None else limit.hi.unit
    step = A.TIME_UNITS[unit]
    for rule in c.spec.rules:
        if rule.trigger.event != event:
            continue
        for i, due in deadlines.timed(rule, shown.event, False):
            if due is not None and due <= bound:
                continue
            if bound == 0:
                why = f"the instant concern {f.subject} is about"
                yield c.ops.deadline(rule, i, 0, "seconds", why)
                continue
            ceiling = None if due is None else (due - 1) // step
            moved = c.moved(f, rule, i, unit, bound // step, ceiling, later=False)
            if moved is not None:
                yield moved


def purpose(c: Candidates, f: Finding) -> Iterator[Patch]:
    """A desirable situation the rules block: each blocking rule steps aside where the purpose
    lives (an unless clause that requires nothing, a narrower trigger, a shorter prohibition),
    or goes."""
    s = next((p for p in c.spec.purposes if p.name == f.subject), None)
    if s is None:
        return
    blockers = c.cause(f)
    where = s.trigger.condition
    why = f"so that purpose {s.name} stays possible"
    for rule in blockers:
        if where is not None:
            yield c.ops.add_unless(rule, where, None, why)
            yield c.ops.refine_trigger(rule, where, why)
        yield from _shorter_prohibitions(c, f, s, rule)
    for rule in blockers:
        yield c.ops.remove(rule, f"it blocks purpose {s.name}")


def _shorter_prohibitions(c: Candidates, f: Finding, s: A.Situation, rule: A.Rule) -> Iterator[Patch]:
    """A blocking rule that forbids an event the purpose needs: its window shrinks to the
    largest that lets the purpose happen."""
    needed = {it.occurrence.event for r in s.responses for it in r.items if not it.occurrence.negated}
    for event in sorted(needed):
        for k, window in deadlines.timed(rule, event, True):
            limit = rule.response.items[k].occurrence.limit
            assert limit is not None and window is not None
            step = A.TIME_UNITS[limit.hi.unit]
            moved = c.moved(f, rule, k, limit.hi.unit, window // step - 1, window // step - 1, later=False)
            if moved is not None:
                yield moved


BY_CODE: dict[str, Callable[[Candidates, Finding], Iterator[Patch]]] = {
    "redundant": redundant,
    "dead-rule": dead,
    "unselectable-clause": unselectable,
    "vacuous-conflict": conflict,
    "situational-conflict": conflict,
    "runtime-conflict": conflict,
    "concern-raised": concern,
    "purpose-blocked": purpose,
}
"""The candidates for each kind of finding, by its code."""


__all__ = ["BY_CODE", "Candidates", "Gone"]
