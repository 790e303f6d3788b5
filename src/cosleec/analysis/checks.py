"""The checks over whole traces: conflicts, redundancy, concerns, purposes, runtime conflicts.

Each is one satisfiability question per rule (or concern, purpose, pair of clauses) over
the traces of :mod:`cosleec.analysis.encoding`, with N-Check's meanings
(``docs/reference/sleec-language.md`` §9 and the README's "Analysing rules"):

vacuous conflict
    rule R's trigger (with its condition) can never occur in a trace that meets every rule.
situational conflict
    there is a situation -- an earlier occurrence that fires a rule, and the values R's
    trigger then reads -- in which R's trigger cannot occur without a rule being broken,
    although R is not vacuously conflicting. Candidates are the clauses whose obligation a
    prohibition of the same event can cover whole (the runtime conflicts); each candidate
    situation is fixed and then checked against every rule.
redundancy
    the other rules imply R: no trace meets them all and breaks R.
concern raised
    some trace meets every rule and shows the concern (the rules are too weak).
purpose blocked
    no trace that meets every rule shows the purpose (the rules are too strict); the
    minimal set of rules that blocks it is named.
runtime conflict
    two clauses (of one rule or two) can owe an event and forbid it in overlapping windows,
    and no declared priority orders their rules: the runtime will have to refuse one.

Relations (the LEGOS ``relation`` block) are assumptions about the world and hold in every
question; cores may name them.
"""

from __future__ import annotations

import functools
import itertools
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, TypeVar

import z3

from cosleec.analysis.cores import Undecided, minimal_core
from cosleec.analysis.deadline import Deadline
from cosleec.analysis.encoding import After, Encoding, Reading, Slot, as_float, clause_items, fallible_events
from cosleec.analysis.findings import BOUNDED, MORE, PROVED, Finding
from cosleec.analysis.witness import reads as _reads
from cosleec.analysis.witness import show, smallest, snapshot, then, witness
from cosleec.lang import CANCEL, HedgeSemantics, Severity, Specification, closure, pairs, visit
from cosleec.lang import ast as A
from cosleec.semantics import Options

T = TypeVar("T")

LISTED = 10_000
"""Undecided subjects a report lists per check (then :data:`MORE`)."""

DEFAULT_BOUND = 6
"""Slots per event the unfolding may create before it stops (``--bound``)."""


@dataclass(frozen=True)
class Settings:
    """How to analyse: the reading of the rules, the bound, the time each question may take."""

    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
    untimed: float | None = None
    bound: int = DEFAULT_BOUND
    timeout: float = 5.0
    priorities: frozenset[tuple[str, str]] = frozenset()
    priority_semantics: str = CANCEL

    @property
    def reading(self) -> Reading:
        """The encoding's view of these settings."""
        return Reading(self.semantics, self.untimed)

    @property
    def options(self) -> Options:
        """The reference semantics' view (for judging witnesses)."""
        return Options(
            semantics=self.semantics,
            untimed=self.untimed,
            priorities=self.priorities,
            priority_semantics=self.priority_semantics,
        )


