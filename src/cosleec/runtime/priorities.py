"""Rule priorities and conflicts: what the Manager does when rules demand E and not E.

A *conflict* is an obligation to produce E whose whole remaining window lies inside the
window of a prohibition of E in force: no behaviour meets both. Without a priority the
prohibition wins (fail closed): the obligation is *refused* -- violated by conflict at that
moment, its ``otherwise`` starting then -- and the action is never dispatched. A
prohibition that forbids only part of the window is no conflict: the Manager holds the
action until it is allowed (``request(E)`` and the dispatch never disagree).

A priority ``H > L`` (declared in the rules' ``priority`` block, or given to the Manager;
closed transitively) resolves clashes between the two rules' *instances* (one firing and
its ``otherwise`` chain, active while anything of it is in force), as SLEEC-TK's
``priority`` branch defines (``docs/reference/sleec-language.md`` §13):

- ``cancel``: whenever an instance of H and one of L are active together, the L instance
  is cancelled at once, whichever came first;
- ``conflict-aware``: L is kept as long as possible and cancelled only when keeping it
  would violate the other rule: at the deadline of an obligation of one rule that the
  other's prohibition forbids at that deadline (``lead`` seconds earlier, so that a robot
  on a real clock has time to act).

A cancelled instance imposes nothing more: no violation, no ``otherwise``. The reference
semantics (:mod:`cosleec.semantics`) defines the same, independently; the differential
test holds the two equal.
"""

from __future__ import annotations

import difflib
import logging
import math
from collections.abc import Container, Iterable, Iterator
from dataclasses import dataclass

from cosleec.errors import show
from cosleec.lang import (
    CANCEL,
    CONFLICT_AWARE,
    PRIORITY_SEMANTICS,
    PrioritySemantics,
    closure,
    cycle,
    parse_priority,
)
from cosleec.runtime.errors import ConfigurationError
from cosleec.runtime.obligations import PENDING, Tracked, Tracker
from cosleec.runtime.ruleset import RuleSet

log = logging.getLogger("cosleec.runtime")


@dataclass(frozen=True)
class Priorities:
    """The declared priorities, closed transitively, and how they resolve clashes."""

    above: frozenset[tuple[str, str]] = frozenset()  # (higher, lower), closed transitively
    semantics: PrioritySemantics = PrioritySemantics.CANCEL
    lead: float = 0.0
    declared: tuple[tuple[str, str], ...] = ()  # as given (the file's and the caller's)

    @classmethod
    def build(
        cls,
        rules: Iterable[str],
        declared: Iterable[str | tuple[str, str]],
        semantics: str = CANCEL,
        lead: float = 0.0,
    ) -> Priorities:
        """Check and close ``declared`` (``"H > L"`` strings or pairs) over the rule names.

        ConfigurationError, naming the fix, for an unknown rule (with the closest names),
        a rule above itself, a cycle, an unknown ``semantics`` or a bad ``lead``.
        """
        if semantics not in PRIORITY_SEMANTICS:
            raise ConfigurationError(
                f"priority_semantics must be one of {', '.join(PRIORITY_SEMANTICS)}, not {show(semantics)}"
            )
        if isinstance(lead, bool) or not isinstance(lead, int | float) or not (0 <= lead < math.inf):
            raise ConfigurationError(f"priority_lead must be a number of seconds >= 0, not {show(lead)}")
        names = list(rules)
        known = set(names)
        pairs: list[tuple[str, str]] = []
        for p in declared:
            if isinstance(p, str):
                got = parse_priority(p)
            elif isinstance(p, tuple | list) and len(p) == 2 and all(isinstance(n, str) for n in p):
                got = [(p[0], p[1])]
            else:
                raise ConfigurationError(
                    f"a priority is a string like 'R1 > R2' or a pair of rule names, not {show(p)}"
                )
            for h, lo in got:
                for n in (h, lo):
                    if n not in known:
                        close = difflib.get_close_matches(n, names, n=3)
                        raise ConfigurationError(
                            f"priority {h} > {lo}: there is no rule {show(n)}"
                            + (f" (did you mean {', '.join(close)}?)" if close else "")
                        )
                if h == lo:
                    raise ConfigurationError(f"priority {h} > {lo}: a rule cannot be above itself")
                pairs.append((h, lo))
        loop = cycle(pairs)
        if loop:
            raise ConfigurationError(
                f"the priorities form a cycle: {' > '.join(loop)}", hint="remove one of the pairs"
            )
        return cls(closure(pairs), PrioritySemantics(semantics), float(lead), tuple(dict.fromkeys(pairs)))

    def related(self, rule: str) -> list[str]:
        """The rules a priority orders ``rule`` against (above or below it), sorted."""
        return sorted({b for a, b in self.above if a == rule} | {a for a, b in self.above if b == rule})

    def between(self, a: str, b: str) -> str | None:
        """The rule of the two that is higher, or None when neither is declared above the other."""
        if (a, b) in self.above:
            return a
        if (b, a) in self.above:
            return b
        return None


def covers(obligation: Tracked, prohibition: Tracked, now: float) -> bool:
    """Does ``prohibition`` forbid every instant left of ``obligation``'s window (a conflict)?"""
    if obligation.branches:
        return False  # an `else` alternative may still meet it
    lo = max(obligation.lo, now)
    hi = obligation.hi
    return prohibition.lo <= lo and (prohibition.hi is None or (hi is not None and hi <= prohibition.hi))


