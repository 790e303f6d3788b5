"""Rule sets as satisfiability problems: the finite timed traces a rule set allows, in z3.

A trace is a finite set of *occurrences* (an event at a time, in a causal order) and, for
each, the *snapshot* of measure values it reads. :class:`Encoding` unfolds the occurrences
a question can need into *slots*: the probe (an occurrence the question is about) and, for
every obligation any slot's rules can raise, one fresh slot that may fulfil it -- and so on
down the chain of obligations, breadth first, at most ``bound`` slots per event. A slot may
or may not be part of the trace (``present``); its time, causal position and snapshot are
free. Every rule then constrains every slot, guarded by one assumption literal per rule (and
per relation), so one solver answers questions about any subset of the rules and unsat
cores name rules.

Why the answers can be *proved*: the constraints a rule puts on a trace are of two kinds --
"some occurrence of E in this window" (an obligation: a demand) and "no occurrence of E in
this window" (a prohibition) -- and removing occurrences never breaks a prohibition. So if
any trace satisfies a question, so does the sub-trace made of the probe and, for every
obligation that trace meets, one occurrence that meets it, recursively: a tree of demands,
which is exactly what the unfolding builds. Two things besides obligations can be what a
trace needs, so they are demands too: the occurrence that raises a prohibition which
*refuses* an obligation with an ``otherwise`` (the fallback then starts at once, not at the
deadline) -- the trigger of its rule, also when the prohibition is inside an ``otherwise``
(what starts that fallback is the rule's own demand) -- and the event that ends an ``until``
relation. When the unfolding finishes
within ``bound`` (:attr:`Encoding.complete`), "unsatisfiable" is a proof about *all* traces;
when it stops at the bound (a chain of demands that feeds itself), "unsatisfiable" holds for
the traces the unfolding can hold -- the probe and at most ``bound`` occurrences per event,
each one a demand's -- and is said to hold up to that bound only. "Satisfiable" is always a
proof: the model is a trace, and :mod:`cosleec.analysis.witness` checks it against the
reference semantics. An ``until`` relation breaks the argument (removing the event that ends
one extends it), so a question that involves one is never called complete.

The meaning is the reference semantics' (:mod:`cosleec.semantics.reference`), with one
reading of its own: a trace is *complete* -- time goes on past every deadline -- so an
untimed obligation (no deadline at run time) must still happen at some time, and ``not E
eventually`` forbids E for ever. Windows are closed, an occurrence counts for an obligation
only if it comes after the step that raised it (the trigger never fulfils its own
response), an ``otherwise`` starts at the deadline it follows (after every occurrence at
that instant), at the first occurrence that breaks its prohibition, or when a prohibition
in force covers the obligation's whole remaining window (a refusal), and reads the values of
that moment. Numeric measures are reals, as at run time; scale measures are their literal's
position. A measure always has a value (the runtime's policy for unknown values is not part
of the rules' meaning). Every prohibition a firing raises refuses, as the reference's does:
a rule's own clause items and those of its braced inner clauses, raised at the trigger
(:func:`~cosleec.analysis.refusals.raised_items`), and those inside an ``otherwise``, raised
when that fallback starts (:func:`~cosleec.analysis.refusals.fallback_items`), each for its
own window; a refused obligation's ``otherwise`` counts what comes after the refusing step
(:class:`~cosleec.analysis.slots.Step`: the step that raised the later of the two, or the
end of an instant whose deadline closed). Declared priorities cancel the lower rule's
firings (:mod:`~cosleec.analysis.priorities`).

:class:`Encoding` unfolds the slots (:mod:`~cosleec.analysis.slots`) and solves; the formulas
over them are built by the parts it holds, one concern each: :mod:`~cosleec.analysis.terms`
(conditions, numbers and clause choices on a snapshot), :mod:`~cosleec.analysis.windows`
(when an item's window opens and closes), :mod:`~cosleec.analysis.relations` (the relation
block), :mod:`~cosleec.analysis.refusals` (prohibitions refusing obligations) and
:mod:`~cosleec.analysis.obligations` (when a response is met). Every z3 object they keep is in
one :class:`~cosleec.analysis.state.State`.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator, Sequence

import z3

from cosleec.analysis.deadline import Deadline, OutOfTime, question_ms
from cosleec.analysis.obligations import Obligations
from cosleec.analysis.priorities import Priorities
from cosleec.analysis.refusals import Refusals, clause_items, fallback_items, raised_items
from cosleec.analysis.relations import Relations
from cosleec.analysis.slots import Z3, After, Fallback, Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms, as_float
from cosleec.analysis.windows import MAX_SECONDS, Windows
from cosleec.lang import HedgeSemantics, Reading, Specification, closure, pairs
from cosleec.lang import ast as A


class Encoding:
    """The traces of ``spec`` around some probe occurrences, as z3 constraints.

    Use: create probes with :meth:`probe`, declare what a question's own formula will need
    with :meth:`demand`, then :meth:`unfold`; after that, the parts build formulas over the
    slots (``enc.obligations.holds``: a response is met; ``enc.windows.window``, ...; the
    common ones are methods here), and :meth:`check` solves under assumption literals.
    """

    def __init__(
        self,
        spec: Specification,
        constants: dict[str, int],
        reading: Reading,
        bound: int,
        *,
        timeout_ms: int = 0,
        ctx: z3.Context | None = None,
        deadline: Deadline | None = None,
    ) -> None:
        ctx = ctx if ctx is not None else z3.Context()
        solver = z3.Solver(ctx=ctx)
        solver.set("random_seed", 0)
        if timeout_ms:
            solver.set("timeout", timeout_ms)
        guard = z3.BoolVal(True, ctx)
        rules_by_event: dict[str, list[A.Rule]] = {}
        for r in spec.rules:
            rules_by_event.setdefault(r.trigger.event, []).append(r)
        refusers: dict[str, set[str]] = {}  # event -> the triggers of rules that can forbid it
        deferred: set[str] = set()  # the events some otherwise forbids
        for r in spec.rules:
            for _, it in raised_items(r.response):
                if it.occurrence.negated:
                    refusers.setdefault(it.occurrence.event, set()).add(r.trigger.event)
            for it in fallback_items(r.response):
                if it.occurrence.negated:
                    refusers.setdefault(it.occurrence.event, set()).add(r.trigger.event)
                    deferred.add(it.occurrence.event)
        self.state = State(  # every z3 object the encoding keeps (state.py: why nothing else holds one)
            ctx=ctx,
            spec=spec,
            constants=constants,
            reading=reading,
            bound=max(1, bound),
            measures={m.name: m.type for m in spec.measures},
            solver=solver,
            timeout_ms=timeout_ms,
            deadline=deadline,
            guard=guard,
            rules_by_event=rules_by_event,
            rule_lit={r.name: z3.Bool(f"rule!{i}", ctx) for i, r in enumerate(spec.rules)},
            relation_lit=[z3.Bool(f"relation!{i}", ctx) for i in range(len(spec.relations))],
            complete=not any(isinstance(r, A.UntilRelation) for r in spec.relations),
            refusers=refusers,
            above=closure([*reading.priorities, *pairs(spec)]),
            deferred=frozenset(deferred),
        )
        self.terms = Terms(self.state)
        self.windows = Windows(self.state, self.terms)
        self.relations = Relations(self.state, self.terms)
        self.priorities = Priorities(self.state, self.terms)
        self.refusals = Refusals(self.state, self.terms, self.windows, self.priorities)
        self.obligations = Obligations(
            self.state, self.terms, self.windows, self.relations, self.refusals, self.priorities
        )

    # ------------------------------------------------------------------ what the state holds
    @property
    def ctx(self) -> z3.Context:
        """The z3 context every term of the encoding is in."""
        return self.state.ctx

    @property
    def solver(self) -> z3.Solver:
        """The solver the encoding's constraints are added to."""
        return self.state.solver

    @property
    def spec(self) -> Specification:
        """The rules encoded."""
        return self.state.spec

    @property
    def bound(self) -> int:
        """Slots per event the unfolding may create."""
        return self.state.bound

    @property
    def complete(self) -> bool:
        """The unfolding held every demand within the bound (and no ``until`` relation is
        involved): an unsatisfiable answer is then a proof about all traces."""
        return self.state.complete

    @complete.setter
    def complete(self, value: bool) -> None:
        self.state.complete = value

    @property
    def measures(self) -> dict[str, A.MeasureType]:
        """Each measure's type, by name."""
        return self.state.measures

    @property
    def slots(self) -> list[Slot]:
        """Every slot, in the order created: the probes, then the unfolding's."""
        return self.state.slots

    @property
    def by_event(self) -> dict[str, list[Slot]]:
        """The slots of each event."""
        return self.state.by_event

    @property
    def rules_by_event(self) -> dict[str, list[A.Rule]]:
        """The rules each event triggers."""
        return self.state.rules_by_event

    @property
    def rule_lit(self) -> dict[str, Z3]:
        """Each rule's assumption literal, by name."""
        return self.state.rule_lit

    @property
    def relation_lit(self) -> list[Z3]:
        """Each relation's assumption literal, in file order."""
        return self.state.relation_lit

    @property
    def fallbacks(self) -> list[Fallback]:
        """The snapshots of the ``otherwise`` responses encoded so far (for witnesses)."""
        return self.state.fallbacks

    # ------------------------------------------------------------------ slots
    def _slot(self, event: str, depth: int, why: str) -> Slot:
        n = next(self.state.ids)
        snap = {m: self.terms.var(m, f"s{n}") for m in self.state.measures}
        s = Slot(
            n,
            event,
            depth,
            z3.Real(f"t{n}", self.state.ctx),
            z3.Int(f"p{n}", self.state.ctx),
            z3.Bool(f"in{n}", self.state.ctx),
            snap,
            why,
        )
        self.state.slots.append(s)
        self.state.by_event.setdefault(event, []).append(s)
        self.state.solver.add(s.t >= 0)
        self.terms.domain(snap)
        return s

    def probe(self, event: str, why: str = "probe") -> Slot:
        """An occurrence of ``event`` that is part of the trace (the question is about it)."""
        s = self._slot(event, 0, why)
        self.state.solver.add(s.present)
        return s

    def free(self, event: str, why: str = "probe") -> Slot:
        """An occurrence of ``event`` the question may or may not include (its presence is
        part of the question's goal)."""
        return self._slot(event, 0, why)

    def demand(self, slot: Slot, response: A.Response | None, *, breaches: bool = False) -> None:
        """A question's formula will ask ``response`` of ``slot``: unfold a slot for every
        occurrence it names (negated ones too: denying a prohibition needs an occurrence).
        With ``breaches``, ``response`` is a rule's (whose slots the unfolding creates
        anyway): only the occurrences that break its prohibitions."""
        if response is not None:
            found = list(_occurrences(response, everything=True))
            if breaches:  # less what the rule's own demands already unfold
                for owed in _occurrences(response, everything=False):
                    found.remove(owed)
            self.state.extra.append((slot, found))

    def unfold(self, *, children: bool = True) -> None:
        """Create the demanded slots, breadth first, at most ``bound`` per event, and add
        the constraints that hold of every trace (order, rules, relations). Without
        ``children``, only the probes: a question about the values one trigger reads."""
        if not children:
            self.state.unfolded = True
            self.refusals.settle()  # no rule encoded: a refusal asked later has every case at once
            return
        queue: deque[tuple[Slot, str, str]] = deque()
        for s in list(self.state.slots):
            queue.extend((s, e, why) for e, why in self._demands(s))
        for s, extra in self.state.extra:
            queue.extend((s, e, why) for e, why in extra)
        while queue:
            self.terms.on_time()
            parent, event, why = queue.popleft()
            if len(self.state.by_event.get(event, ())) >= self.state.bound:
                self.state.complete = False
                continue
            child = self._slot(event, parent.depth + 1, why)
            queue.extend((child, e, w) for e, w in self._demands(child))
        if len(self.state.slots) > 1:
            self.state.solver.add(z3.Distinct(*(s.pos for s in self.state.slots)))
        self.state.unfolded = True
        self.priorities.prepare(self.state.slots)
        self.refusals.register(self.state.slots)
        for s in self.state.slots:
            for r in self.state.rules_by_event.get(s.event, ()):
                self.terms.on_time()
                self.state.solver.add(
                    z3.Implies(self.state.rule_lit[r.name], self.obligations.rule_holds(r, s))
                )
        for lit, rel in zip(self.state.relation_lit, self.state.spec.relations):
            self.state.solver.add(z3.Implies(lit, self.relations.holds(rel)))
        self.priorities.settle()
        self.refusals.settle()

    def _demands(self, s: Slot) -> Iterator[tuple[str, str]]:
        """The events an occurrence ``s`` can need (with why): what its rules owe, what can
        refuse it, what the relations ask of it."""
        for r in self.state.rules_by_event.get(s.event, ()):
            for e, why in _occurrences(r.response, everything=False):
                yield e, f"{r.name}: {why}"
            # an obligation with an otherwise can be refused, which moves its fallback: the
            # occurrence that raises the refusing prohibition may be what a trace needs
            for e in fallible_events(r.response):
                for trigger in sorted(self.state.refusers.get(e, ())):
                    yield trigger, f"may refuse {e} of {r.name}"
            # a firing of a higher rule may cancel this one: its trigger may be what a trace needs
            for event in dict.fromkeys(h.trigger.event for h in self.priorities.higher(r.name)):
                yield event, f"may cancel {r.name}"
        yield from self.relations.demands(s.event)

    # ------------------------------------------------------------------ formulas most questions ask for
    def truth(self, e: A.Expr | None, snap: dict[str, Z3]) -> Z3:
        """The condition ``e`` on a snapshot (None: true): :meth:`Terms.truth`."""
        return self.terms.truth(e, snap)

    def seconds(self, d: A.Duration, snap: dict[str, Z3]) -> Z3:
        """A duration in seconds: :meth:`Terms.seconds`."""
        return self.terms.seconds(d, snap)

    def chosen(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], semantics: HedgeSemantics | None = None
    ) -> list[Z3]:
        """For each clause (0: the default), when it applies: :meth:`Terms.chosen`."""
        return self.terms.chosen(defeaters, snap, semantics)

    def chosen_at(self, response: A.Response, clause: int, snap: dict[str, Z3]) -> Z3:
        """Clause ``clause`` of ``response`` applies on ``snap``."""
        return self.terms.chosen_at(response, clause, snap)

    def each_clause(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], ask: Callable[[int, Z3], None]
    ) -> None:
        """``ask(k, applies)`` for every clause ``k``, in linear time: :meth:`Terms.each_clause`."""
        self.terms.each_clause(defeaters, snap, ask)

    def assumptions(self, snap: dict[str, Z3]) -> Z3:
        """The measure relations on one snapshot, each guarded by its relation literal."""
        return self.relations.assumptions(snap)

    def fires(self, rule: A.Rule, x: Slot) -> Z3:
        """``x`` is present and triggers ``rule``."""
        return self.terms.fires(rule, x)

    # ------------------------------------------------------------------ solving
    def check(self, assumptions: Sequence[Z3]) -> z3.CheckSatResult:
        """Solve under ``assumptions`` (rule and relation literals, goal literals)."""
        assert self.state.unfolded, "unfold() first"
        if self.state.deadline is None:
            return self.state.solver.check(*assumptions)
        self.state.deadline.check()
        self.state.solver.set("timeout", question_ms(self.state.timeout_ms, self.state.deadline))
        answer = self.state.solver.check(*assumptions)
        if answer == z3.unknown and self.state.deadline.passed():
            raise OutOfTime  # the deadline, not the question's own limit, cut it short
        return answer

    def fresh(self, name: str) -> Z3:
        """A new assumption literal."""
        return self.terms.fresh(name)