@dataclass
class Analysis:
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
        fallible = {e for r in self.spec.rules for e in fallible_events(r.response)}
        top = {(r.name, id(it)) for r in self.spec.rules for _, it in clause_items(r.response)}
        nested = sorted(
            {
                r.name
                for r in self.spec.rules
                for resp in visit.responses(r.response)
                for it in resp.items
                if it.occurrence.negated and it.occurrence.event in fallible and (r.name, id(it)) not in top
            }
        )
        if nested:  # said once per file: the encoding's known limit (README, "What is not modelled")
            self.unknown.append(
                f"{', '.join(nested)}: a prohibition inside an otherwise or a braced clause can refuse an "
                "obligation here, which the analysis does not model; a finding that involves "
                f"{'it' if len(nested) == 1 else 'them'} may miss that"
            )

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

    def left_to_priority(self, what: str, names: tuple[str, ...]) -> bool:
        """Whether a rule of ``names`` is the lower rule of a declared priority: the runtime
        may then cancel it, which the encoding does not model, so the finding is not shown as
        proved but listed as left to the priority (in :attr:`unknown`)."""
        lower = sorted({(h, low) for h, low in self.above if low in names})
        if not lower:
            return False
        said = ", ".join(f"{h} > {low}" for h, low in lower)
        self.unknown.append(f"{what}: left to the declared priority {said} (cancellations are not analysed)")
        return True

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

    def status(self, enc: Encoding) -> tuple[str, int | None]:
        """Whether an unsat answer of ``enc`` is a proof, or holds up to the bound."""
        return (PROVED, None) if enc.complete else (BOUNDED, enc.bound)

    def span_of(self, name: str) -> A.Span:
        """Where a rule or relation is (relations are ``relation N``)."""
        if name.startswith("relation "):
            return self.spec.relations[int(name.split()[1]) - 1].span
        for r in self.spec.rules:
            if r.name == name:
                return r.span
        return A.NO_SPAN

    def related(self, names: tuple[str, ...], skip: str = "") -> tuple[tuple[str, A.Span], ...]:
        """Notes pointing at each named rule or relation."""
        return tuple((f"{n} is part of the cause", self.span_of(n)) for n in names if n != skip)

    def solve(self, enc: Encoding, assumptions: list[Any], what: str) -> Any:
        """Check; an ``unknown`` answer is recorded and returned as None."""
        answer = enc.check(assumptions)
        if answer == z3.unknown:
            self.unknown.append(f"{what}: the solver gave up ({enc.solver.reason_unknown()})")
            return None
        return answer

    # ------------------------------------------------------------------ N-Check's checks
    def vacuous_conflicts(self) -> None:
        """Rules whose trigger can never occur while every rule holds."""
        possible: set[str] = set()  # rules a trace already showed triggered with every rule met
        for rule in self.walk("vacuous-conflict", self.spec.rules, _named):
            if rule.name in possible:
                continue

            def make(bound: int, rule: A.Rule = rule) -> tuple[Encoding, Any]:
                enc, x = self.encoding(rule.trigger.event, bound)
                goal = enc.fresh("goal")
                enc.solver.add(z3.Implies(goal, enc.fires(rule, x)))
                return enc, goal

            asked = self.deepen(make, None, f"vacuous conflict of {rule.name}")
            if asked is None:
                continue
            if asked[0] == z3.sat:
                enc, model = asked[1], asked[1].solver.model()
                for s in enc.slots:
                    if z3.is_true(model.eval(s.present, model_completion=True)):
                        possible.update(
                            r.name
                            for r in enc.rules_by_event.get(s.event, ())
                            if z3.is_true(model.eval(enc.fires(r, s), model_completion=True))
                        )
                continue
            _, enc, goal, cands = asked
            core = self.core(enc, goal, cands, f"vacuous conflict of {rule.name}")
            if self.left_to_priority(f"vacuous conflict of {rule.name}", (rule.name, *core)):
                continue
            status, bound = self.status(enc)
            if all(n.startswith("relation ") for n in core):  # no rule needed: the condition never holds
                self.findings.append(
                    Finding(
                        code="dead-rule",
                        subject=rule.name,
                        message=f"rule {rule.name} can never fire: its trigger condition never holds"
                        + (f" (given {', '.join(core)})" if core else ""),
                        path=self.spec.path,
                        span=rule.trigger.condition.span if rule.trigger.condition is not None else rule.span,
                        rules=(rule.name, *core),
                        related=self.related(core),
                        hint="correct the condition (a comparison the wrong way round, a constant, a literal of "
                        "another scale), or remove the rule",
                        status=PROVED,
                        severity=Severity.WARNING,
                    )
                )
                continue
            others = [n for n in core if n != rule.name]
            cause = f"because of {', '.join(others)}" if others else "because of its own response"
            self.findings.append(
                Finding(
                    code="vacuous-conflict",
                    subject=rule.name,
                    message=f"rule {rule.name} conflicts whenever it is triggered: `{rule.trigger.event}` "
                    f"can never occur{' with its condition' if rule.trigger.condition else ''} without "
                    f"breaking a rule, {cause}",
                    path=self.spec.path,
                    span=rule.span,
                    rules=core,
                    related=self.related(core, rule.name),
                    hint="weaken one of these rules (a deadline, an unless clause) or declare which prevails "
                    "in a priority block",
                    status=status,
                    bound=bound,
                    severity=Severity.ERROR,
                )
            )

    def redundancies(self) -> None:
        """Rules the other rules already imply (a dead rule, already reported, is not repeated)."""
        dead = {f.subject for f in self.findings if f.code == "dead-rule"}
        for rule in self.walk("redundant", self.spec.rules, _named):
            if rule.name in dead:
                continue

            def make(bound: int, rule: A.Rule = rule) -> tuple[Encoding, Any]:
                enc, x = self.encoding(rule.trigger.event, bound)
                goal = enc.fresh("broken")
                enc.solver.add(
                    z3.Implies(goal, z3.And(enc.fires(rule, x), z3.Not(enc.holds(rule.response, x))))
                )
                return enc, goal

            asked = self.deepen(make, rule.name, f"redundancy of {rule.name}")
            if asked is None or asked[0] != z3.unsat:
                continue
            _, enc, goal, cands = asked
            core = self.core(enc, goal, cands, f"redundancy of {rule.name}")
            if self.left_to_priority(f"redundancy of {rule.name}", (rule.name, *core)):
                continue
            status, bound = self.status(enc)
            why = (
                f"the other rules already imply it: {', '.join(core)}"
                if core
                else "it can never be broken (its trigger cannot occur with its condition, or its response "
                "always holds)"
            )
            self.findings.append(
                Finding(
                    code="redundant",
                    subject=rule.name,
                    message=f"rule {rule.name} is redundant: {why}",
                    path=self.spec.path,
                    span=rule.span,
                    rules=core,
                    related=self.related(core),
                    hint="remove the rule, or check that the rules it names say what was meant",
                    status=status,
                    bound=bound,
                )
            )

    def situations(self, kind: str) -> None:
        """Concerns the rules allow (``concern``) and purposes they block (``purpose``)."""
        items = self.spec.concerns if kind == "concern" else self.spec.purposes
        for s in self.walk("concern-raised" if kind == "concern" else "purpose-blocked", items, _named):
            asked = self.deepen(functools.partial(self._situation, s), None, f"{kind} {s.name}")
            if asked is None:
                continue
            answer, enc, goal, cands = asked
            status, bound = self.status(enc)
            if kind == "concern" and answer == z3.sat:
                model = smallest(enc, [goal, *(lit for _, lit in cands)])
                w = witness(enc, model, self.settings.options, shows=[_as_rule(s)])
                self.findings.append(
                    Finding(
                        code="concern-raised",
                        subject=s.name,
                        message=f"concern {s.name} is raised: the rules allow this undesirable situation",
                        path=self.spec.path,
                        span=s.span,
                        hint="strengthen the rules so that the situation cannot happen (the witness shows how "
                        "it can)",
                        status=PROVED,
                        witness=w,
                    )
                )
            elif kind == "purpose" and answer == z3.unsat:
                core = self.core(enc, goal, cands, f"purpose {s.name}")
                if self.left_to_priority(f"purpose {s.name}", core):
                    continue
                self.findings.append(
                    Finding(
                        code="purpose-blocked",
                        subject=s.name,
                        message=f"purpose {s.name} is blocked by {', '.join(core) or 'the relations'}: no trace "
                        "that meets the rules achieves it",
                        path=self.spec.path,
                        span=s.span,
                        rules=core,
                        related=self.related(core),
                        hint="relax one of these rules (an unless clause for this situation) so the purpose "
                        "stays possible",
                        status=status,
                        bound=bound,
                        severity=Severity.ERROR,
                    )
                )

    def _situation(self, s: A.Situation, bound: int) -> tuple[Encoding, Any]:
        """An encoding and goal literal for ``s`` (the situation occurs)."""
        if s.meanwhile is None:
            enc, x = self.encoding(s.trigger.event, bound)
        else:
            enc = self.new_encoding(bound)
            chain: list[tuple[A.Situation, Slot]] = []
            cur: A.Situation | None = s
            while cur is not None:
                slot = enc.probe(cur.trigger.event)
                for r in cur.responses:
                    enc.demand(slot, r)
                chain.append((cur, slot))
                cur = cur.meanwhile
            enc.unfold()
            x = chain[0][1]
        goal = enc.fresh("situation")
        parts = []
        cur = s
        slots = [x] if s.meanwhile is None else [slot for _, slot in chain]
        for slot in slots:
            assert cur is not None
            parts.append(enc.truth(cur.trigger.condition, slot.snap))
            parts += [enc.holds(r, slot, untimed=0.0, situation=True) for r in cur.responses]
            cur = cur.meanwhile
        enc.solver.add(z3.Implies(goal, z3.And(*parts, enc.ctx)))
        return enc, goal

    # ------------------------------------------------------------------ runtime conflicts
    def clashes(self) -> Iterator[tuple[A.Rule, int, A.ResponseItem, A.Rule, int, A.ResponseItem]]:
        """Every (rule, clause, obligation) and (rule, clause, prohibition) of the same event."""
        owes: dict[str, list[tuple[A.Rule, int, A.ResponseItem]]] = {}
        bans: dict[str, list[tuple[A.Rule, int, A.ResponseItem]]] = {}
        for r in self.spec.rules:
            for k, it in clause_items(r.response):
                (bans if it.occurrence.negated else owes).setdefault(it.occurrence.event, []).append(
                    (r, k, it)
                )
        for event in sorted(owes.keys() & bans.keys()):
            for ro, ko, io in owes[event]:
                for rp, kp, ip in bans[event]:
                    yield ro, ko, io, rp, kp, ip

    def runtime_conflicts(self, situational: bool) -> None:
        """Clauses that can owe and forbid an event in overlapping windows (and, with
        ``situational``, the situations where that leaves a trigger unanswerable)."""
        above = self.above
        for ro, ko, io, rp, kp, ip in self.walk("runtime-conflict", self.clashes(), _pair):
            if (ro.name, rp.name) in above or (rp.name, ro.name) in above:
                continue  # a declared priority settles it
            found = list(self._clash(ro, ko, io, rp, kp, ip))
            if not found:
                continue
            enc, xo, xp, base, (lo, hi, plo, phi) = found[0]
            event = io.occurrence.event
            w = witness(
                enc,
                enc.solver.model(),
                self.settings.options,
                confirm=functools.partial(_overlap, event=event, owing=ro.name, banning=rp.name),
            )
            same = ro.name == rp.name
            self.findings.append(
                Finding(
                    code="runtime-conflict",
                    subject=f"{_clause(ro.name, ko)}/{_clause(rp.name, kp)}",
                    message=f"{_clause(ro.name, ko)} can owe `{event}` while {_clause(rp.name, kp)} forbids it, "
                    "in overlapping windows"
                    + (" (two activations of the rule)" if same and xo is not xp else ""),
                    path=self.spec.path,
                    span=io.occurrence.span or ro.span,
                    rules=self.in_order({ro.name, rp.name}),
                    related=((f"{_clause(rp.name, kp)} forbids `{event}` here", ip.occurrence.span),),
                    hint=(
                        f"declare which prevails (priority_start {ro.name} > {rp.name} priority_end), or "
                        "separate the clauses' conditions"
                        if not same
                        else "separate the clauses' conditions, or shorten the prohibition so that a later "
                        "activation can still be answered"
                    ),
                    status=PROVED,
                    witness=w,
                )
            )
            if situational:  # one occurrence triggering both, and two occurrences
                t0 = time.perf_counter()
                for enc, xo, xp, base, (lo, hi, plo, phi) in found:
                    self._situational(enc, ro, ko, io, xo, rp, kp, ip, xp, base, lo, hi, plo, phi)
                self.situational_seconds += time.perf_counter() - t0

    def _clash(
        self, ro: A.Rule, ko: int, io: A.ResponseItem, rp: A.Rule, kp: int, ip: A.ResponseItem
    ) -> Iterator[tuple[Encoding, Slot, Slot, list[Any], tuple[Any, Any, Any, Any]]]:
        """Situations where the obligation and the prohibition overlap: one occurrence
        triggering both (when the rules share their trigger), then two; with no other
        occurrence when that is possible (the smallest witness)."""
        shared = ro.trigger.event == rp.trigger.event
        for one in [True, False] if shared else [False]:
            if one and ro is rp and ko != kp:
                continue  # two clauses of one rule never apply to one occurrence
            enc = self.new_encoding(min(2, self.settings.bound))  # the two triggers, and what relations need
            xo = enc.probe(ro.trigger.event, "obligation")
            xp = xo if one else enc.probe(rp.trigger.event, "prohibition")
            enc.unfold()
            lo, hi = self._item_window(enc, ro, ko, io, xo)
            plo, phi = self._item_window(enc, rp, kp, ip, xp)
            probes = {xo.id, xp.id}
            readable = [  # windows the reference can read (at most 1e10 s): the witness must be judged
                r
                for it, x in ((io, xo), (ip, xp))
                if (r := enc._in_range(A.Response((it,)), x.snap)) is not None
            ]
            base = [
                *readable,
                enc.fires(ro, xo),
                enc.chosen_at(ro.response, ko, xo.snap),
                enc.fires(rp, xp),
                enc.chosen_at(rp.response, kp, xp.snap),
                *[
                    z3.Implies(lit, enc._relation(rel))
                    for lit, rel in zip(enc.relation_lit, self.spec.relations)
                ],
                *enc.relation_lit,
            ]
            overlap = z3.And(
                *([lo <= phi] if phi is not None else []), *([plo <= hi] if hi is not None else [])
            )
            alone = z3.And(*(z3.Not(s.present) for s in enc.slots if s.id not in probes), enc.ctx)
            what = f"runtime conflict {_clause(ro.name, ko)} / {_clause(rp.name, kp)}"
            if (
                self.solve(enc, [*base, overlap, alone], what) == z3.sat
                or self.solve(enc, [*base, overlap], what) == z3.sat
            ):
                yield enc, xo, xp, base, (lo, hi, plo, phi)

    def _item_window(
        self, enc: Encoding, rule: A.Rule, clause: int, it: A.ResponseItem, x: Slot
    ) -> tuple[Any, Any]:
        return enc.window(it.occurrence, it.otherwise is not None, x.t, x.snap, self.settings.untimed)

    def _situational(
        self,
        enc: Encoding,
        ro: A.Rule,
        ko: int,
        io: A.ResponseItem,
        xo: Slot,
        rp: A.Rule,
        kp: int,
        ip: A.ResponseItem,
        xp: Slot,
        base: list[Any],
        lo: Any,
        hi: Any,
        plo: Any,
        phi: Any,
    ) -> None:
        """N-Check's situational conflict, proved: a history the rules allow (it can be
        continued without breaking any rule), after which one more trigger cannot be answered.

        The candidate comes from the clash: the obligation still pending (its event has not
        occurred since it was raised) when the prohibition starts, and its whole remaining
        window forbidden. The history is pinned (times and values); it must be satisfiable
        without the later trigger and unsatisfiable with it.
        """
        if hi is None:
            return  # an obligation without deadline can always wait
        event = io.occurrence.event
        remaining = z3.If(lo >= xp.t, lo, xp.t)
        covered = z3.And(remaining <= hi, plo <= remaining, *([hi <= phi] if phi is not None else []))
        pending = (
            z3.Not(enc.occurs(event, lo, xp.t, After(slot=xo))) if xo is not xp else z3.BoolVal(True, enc.ctx)
        )
        orders = (
            [(z3.BoolVal(True, enc.ctx), ro)]
            if xo is xp
            else [(After(slot=xp)(xo), ro), (After(slot=xo)(xp), rp)]
        )
        for order, later in orders:  # each trigger in turn as the one that cannot be answered
            if any(  # this pair already leaves this trigger unanswerable: one finding says it
                f.code == "situational-conflict"
                and later.name in f.extra["triggers"]
                and {ro.name, rp.name} <= set(f.rules)
                for f in self.findings
            ):
                continue
            if self.solve(enc, [*base, covered, pending, order], "situation") == z3.sat:
                self._pinned(enc.solver.model(), ro, ko, io, xo, rp, kp, xp)

    def _history(
        self, model: Any, probes: list[Slot], event: str, xo: Slot, xp: Slot, bound: int
    ) -> tuple[Encoding, Slot, Any, list[tuple[str, Any]], Any] | str | None:
        """At ``bound``: the pinned history is allowed and the later trigger then cannot be
        answered -> (encoding, the trigger's slot, goal, candidates, a model of the history);
        None when not; ``"unknown"`` when the solver ran out of time."""
        fixed = self.new_encoding(bound)
        pinned: dict[int, Slot] = {}
        for n, x in enumerate(probes):
            pinned[x.id] = fixed.probe(x.event) if n + 1 < len(probes) else fixed.free(x.event)
        fixed.unfold()
        last = pinned[probes[-1].id]
        pins = []
        for x in probes:
            s = pinned[x.id]
            pins.append(s.t == model.eval(x.t, model_completion=True))
            pins += [s.snap[m] == model.eval(v, model_completion=True) for m, v in x.snap.items()]
        if len(probes) == 2:
            pins.append(pinned[probes[0].id].pos < last.pos)
        if xo is not xp:  # the obligation is still pending when the later trigger comes
            so = pinned[xo.id]
            between = [
                z3.And(y.present, After(slot=so)(y), z3.Not(After(slot=last)(y)))
                for y in fixed.by_event.get(event, ())
            ]
            pins.append(z3.Not(z3.Or(*between, fixed.ctx)))
        history, situation_goal = fixed.fresh("history"), fixed.fresh("situation")
        fixed.solver.add(z3.Implies(history, z3.And(*pins, z3.Not(last.present))))
        fixed.solver.add(z3.Implies(situation_goal, z3.And(*pins, last.present)))
        cands = self.candidates(fixed)
        lits = [lit for _, lit in cands]
        answer = fixed.check([history, *lits])
        if answer != z3.sat:
            return "unknown" if answer == z3.unknown else None
        allowed = fixed.solver.model()
        answer = fixed.check([situation_goal, *lits])
        if answer != z3.unsat:
            return "unknown" if answer == z3.unknown else None
        return fixed, last, situation_goal, cands, allowed

    def _pinned(
        self, model: Any, ro: A.Rule, ko: int, io: A.ResponseItem, xo: Slot, rp: A.Rule, kp: int, xp: Slot
    ) -> None:
        """The candidate situation of ``model``: the history before the later trigger pinned."""
        event = io.occurrence.event
        probes = list(dict.fromkeys([xo, xp]))
        probes.sort(key=lambda x: (as_float(model.eval(x.t, True)), as_float(model.eval(x.pos, True))))
        built: tuple[Encoding, Slot, Any, list[tuple[str, Any]], Any] | None = None
        for b in self.bounds():
            attempt = self._history(model, probes, event, xo, xp, b)
            if attempt is None:
                return  # the rules do not allow the history, or the trigger can be answered
            if isinstance(attempt, str):  # out of time: the last answer stands, up to its bound
                if built is not None:
                    self.unknown.append(
                        f"situational conflict: answered up to bound {built[0].bound} only "
                        f"(bound {b} ran out of time)"
                    )
                break
            built = attempt
            if built[0].complete:
                break
        if built is None:
            return
        fixed, last, situation_goal, cands, allowed = built
        later = ro if probes[-1] is xo else rp
        core = self.core(fixed, situation_goal, cands, f"situational conflict of {later.name}")
        if self.left_to_priority(f"situational conflict of {later.name}", core):
            return
        if any(f.code == "vacuous-conflict" and f.subject in core for f in self.findings):
            return
        # the rules of the cause that the later occurrence triggers: those it leaves unanswerable
        triggers = [n for n in core if self.spec.rule(n).trigger.event == last.event] or [later.name]
        if later.name not in triggers:
            later = self.spec.rule(triggers[0])
        if any(  # the same cause, and the same triggers unanswerable, already shown
            f.code == "situational-conflict" and f.rules == core and set(triggers) <= set(f.extra["triggers"])
            for f in self.findings
        ):
            return
        status, bound = self.status(fixed)
        reads = _reads(ro) | _reads(rp)
        situation = "; ".join(
            f"{x.event} at t={show(model, x.t)}"
            + (" with " + snapshot(fixed, model, x.snap, reads) if reads & x.snap.keys() else "")
            for x in probes
        )
        if xo is not xp:
            situation += f"; no `{event}` in between"
        self.findings.append(
            Finding(
                code="situational-conflict",
                subject=later.name,
                message=f"rule {later.name} cannot be answered in a situation the rules allow: "
                f"{_clause(rp.name, kp)} forbids `{event}` for the whole window in which "
                f"{_clause(ro.name, ko)} owes it (the cause: {', '.join(core)})",
                path=self.spec.path,
                span=later.span,
                rules=core,
                related=self.related(core, later.name),
                hint="add an unless clause for this situation to one of the rules, or declare which prevails "
                "in a priority block",
                status=status,
                bound=bound,
                situation=situation,
                witness=then(fixed, allowed, last, self.settings.options),
                extra={"triggers": triggers},
            )
        )