def forced(
    tracker: Tracker, priorities: Priorities, fresh: Iterable[Tracked] | None = None
) -> tuple[float, Tracked, str] | None:
    """Conflict-aware: the earliest cancellation due -- (time, an item of the instance to
    cancel, the higher rule) -- or None.

    An obligation of one rule whose deadline finds a prohibition of the same event by a
    rule it is prioritised against forces the lower of the two out at that deadline
    (minus ``lead``). The answer depends only on what is in force, not on the time; with
    ``fresh``, only the pairs that involve those items are looked at (the caller keeps the
    answer for the rest, while nothing ends).
    """
    if priorities.semantics != CONFLICT_AWARE or not priorities.above:
        return None
    best: tuple[float, int, Tracked, str] | None = None
    for o, p in _pairs(tracker) if fresh is None else _pairs_with(tracker, fresh):
        d = o.own_hi
        if d is None or o.branches or o.clause is None:
            continue  # no deadline to force; an `else` may meet it; undetermined: no activation
        if p.instance == o.instance or p.clause is None or not (p.lo <= d and (p.hi is None or d <= p.hi)):
            continue
        higher = priorities.between(o.rule, p.rule)
        if higher is None:
            continue
        victim = p if higher == o.rule else o
        at = max(d - priorities.lead, o.start, p.lo)
        if best is None or (at, victim.id) < best[:2]:
            best = (at, victim.id, victim, higher)
    return None if best is None else (best[0], best[2], best[3])


def _pairs(tracker: Tracker) -> Iterator[tuple[Tracked, Tracked]]:
    """Every (obligation, prohibition) of one event in force; only banned events can force."""
    for event in tracker.banned():
        bans = tracker.banning(event)
        for o in tracker.obliging(event):
            for p in bans:
                yield o, p


def _pairs_with(tracker: Tracker, fresh: Iterable[Tracked]) -> Iterator[tuple[Tracked, Tracked]]:
    """The (obligation, prohibition) pairs in force that involve one of ``fresh``."""
    for t in fresh:
        if t.status != PENDING:
            continue
        if t.prohibition:
            for o in tracker.obliging(t.event):
                yield o, t
        else:
            for p in tracker.banning(t.event):
                yield t, p


@dataclass(frozen=True)
class PossibleConflict:
    """A response item of one rule that obliges ``event`` and one that forbids it: if both
    are ever in force together the Manager must resolve a conflict (a quick pairwise check;
    ``cosleec analyse`` decides whether it can really happen)."""

    event: str
    obliges: str  # the item's key, e.g. R1:0 or R2.1:0/o:0
    forbids: str
    rules: tuple[str, str]

    def describe(self) -> str:
        """``R1:0 obliges OpenCurtains, R2:0 forbids it``."""
        return f"{self.obliges} obliges {self.event}, {self.forbids} forbids it"


def possible_conflicts(
    ruleset: RuleSet, priorities: Priorities, *, among: Container[str] | None = None, limit: int | None = None
) -> list[PossibleConflict]:
    """Every pair of response items that oblige and forbid the same event, across rules that
    no declared priority orders (within one rule, across its clauses and fallbacks); only
    between rules named in ``among`` when given, and at most ``limit`` pairs (there can be
    as many as rules squared: ``cosleec graph`` of part of 100,000 rules asks for few)."""
    owed: dict[str, list[tuple[str, str]]] = {}
    forbidden: dict[str, list[tuple[str, str]]] = {}
    order: dict[str, None] = {}  # events in the order items first name them (warnings list so)
    for rule in ruleset.rules:
        if among is not None and rule.name not in among:
            continue
        for spec in rule.responses():
            for it in spec.walk():
                if "/e" not in it.key:  # an `else` alternative is accepted, never enacted or enforced
                    side = forbidden if it.negated else owed
                    side.setdefault(it.event, []).append((rule.name, it.key))
                    order.setdefault(it.event, None)
    out = []
    for event in order:
        against = forbidden.get(event)
        if not against:  # nothing forbids it: no pair to look at (linear when nothing does)
            continue
        for r1, k1 in owed.get(event, ()):
            for r2, k2 in against:
                if priorities.between(r1, r2) is None:
                    out.append(PossibleConflict(event, k1, k2, (r1, r2)))
                    if limit is not None and len(out) >= limit:
                        return out
    return out


def warn_conflicts(
    ruleset: RuleSet, priorities: Priorities, known: Iterable[PossibleConflict] = ()
) -> list[PossibleConflict]:
    """The item pairs of ``ruleset`` that can conflict (:func:`possible_conflicts`); logs a
    warning when there are any other than those ``known`` (warned of before a reload)."""
    found = possible_conflicts(ruleset, priorities)
    if set(found) - set(known):
        shown = "; ".join(c.describe() for c in found[:5])
        more = len(found) - 5
        log.warning(
            "the rules can conflict (%s%s): the prohibition will win unless a priority is declared "
            "(a priority_start block, or Manager(priorities=[...]))",
            shown,
            f"; and {more} more" if more > 0 else "",
        )
    return found


def warn_lead(priorities: Priorities, real_clock: bool) -> None:
    """Warn when conflict-aware priorities with no lead run on a real clock (too late to act)."""
    if priorities.semantics == CONFLICT_AWARE and priorities.above and not priorities.lead and real_clock:
        log.warning(
            "conflict-aware priorities with priority_lead=0 on a real clock: the lower rule is cancelled "
            "at the higher rule's deadline, too late for the robot to act in time; give priority_lead "
            "(seconds the robot needs)"
        )
