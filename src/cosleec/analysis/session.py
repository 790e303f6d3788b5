"""What every check of one analysis shares: the settings, the encodings, the questions' helpers.

A :class:`Session` holds one checked specification and what the checks leave behind (the
findings, what the solver could not settle); it builds the encodings in a z3 context of its
own per check (:meth:`Session.fresh_context`), walks a check's subjects so that a deadline can
say which were not decided (:meth:`Session.walk`), asks a question at growing bounds
(:meth:`Session.deepen`), and minimises an unsat core (:meth:`Session.core`). The checks
themselves are functions of a session, one module per family (checks.py lists them).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import z3

from cosleec.analysis.cores import Undecided, minimal_core
from cosleec.analysis.deadline import Deadline
from cosleec.analysis.encoding import Encoding, Slot
from cosleec.analysis.findings import MORE, Finding
from cosleec.lang import (
    HedgeSemantics,
    PrioritySemantics,
    Reading,
    Specification,
    Untimed,
    closure,
    pairs,
)
from cosleec.lang import ast as A

T = TypeVar("T")

LISTED = 10_000
"""Undecided subjects a report lists per check (then :data:`MORE`)."""

DEFAULT_BOUND = 6
"""Slots per event the unfolding may create before it stops (``--bound``)."""


@dataclass(frozen=True)
class Settings:
    """How to analyse: the reading of the rules, the bound, the time each question may take.

    ``untimed`` :attr:`~cosleec.lang.Untimed.NONE`: an untimed obligation must happen at some
    time after its trigger (the runtime's "no deadline", on a complete trace); seconds: within
    that many (LEGOS reads ``0``).
    """

    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
    untimed: Untimed | float = Untimed.NONE
    bound: int = DEFAULT_BOUND
    timeout: float = 5.0
    priorities: frozenset[tuple[str, str]] = frozenset()
    priority_semantics: PrioritySemantics = PrioritySemantics.CANCEL

    @functools.cached_property
    def reading(self) -> Reading:
        """How the rules are read: the encoding's, and the reference semantics' when it judges a
        witness (``priority_lead`` stays 0, SLEEC-TK's: the encoding reads it as the reference does)."""
        return Reading(
            semantics=self.semantics,
            untimed=self.untimed,
            priorities=tuple(self.priorities),
            priority_semantics=self.priority_semantics,
        )


@dataclass
class Session:
    """The questions about one checked specification; findings accumulate in ``findings``."""

    spec: Specification
    constants: dict[str, int]
    settings: Settings
    findings: list[Finding] = field(default_factory=list)
    unknown: list[str] = field(default_factory=list)  # what was not settled (FileReport.unknown)
    _by_event: dict[tuple[str, int], Encoding] = field(default_factory=dict)
    above: frozenset[tuple[str, str]] = frozenset()  # declared priorities, closed (set at start)
    situational_seconds: float = 0.0  # the part of runtime_conflicts spent on situations
    # one z3 context per file and check: terms built elsewhere cannot change this one's answers
    ctx: z3.Context = field(default_factory=z3.Context)
    deadline: Deadline | None = None  # the whole run's (--deadline): OutOfTime once it passes
    _at: tuple[str, Any, Iterator[Any], Callable[[Any], str]] | None = None  # walk()'s position

    def __post_init__(self) -> None:
        self.above = frozenset(closure([*self.settings.priorities, *pairs(self.spec)]))

    def fresh_context(self) -> None:
        """Start a check in a z3 context of its own: what other checks solved before it (or
        whether they ran at all) cannot change its situations and witnesses."""
        self.ctx = z3.Context()
        self._by_event = {}

    # ------------------------------------------------------------------ helpers
    def encoding(self, event: str, bound: int) -> tuple[Encoding, Slot]:
        """The shared encoding whose probe is an occurrence of ``event`` (built once per bound)."""
        enc = self._by_event.get((event, bound))
        if enc is None:
            enc = self.new_encoding(bound)
            enc.probe(event)
            for s in (*self.spec.concerns, *self.spec.purposes):
                if s.trigger.event == event and s.meanwhile is None:
                    for wanted in s.responses:
                        enc.demand(enc.slots[0], wanted)
            for rule in self.spec.rules:
                if rule.trigger.event == event:  # denying a rule's response (redundancy)
                    enc.demand(enc.slots[0], rule.response, breaches=True)
            enc.unfold()
            self._by_event[(event, bound)] = enc
        return enc, enc.slots[0]

    def new_encoding(self, bound: int | None = None) -> Encoding:
        """An empty encoding of these rules in this check's context, with the run's limits
        (``bound``: slots per event, by default the settings')."""
        return Encoding(
            self.spec,
            self.constants,
            self.settings.reading,
            self.settings.bound if bound is None else bound,
            timeout_ms=int(self.settings.timeout * 1000),
            ctx=self.ctx,
            deadline=self.deadline,
        )

    def walk(self, check: str, items: Iterable[T], name: Callable[[T], str]) -> Iterator[T]:
        """``items`` (the subjects of ``check``) in turn, remembering which is being decided:
        when the deadline stops the check, :meth:`not_decided` names it and those after it.
        ``items`` may be lazy (the pairs of clauses that can clash are as many as clauses
        squared): it is read no further than the walk goes."""
        rest = iter(items)
        for item in rest:
            self._at = (check, item, rest, name)
            yield item
        self._at = None

    def not_decided(self) -> tuple[str, list[str]] | None:
        """The check the deadline stopped and its subjects left undecided -- the one being
        decided, then those after it, at most :data:`LISTED` (then :data:`MORE`) -- or None
        when no check was under way."""
        if self._at is None:
            return None
        check, item, rest, name = self._at
        names = [name(item), *(name(x) for x in itertools.islice(rest, LISTED - 1))]
        if next(rest, None) is not None:
            names.append(MORE)
        return check, names

    def deepen(
        self, make: Callable[[int], tuple[Encoding, Any]], without: str | None, what: str
    ) -> tuple[Any, Encoding, Any, list[tuple[str, Any]]] | None:
        """Ask ``make(bound)``'s goal with every rule (but ``without``) at bound 2, 4, then the
        full bound: a trace found at any bound is a proof, and so is "none" once
        the unfolding completes; an inconclusive "none" is asked again one bound up. When a
        larger bound runs out of time, the answer is the last one the solver gave: "none"
        up to that smaller bound (said in :attr:`unknown`)."""
        last: tuple[Any, Encoding, Any, list[tuple[str, Any]]] | None = None
        for bound in self.bounds():
            enc, goal = make(bound)
            cands = self.candidates(enc, without)
            answer = enc.check([goal, *(lit for _, lit in cands)])
            if answer == z3.unknown:
                if last is None:
                    self.unknown.append(f"{what}: the solver gave up ({enc.solver.reason_unknown()})")
                else:
                    self.unknown.append(
                        f"{what}: answered up to bound {last[1].bound} only (bound {bound} ran out of time)"
                    )
                return last
            last = answer, enc, goal, cands
            if answer == z3.sat or enc.complete:
                return last
        return last

    def bounds(self) -> list[int]:
        """The bounds a question is asked at, in turn: 2, 4, then the full bound."""
        full = self.settings.bound
        return sorted({min(2, full), min(4, full), full})

    def candidates(self, enc: Encoding, without: str | None = None) -> list[tuple[str, Any]]:
        """Rules (that some slot can trigger) and relations, as (name, literal), in file order."""
        out = [
            (r.name, enc.rule_lit[r.name])
            for r in self.spec.rules
            if r.name != without and r.trigger.event in enc.by_event
        ]
        out += [(f"relation {i + 1}", lit) for i, lit in enumerate(enc.relation_lit)]
        return out

    def in_order(self, names: set[str]) -> tuple[str, ...]:
        """``names`` (rules) in file order."""
        return tuple(r.name for r in self.spec.rules if r.name in names)

    def core(self, enc: Encoding, goal: Any, cands: list[tuple[str, Any]], what: str) -> tuple[str, ...]:
        """The minimal cause of an unsatisfiable ``goal``; when the solver runs out of time
        while minimising, z3's own core (in file order), and :attr:`unknown` says so."""
        try:
            return minimal_core(enc, [goal], cands)
        except Undecided as u:
            self.unknown.append(f"{what}: the cause shown is not minimised ({u})")
        names = {str(lit): name for name, lit in cands}
        if enc.check([goal, *(lit for _, lit in cands)]) == z3.unsat:
            found = {names[str(x)] for x in enc.solver.unsat_core() if str(x) in names}
        else:
            found = set(names.values())
        return tuple(name for name, _ in cands if name in found)

    def solve(self, enc: Encoding, assumptions: list[Any], what: str) -> Any:
        """Check; an ``unknown`` answer is recorded and returned as None."""
        answer = enc.check(assumptions)
        if answer == z3.unknown:
            self.unknown.append(f"{what}: the solver gave up ({enc.solver.reason_unknown()})")
            return None
        return answer


def named(x: A.Rule | A.Situation) -> str:
    """A rule's, concern's or purpose's name: how :meth:`Session.walk` names a subject."""
    return x.name


__all__ = ["DEFAULT_BOUND", "LISTED", "Session", "Settings", "named"]