def _overlap(j: Any, event: str, owing: str, banning: str) -> bool:
    """The judgement has an obligation of ``owing`` and a prohibition of ``banning`` on
    ``event`` whose windows overlap."""
    inf = float("inf")
    for o in j.verdicts:
        if o.rule != owing or o.negated or o.event != event:
            continue
        for p in j.verdicts:
            if p.rule == banning and p.negated and p.event == event and p is not o:
                olo, ohi = o.window
                plo, phi = p.window
                if olo <= (inf if phi is None else phi) and plo <= (inf if ohi is None else ohi):
                    return True
    return False


def _named(x: A.Rule | A.Situation) -> str:
    return x.name


def _pair(clash: tuple[A.Rule, int, A.ResponseItem, A.Rule, int, A.ResponseItem]) -> str:
    return f"{_clause(clash[0].name, clash[1])}/{_clause(clash[3].name, clash[4])}"


def _clause(rule: str, k: int) -> str:
    return rule if k == 0 else f"{rule}.{k}"


def _as_rule(s: A.Situation) -> A.Rule:
    """A concern or purpose read as a rule (to judge a witness by the reference semantics)."""
    items: list[A.ResponseItem] = []
    for r in s.responses:
        items.extend(r.items)
    return A.Rule(s.name, s.trigger, A.Response(tuple(items)) if items else A.Response(()))