def fallible_events(resp: A.Response | None) -> Iterator[str]:
    """The events of the obligations in ``resp`` that have an ``otherwise`` (and no ``else``):
    a prohibition can refuse them, and their fallback then starts at once."""
    if resp is None:
        return
    for it in resp.items:
        if not it.occurrence.negated and it.otherwise is not None and it.alternative is None:
            yield it.occurrence.event
        yield from fallible_events(it.otherwise)
    for d in resp.defeaters:
        yield from fallible_events(d.response)


def _occurrences(resp: A.Response | None, *, everything: bool) -> Iterator[tuple[str, str]]:
    """The events ``resp`` can owe, with where: every positive occurrence, and the event
    of a prohibition that has an ``otherwise`` (breaking it starts the fallback); with
    ``everything``, every event it names."""
    if resp is None:
        return
    for it in resp.items:
        occ = it.occurrence
        if not occ.negated or it.otherwise is not None or everything:
            yield occ.event, f"{'not ' if occ.negated else ''}{occ.event}"
        yield from _occurrences(it.otherwise, everything=everything)
        yield from _occurrences(it.alternative, everything=everything)
    for d in resp.defeaters:
        yield from _occurrences(d.response, everything=everything)


__all__ = [
    "MAX_SECONDS",
    "Z3",
    "After",
    "Encoding",
    "Fallback",
    "Slot",
    "as_float",
    "clause_items",
    "fallible_events",
]
