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
deadline), and the event that ends an ``until`` relation. When the unfolding finishes
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
of the rules' meaning). One known limit: only a rule's own clause items refuse; a
prohibition inside an ``otherwise`` or a braced clause does not, where the reference's does
(:class:`cosleec.analysis.checks.Analysis` names such rules per file).
"""

from __future__ import annotations

import contextlib
import itertools
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import z3

from cosleec.analysis.deadline import Deadline, OutOfTime, question_ms
from cosleec.lang import HedgeSemantics, Specification, visit
from cosleec.lang import ast as A

Z3 = Any  # z3's Python API is untyped

MAX_SECONDS = 1e10
"""The longest deadline the reference semantics reads (about 317 years); a longer one is
unknown there, and the response that has it imposes nothing (``semantics.reference``)."""


@dataclass(frozen=True)
class Reading:
    """How rules are read: clause semantics and the deadline of an untimed obligation.

    ``untimed`` None: an untimed obligation must happen at some time after its trigger
    (the runtime's "no deadline"); a number: within that many seconds (LEGOS reads ``0``).
    """

    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
    untimed: float | None = None


@dataclass(eq=False)
class Slot:
    """One possible occurrence of ``event``: present or not, with its time and snapshot."""

    id: int
    event: str
    depth: int
    t: Z3
    pos: Z3
    present: Z3
    snap: dict[str, Z3]
    why: str = ""  # what it may fulfil, for a witness's timeline


@dataclass(eq=False)
class Fallback:
    """The snapshot an ``otherwise`` that starts at a deadline reads, and when it starts."""

    at: Z3
    started: Z3
    snap: dict[str, Z3]


@dataclass(frozen=True)
class After:
    """Which occurrences come after the step that raised an obligation: after slot ``slot``
    in causal order, or strictly after time ``at`` (an ``otherwise`` started by a deadline)."""

    slot: Slot | None = None
    at: Z3 = None

    def __call__(self, y: Slot) -> Z3:
        """``y`` comes after the raising step."""
        if self.slot is not None:
            x = self.slot
            if y is x:
                return z3.BoolVal(False, y.present.ctx)
            return z3.Or(y.t > x.t, z3.And(y.t == x.t, y.pos > x.pos))
        return y.t > self.at


class Encoding:
    """The traces of ``spec`` around some probe occurrences, as z3 constraints.

    Use: create probes with :meth:`probe`, declare what a question's own formula will need
    with :meth:`demand`, then :meth:`unfold`; after that, :meth:`holds` and :meth:`rule_holds`
    build formulas over the slots, and :meth:`check` solves under assumption literals.
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
        self.ctx = ctx if ctx is not None else z3.Context()
        self.spec = spec
        self.constants = constants
        self.reading = reading
        self.bound = max(1, bound)
        self.measures = {m.name: m.type for m in spec.measures}
        self.solver = z3.Solver(ctx=self.ctx)
        self.solver.set("random_seed", 0)
        self.timeout_ms = timeout_ms
        self.deadline = deadline  # the whole run's (--deadline): checked while building and asking
        if timeout_ms:
            self.solver.set("timeout", timeout_ms)
        self.slots: list[Slot] = []
        self.by_event: dict[str, list[Slot]] = {}
        self.fallbacks: list[Fallback] = []
        self.bans: dict[str, list[_Ban]] = {}
        self._guard: Z3 = z3.BoolVal(True, self.ctx)  # when what is being encoded is in force
        self._situation = False  # encoding a concern's or purpose's response (nothing refuses it)
        self.rules_by_event: dict[str, list[A.Rule]] = {}
        for r in spec.rules:
            self.rules_by_event.setdefault(r.trigger.event, []).append(r)
        self.rule_lit = {r.name: z3.Bool(f"rule!{i}", self.ctx) for i, r in enumerate(spec.rules)}
        self.relation_lit = [z3.Bool(f"relation!{i}", self.ctx) for i in range(len(spec.relations))]
        self.complete = not any(isinstance(r, A.UntilRelation) for r in spec.relations)
        self._refusers: dict[str, set[str]] = {}  # event -> the triggers of rules that can forbid it
        for r in spec.rules:
            for _, it in clause_items(r.response):
                if it.occurrence.negated:
                    self._refusers.setdefault(it.occurrence.event, set()).add(r.trigger.event)
        self._extra: list[tuple[Slot, list[tuple[str, str]]]] = []
        self._ids = itertools.count()
        self._fresh = itertools.count()
        self._unfolded = False
        self._choices: dict[tuple[int, int, HedgeSemantics], tuple[object, object, list[Z3]]] = {}
        self._truths: dict[tuple[int, int], tuple[object, object, Z3]] = {}

    # ------------------------------------------------------------------ slots
    def _slot(self, event: str, depth: int, why: str) -> Slot:
        n = next(self._ids)
        snap = {m: self._var(m, f"s{n}") for m in self.measures}
        s = Slot(
            n,
            event,
            depth,
            z3.Real(f"t{n}", self.ctx),
            z3.Int(f"p{n}", self.ctx),
            z3.Bool(f"in{n}", self.ctx),
            snap,
            why,
        )
        self.slots.append(s)
        self.by_event.setdefault(event, []).append(s)
        self.solver.add(s.t >= 0)
        self._domain(snap)
        return s

    def _var(self, measure: str, prefix: str) -> Z3:
        t = self.measures[measure]
        name = f"{prefix}!{measure}"
        if isinstance(t, A.BooleanType):
            return z3.Bool(name, self.ctx)
        if isinstance(t, A.ScaleType):
            return z3.Int(name, self.ctx)
        return z3.Real(name, self.ctx)

    def _domain(self, snap: dict[str, Z3]) -> None:
        for m, v in snap.items():
            t = self.measures[m]
            if isinstance(t, A.ScaleType):
                self.solver.add(v >= 0, v < len(t.literals))

    def probe(self, event: str, why: str = "probe") -> Slot:
        """An occurrence of ``event`` that is part of the trace (the question is about it)."""
        s = self._slot(event, 0, why)
        self.solver.add(s.present)
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
            self._extra.append((slot, found))

    def unfold(self, *, children: bool = True) -> None:
        """Create the demanded slots, breadth first, at most ``bound`` per event, and add
        the constraints that hold of every trace (order, rules, relations). Without
        ``children``, only the probes: a question about the values one trigger reads."""
        if not children:
            self._unfolded = True
            return
        queue: deque[tuple[Slot, str, str]] = deque()
        for s in list(self.slots):
            queue.extend((s, e, why) for e, why in self._demands(s))
        for s, extra in self._extra:
            queue.extend((s, e, why) for e, why in extra)
        while queue:
            self._on_time()
            parent, event, why = queue.popleft()
            if len(self.by_event.get(event, ())) >= self.bound:
                self.complete = False
                continue
            child = self._slot(event, parent.depth + 1, why)
            queue.extend((child, e, w) for e, w in self._demands(child))
        if len(self.slots) > 1:
            self.solver.add(z3.Distinct(*(s.pos for s in self.slots)))
        self._unfolded = True
        self._register_bans()
        for s in self.slots:
            for r in self.rules_by_event.get(s.event, ()):
                self._on_time()
                self.solver.add(z3.Implies(self.rule_lit[r.name], self.rule_holds(r, s)))
        for lit, rel in zip(self.relation_lit, self.spec.relations):
            self.solver.add(z3.Implies(lit, self._relation(rel)))

    def _demands(self, s: Slot) -> Iterator[tuple[str, str]]:
        for r in self.rules_by_event.get(s.event, ()):
            for e, why in _occurrences(r.response, everything=False):
                yield e, f"{r.name}: {why}"
            # an obligation with an otherwise can be refused, which moves its fallback: the
            # occurrence that raises the refusing prohibition may be what a trace needs
            for e in fallible_events(r.response):
                for trigger in sorted(self._refusers.get(e, ())):
                    yield trigger, f"may refuse {e} of {r.name}"
        for rel in self.spec.relations:
            if isinstance(rel, A.EventRelation):
                if rel.kind == "witness" and s.event == rel.first:
                    yield rel.second, f"witness {rel.first} {rel.second}"
                elif rel.kind == "equal" and s.event in (rel.first, rel.second):
                    other = rel.second if s.event == rel.first else rel.first
                    yield other, f"equal {rel.first} {rel.second}"
                elif rel.kind == "happenBefore" and s.event == rel.second:
                    yield rel.first, f"happenBefore {rel.first} {rel.second}"
            elif isinstance(rel, A.EventMeasureRelation) and rel.kind == "causation" and s.event != rel.event:
                yield rel.event, f"causation {rel.event}"
            elif isinstance(rel, A.UntilRelation) and s.event == rel.trigger.event:
                yield rel.until_event, f"until {rel.until_event}"  # what may end it

    # ------------------------------------------------------------------ expressions
    def truth(self, e: A.Expr | None, snap: dict[str, Z3]) -> Z3:
        """The condition ``e`` on a snapshot (None: true); built once per condition and
        snapshot (a question asks a trigger's condition several times)."""
        if e is None:
            return z3.BoolVal(True, self.ctx)
        key = (id(e), id(snap))
        known = self._truths.get(key)
        if known is None:
            known = self._truths[key] = (e, snap, self._truth(e, snap))  # the keys' objects kept alive
        return known[2]

    def _truth(self, e: A.Expr, snap: dict[str, Z3]) -> Z3:
        if isinstance(e, A.BoolLit):
            return z3.BoolVal(e.value, self.ctx)
        if isinstance(e, A.Name):
            return snap[e.name]
        if isinstance(e, A.Not):
            return z3.Not(self.truth(e.operand, snap))
        if isinstance(e, A.BinOp) and e.op in ("and", "or"):
            # a chain read as one n-ary term, without recursion: a generated condition of
            # 50,000 terms is as deep (issue 28), and so would the z3 term be
            parts = [self.truth(t, snap) for t in visit.terms(e)]
            return z3.And(*parts) if e.op == "and" else z3.Or(*parts)
        if isinstance(e, A.Compare):
            if self._boolean(e.left) or self._boolean(e.right):
                a, b = self.truth(e.left, snap), self.truth(e.right, snap)
            else:
                scale = self._scale(e.left) or self._scale(e.right)
                a, b = self.value(e.left, snap, scale), self.value(e.right, snap, scale)
            return {
                "<": lambda: a < b,
                "<=": lambda: a <= b,
                ">": lambda: a > b,
                ">=": lambda: a >= b,
                "=": lambda: a == b,
                "<>": lambda: a != b,
            }[e.op]()
        raise AssertionError(f"not a condition: {e!r}")

    def value(self, e: A.Expr, snap: dict[str, Z3], scale: A.ScaleType | None = None) -> Z3:
        """A numeric (or scale position) expression on a snapshot."""
        if isinstance(e, A.IntLit):
            return z3.IntVal(e.value, self.ctx) if scale is not None else z3.RealVal(e.value, self.ctx)
        if isinstance(e, A.Name):
            if e.name in self.measures:
                return snap[e.name]
            if e.name in self.constants:
                v = self.constants[e.name]
                return z3.IntVal(v, self.ctx) if scale is not None else z3.RealVal(v, self.ctx)
            if scale is not None and e.name in scale.literals:
                return z3.IntVal(scale.literals.index(e.name), self.ctx)
            raise AssertionError(f"unresolved name {e.name!r}")
        if isinstance(e, A.BinOp) and e.op in ("+", "-", "*"):
            a, b = self.value(e.left, snap, scale), self.value(e.right, snap, scale)
            return a + b if e.op == "+" else a - b if e.op == "-" else a * b
        raise AssertionError(f"not a number: {e!r}")

    def _boolean(self, e: A.Expr) -> bool:
        if isinstance(e, A.BoolLit | A.Not | A.Compare):
            return True
        if isinstance(e, A.BinOp):
            return e.op in ("and", "or")
        return isinstance(e, A.Name) and isinstance(self.measures.get(e.name), A.BooleanType)

    def _scale(self, e: A.Expr) -> A.ScaleType | None:
        if isinstance(e, A.Name):
            t = self.measures.get(e.name)
            if isinstance(t, A.ScaleType):
                return t
        return None

    def seconds(self, d: A.Duration, snap: dict[str, Z3]) -> Z3:
        """A duration in seconds."""
        return self.value(d.value, snap) * A.TIME_UNITS.get(d.unit.lower(), 1)

    # ------------------------------------------------------------------ responses
    def chosen(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], semantics: HedgeSemantics | None = None
    ) -> list[Z3]:
        """For each clause (0: the default), the condition under which it applies (under
        ``semantics``, by default the reading's); built once per clause list and snapshot.

        Linear in the clauses (issue 28): what clause ``i`` needs besides its own condition --
        that no later condition holds (last-wins), or that every earlier one does (nested) --
        is one literal per clause, defined from its neighbour's (:meth:`_chain`), where
        spelling each out made the choice among ``k`` clauses ``k**2`` terms."""
        sem = semantics or self.reading.semantics
        key = (id(defeaters), id(snap), sem)
        known = self._choices.get(key)
        if known is not None:
            return known[2]
        c = [self.truth(d.condition, snap) for d in defeaters]
        k = len(c)
        if sem == HedgeSemantics.LAST_WINS:
            none_from = self._chain([z3.Not(x) for x in c], "none")  # no condition i.. holds
            out = [none_from[0]] + [z3.And(c[i], none_from[i + 1]) for i in range(k)]
        else:
            every = self._chain(c[::-1], "all")[::-1]  # every[i]: conditions 0..i-1 all hold
            out = [z3.Not(c[0])] if c else [z3.BoolVal(True, self.ctx)]
            out += [z3.And(every[i + 1], z3.Not(c[i + 1])) if i + 1 < k else every[k] for i in range(k)]
        self._choices[key] = (defeaters, snap, out)  # the keys' objects kept alive: ids stay theirs
        return out

    def _chain(self, parts: list[Z3], name: str) -> list[Z3]:
        """``v`` with ``v[i]`` equivalent to ``And(parts[i:])`` (``v[len(parts)]`` true): each a
        fresh literal defined as its part and the next one, so the chain is linear in size and
        one level deep in z3 whatever its length."""
        v = [z3.BoolVal(True, self.ctx)]
        for p in reversed(parts):
            self._on_time()
            lit = z3.Bool(f"{name}!{next(self._fresh)}", self.ctx)
            self.solver.add(lit == z3.And(p, v[-1]))
            v.append(lit)
        return v[::-1]

    def each_clause(
        self, defeaters: Sequence[A.Defeater], snap: dict[str, Z3], ask: Callable[[int, Z3], None]
    ) -> None:
        """``ask(k, applies)`` for every clause ``k`` (0: the default), where ``applies`` is,
        while ``ask`` runs, what it takes for clause ``k`` to apply on ``snap`` under the
        reading's semantics. One question per clause in linear time (issue 28): what the
        other clauses must not do is asserted as the walk goes, in a solver scope closed
        after -- from the last clause back under last-wins (its condition does not hold),
        from the first on under nested (it does) -- rather than spelled out per question.
        ``ask`` asks and builds nothing that adds to the solver (:meth:`chosen` does): what it
        added would go with the scope."""
        c = [self.truth(d.condition, snap) for d in defeaters]
        true = z3.BoolVal(True, self.ctx)
        self.solver.push()
        try:
            if self.reading.semantics == HedgeSemantics.LAST_WINS:
                for k in range(len(c), -1, -1):
                    ask(k, c[k - 1] if k else true)
                    if k:
                        self.solver.add(z3.Not(c[k - 1]))
            else:
                for k in range(len(c) + 1):
                    ask(k, z3.Not(c[k]) if k < len(c) else true)
                    if k < len(c):
                        self.solver.add(c[k])
        finally:
            self.solver.pop()

    def chosen_at(self, response: A.Response, clause: int, snap: dict[str, Z3]) -> Z3:
        """Clause ``clause`` of ``response`` applies on ``snap``."""
        return self.chosen(response.defeaters, snap)[clause]

    def assumptions(self, snap: dict[str, Z3]) -> Z3:
        """The measure relations on one snapshot, each guarded by its relation literal."""
        return z3.And(
            *(
                z3.Implies(lit, self._measure_relation(rel, snap))
                for lit, rel in zip(self.relation_lit, self.spec.relations)
                if isinstance(rel, A.MeasureRelation)
            ),
            self.ctx,
        )

    def rule_holds(self, rule: A.Rule, x: Slot) -> Z3:
        """``rule`` is met at slot ``x``: if ``x`` is present and triggers it, its response holds."""
        fires = z3.And(x.present, self.truth(rule.trigger.condition, x.snap))
        return z3.Implies(fires, self.holds(rule.response, x, guard=fires))

    def fires(self, rule: A.Rule, x: Slot) -> Z3:
        """``x`` is present and triggers ``rule``."""
        return z3.And(x.present, self.truth(rule.trigger.condition, x.snap))

    def holds(
        self,
        response: A.Response | None,
        x: Slot,
        *,
        untimed: float | str | None = "reading",
        guard: Z3 | None = None,
        situation: bool = False,
    ) -> Z3:
        """``response``, started by slot ``x``, is met (``untimed`` overrides the reading's).
        ``guard`` says when the response is in force (default: when ``x`` is present): an
        ``otherwise`` counts as started only then (:attr:`Fallback.started`). A
        ``situation`` (a concern's or purpose's response) describes what occurs, not what a
        rule owes: no prohibition refuses it."""
        u = self.reading.untimed if untimed == "reading" else untimed
        assert not isinstance(u, str)
        self._guard = x.present if guard is None else guard
        self._situation = situation
        try:
            return self._response(response, x.t, After(slot=x), x.snap, u)
        finally:
            self._situation = False

    @contextlib.contextmanager
    def _within(self, condition: Z3) -> Iterator[None]:
        """Encode under ``condition`` too (a clause chosen, a primary missed)."""
        outer = self._guard
        self._guard = z3.And(outer, condition)
        try:
            yield
        finally:
            self._guard = outer

    def _response(
        self,
        resp: A.Response | None,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        if resp is None:
            return z3.BoolVal(True, self.ctx)
        if not resp.defeaters:
            items = z3.And(*(self._item(it, start, after, snap, untimed) for it in resp.items), self.ctx)
            known = self._in_range(resp, snap)
            return items if known is None else z3.Or(z3.Not(known), items)
        conds = self.chosen(resp.defeaters, snap)
        parts = []
        for sub, cond in zip([A.Response(resp.items), *(d.response for d in resp.defeaters)], conds):
            self._on_time()  # a rule of thousands of clauses takes seconds to encode
            with self._within(cond):
                parts.append(z3.Implies(cond, self._response(sub, start, after, snap, untimed)))
        return z3.And(*parts, self.ctx)

    def _in_range(self, resp: A.Response, snap: dict[str, Z3]) -> Z3 | None:
        """The deadlines of ``resp``'s items are at most :data:`MAX_SECONDS` long (None: they
        always are). A longer one is unknown to the reference semantics, and a response that
        has one imposes nothing."""
        parts = []
        for it in resp.items:
            lim = it.occurrence.limit
            for d in () if lim is None else (lim.hi, lim.lo):
                if d is None:
                    continue
                v = self.seconds(d, snap)
                simple = z3.simplify(v)
                if (z3.is_rational_value(simple) or z3.is_int_value(simple)) and abs(
                    as_float(simple)
                ) <= MAX_SECONDS:
                    continue
                parts.append(z3.And(v >= -MAX_SECONDS, v <= MAX_SECONDS))
        return z3.And(*parts) if parts else None

    def window(
        self, occ: A.Occurrence, has_otherwise: bool, start: Z3, snap: dict[str, Z3], untimed: float | None
    ) -> tuple[Z3, Z3 | None]:
        """The absolute window ``[lo, hi]`` of an occurrence started at ``start`` (hi None: none)."""
        if occ.limit is not None:
            hi = start + self.seconds(occ.limit.hi, snap)
            lo = start + self.seconds(occ.limit.lo, snap) if occ.limit.lo is not None else start
            return lo, hi
        if occ.eventually:
            return start, None
        if occ.negated or has_otherwise:
            return start, start
        return start, None if untimed is None else start + untimed

    def occurs(self, event: str, lo: Z3, hi: Z3 | None, after: Callable[[Slot], Z3]) -> Z3:
        """Some present occurrence of ``event`` in ``[lo, hi]`` after the raising step."""
        return z3.Or(
            *(
                z3.And(y.present, lo <= y.t, *([y.t <= hi] if hi is not None else []), after(y))
                for y in self.by_event.get(event, ())
            ),
            self.ctx,
        )

    def _item(
        self,
        it: A.ResponseItem,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        occ = it.occurrence
        lo, hi = self.window(occ, it.otherwise is not None, start, snap, untimed)
        if occ.negated:
            ok = z3.Not(self.occurs(occ.event, lo, hi, after))
            if it.otherwise is None:
                return ok
            breaks = [
                (y, z3.And(y.present, lo <= y.t, *([y.t <= hi] if hi is not None else []), after(y)))
                for y in self.by_event.get(occ.event, ())
            ]
            firsts = []
            for y, by in breaks:
                first = z3.And(by, *(z3.Not(z3.And(bz, _before(z, y))) for (z, bz) in breaks if z is not y))
                with self._within(first):
                    fallback = self._response(it.otherwise, y.t, After(slot=y), y.snap, untimed)
                firsts.append(z3.And(first, fallback))
            return z3.Or(ok, *firsts)
        ok = self.occurs(occ.event, lo, hi, after)
        if it.alternative is not None:
            ok = z3.Or(ok, self._branch(it.alternative, start, after, snap, untimed))
        if it.otherwise is None and it.alternative is None and hi is not None and not self._situation:
            # refused at once by a prohibition that covers its whole window: a breach, even if
            # the event then occurs (breaking that prohibition, whose own otherwise may be met)
            refused, _, _ = self._refusal(occ.event, lo, hi, start, after, snap)
            if refused is not None:
                ok = z3.And(z3.Not(refused), ok)
        if it.otherwise is not None and hi is not None:
            at = z3.If(hi < lo, start, hi)
            fresh = {m: self._var(m, f"o{next(self._fresh)}") for m in self.measures}
            refused, when, reads = (
                self._refusal(occ.event, lo, hi, start, after, snap)
                if it.alternative is None and not self._situation  # an `else` may still meet it
                else (None, None, [])
            )
            if refused is not None:  # refused: its fallback starts then, not at the deadline
                ok = z3.And(z3.Not(refused), ok)
                at = z3.If(refused, when, at)
                for cond, values in reads:
                    self.solver.add(
                        z3.Implies(cond, z3.And(*(fresh[m] == values[m] for m in fresh), self.ctx))
                    )
            fb = Fallback(at, z3.And(self._guard, z3.Not(ok)), fresh)
            self._domain(fb.snap)
            for other in self.fallbacks:
                self.solver.add(
                    z3.Implies(
                        z3.And(fb.started, other.started, fb.at == other.at),
                        z3.And(*(fb.snap[m] == other.snap[m] for m in self.measures), self.ctx),
                    )
                )
            for lit, rel in zip(self.relation_lit, self.spec.relations):
                on_fallback = self._relation_on(rel, fb)
                if on_fallback is not None:
                    self.solver.add(z3.Implies(lit, on_fallback))
            self.fallbacks.append(fb)
            later = _FallbackStart(at, hi < lo, after, refused, when)
            with self._within(z3.Not(ok)):
                fallback = self._response(it.otherwise, at, later, fb.snap, untimed)
            ok = z3.Or(ok, fallback)
        return ok

    def _refusal(
        self, event: str, lo: Z3, hi: Z3, start: Z3, after: Callable[[Slot], Z3], snap: dict[str, Z3]
    ) -> tuple[Z3 | None, Z3, list[tuple[Z3, dict[str, Z3]]]]:
        """When a prohibition in force covers an obligation's whole remaining window, the
        reference semantics refuses it at once (the moment the second of the two is raised)
        and starts its ``otherwise`` then. Returns (refused, when, [(case, values read)]);
        prohibitions inside an ``otherwise`` are not counted (only a rule's own clauses)."""
        cases = []
        for b in self.bans.get(event, ()):
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
                for y in self.by_event.get(event, ())
            ]
            in_force = z3.And(in_force, z3.Not(z3.And(z3.Not(b_later), z3.Or(*broken, self.ctx))))

            def before_refusal(y: Slot, b_later: Z3 = b_later, now: Z3 = now, b: _Ban = b) -> Z3:
                return z3.And(after(y), z3.Or(y.t < now, z3.And(y.t == now, b_later, y.pos < b.slot.pos)))

            met_before = self.occurs(event, lo, hi, before_refusal)
            cond = z3.And(in_force, covers, z3.Not(met_before))
            values = {m: z3.If(b_later, b.slot.snap[m], snap[m]) for m in snap}
            cases.append((cond, now, values))
        if not cases:
            return None, None, []
        refused = z3.Or(*(c for c, _, _ in cases))
        when = z3.Real(f"refused{next(self._fresh)}", self.ctx)
        self.solver.add(z3.Implies(refused, z3.Or(*(z3.And(c, when == n) for c, n, _ in cases))))
        for c, n, _ in cases:
            self.solver.add(z3.Implies(c, when <= n))
        reads = [(z3.And(c, when == n), v) for c, n, v in cases]
        return refused, when, reads

    def _register_bans(self) -> None:
        """The prohibitions each slot's rules can raise (a clause's own items), for refusals."""
        for x in self.slots:
            for r in self.rules_by_event.get(x.event, ()):
                self._on_time()
                for k, it in clause_items(r.response):
                    occ = it.occurrence
                    if not occ.negated:
                        continue
                    lo, hi = self.window(occ, it.otherwise is not None, x.t, x.snap, self.reading.untimed)
                    known = self._in_range(A.Response((it,)), x.snap)  # an unreadable window forbids nothing
                    active = z3.And(
                        self.rule_lit[r.name],
                        self.fires(r, x),
                        self.chosen_at(r.response, k, x.snap),
                        *([known] if known is not None else []),
                    )
                    self.bans.setdefault(occ.event, []).append(_Ban(x, active, lo, hi))

    def _branch(
        self,
        resp: A.Response,
        start: Z3,
        after: Callable[[Slot], Z3],
        snap: dict[str, Z3],
        untimed: float | None,
    ) -> Z3:
        """An ``else`` alternative: every item of its chosen clause occurs in its own window."""
        if resp.defeaters:
            conds = self.chosen(resp.defeaters, snap)
            parts = [z3.Implies(conds[0], self._branch(A.Response(resp.items), start, after, snap, untimed))]
            for d, cond in zip(resp.defeaters, conds[1:]):
                sub = d.response
                parts.append(
                    z3.Implies(
                        cond,
                        z3.BoolVal(False, self.ctx)
                        if sub is None
                        else self._branch(sub, start, after, snap, untimed),
                    )
                )
            return z3.And(*parts, self.ctx)
        out = []
        for it in resp.items:
            if it.occurrence.negated:
                return z3.BoolVal(False, self.ctx)
            lo, hi = self.window(it.occurrence, it.otherwise is not None, start, snap, untimed)
            out.append(self.occurs(it.occurrence.event, lo, hi, after))
        return z3.And(*out, self.ctx) if out else z3.BoolVal(False, self.ctx)

    # ------------------------------------------------------------------ relations
    def _relation(self, rel: A.Relation) -> Z3:
        every = self.slots
        if isinstance(rel, A.EventRelation):
            a, b = self.by_event.get(rel.first, []), self.by_event.get(rel.second, [])

            def with_(xs: list[Slot], ys: list[Slot]) -> Z3:
                return z3.And(
                    *(
                        z3.Implies(x.present, z3.Or(*(z3.And(y.present, y.t == x.t) for y in ys), self.ctx))
                        for x in xs
                    ),
                    self.ctx,
                )

            if rel.kind == "witness":
                return with_(a, b)
            if rel.kind == "equal":
                return z3.And(with_(a, b), with_(b, a))
            if rel.kind in ("mutualExclusive", "isContradictoryWith"):
                return z3.And(
                    *(z3.Not(z3.And(x.present, y.present, x.t == y.t)) for x in a for y in b if x is not y),
                    self.ctx,
                )
            if rel.kind == "happenBefore":
                return z3.And(
                    *(
                        z3.Implies(y.present, z3.Or(*(z3.And(x.present, x.t < y.t) for x in a), self.ctx))
                        for y in b
                    ),
                    self.ctx,
                )
            raise AssertionError(f"unknown relation {rel.kind}")
        if isinstance(rel, A.MeasureRelation):
            return z3.And(
                *(z3.Implies(s.present, self._measure_relation(rel, s.snap)) for s in every), self.ctx
            )
        if isinstance(rel, A.EventMeasureRelation):
            es = self.by_event.get(rel.event, [])
            if rel.kind == "causation":
                return z3.And(
                    *(
                        z3.Implies(
                            z3.And(s.present, self.truth(rel.condition, s.snap)),
                            z3.Or(*(z3.And(y.present, y.t == s.t) for y in es), self.ctx),
                        )
                        for s in every
                    ),
                    self.ctx,
                )
            want = self.truth if rel.kind == "includes" else (lambda c, s: z3.Not(self.truth(c, s)))
            return z3.And(*(z3.Implies(s.present, want(rel.condition, s.snap)) for s in es), self.ctx)
        if isinstance(rel, A.UntilRelation):
            starts = self.by_event.get(rel.trigger.event, [])
            ends = self.by_event.get(rel.until_event, [])
            parts = []
            for a_ in starts:
                on = z3.And(a_.present, self.truth(rel.trigger.condition, a_.snap))
                for y in every:
                    after_a = z3.BoolVal(True, self.ctx) if y is a_ else After(slot=a_)(y)  # A's own too
                    stopped = z3.Or(
                        *(
                            z3.And(
                                b.present,
                                self.truth(rel.until_condition, b.snap),
                                After(slot=a_)(b),
                                z3.Not(After(slot=y)(b)),
                            )
                            for b in ends
                        ),
                        self.ctx,
                    )
                    parts.append(
                        z3.Implies(
                            z3.And(on, y.present, after_a, z3.Not(stopped)), self.truth(rel.condition, y.snap)
                        )
                    )
            return z3.And(*parts, self.ctx)
        if isinstance(rel, A.ForRelation):
            starts = self.by_event.get(rel.trigger.event, [])
            parts = []
            for a_ in starts:
                on = z3.And(a_.present, self.truth(rel.trigger.condition, a_.snap))
                end = a_.t + self.seconds(rel.duration, a_.snap)
                for y in every:
                    parts.append(
                        z3.Implies(
                            z3.And(
                                on,
                                y.present,
                                z3.BoolVal(True, self.ctx) if y is a_ else After(slot=a_)(y),
                                y.t <= end,
                            ),
                            self.truth(rel.condition, y.snap),
                        )
                    )
            return z3.And(*parts, self.ctx)
        raise AssertionError(f"unknown relation {rel!r}")

    def _relation_on(self, rel: A.Relation, fb: Fallback) -> Z3 | None:
        """What ``rel`` says of the values an ``otherwise`` reads (a snapshot at ``fb.at``,
        after every occurrence at that instant); None: nothing."""
        if isinstance(rel, A.MeasureRelation):
            return self._measure_relation(rel, fb.snap)
        if isinstance(rel, A.EventMeasureRelation) and rel.kind == "causation":
            happens = z3.Or(
                *(z3.And(y.present, y.t == fb.at) for y in self.by_event.get(rel.event, ())), self.ctx
            )
            return z3.Implies(z3.And(fb.started, self.truth(rel.condition, fb.snap)), happens)
        if isinstance(rel, A.ForRelation | A.UntilRelation):
            parts = []
            for a_ in self.by_event.get(rel.trigger.event, ()):
                on = z3.And(a_.present, self.truth(rel.trigger.condition, a_.snap), fb.started, a_.t <= fb.at)
                if isinstance(rel, A.ForRelation):
                    inside = fb.at <= a_.t + self.seconds(rel.duration, a_.snap)
                else:
                    inside = z3.Not(
                        z3.Or(
                            *(
                                z3.And(
                                    b.present,
                                    self.truth(rel.until_condition, b.snap),
                                    After(slot=a_)(b),
                                    b.t <= fb.at,
                                )
                                for b in self.by_event.get(rel.until_event, ())
                            ),
                            self.ctx,
                        )
                    )
                parts.append(z3.Implies(z3.And(on, inside), self.truth(rel.condition, fb.snap)))
            return z3.And(*parts, self.ctx)
        return None

    def _measure_relation(self, rel: A.MeasureRelation, snap: dict[str, Z3]) -> Z3:
        p = self.truth(rel.first, snap)
        if rel.kind == "invariant" or rel.second is None:
            return p
        q = self.truth(rel.second, snap)
        if rel.kind == "imply":
            return z3.Implies(p, q)
        if rel.kind == "iff":
            return p == q
        return z3.Implies(p, z3.Not(q))  # mutualExclusive, opposite (docs/reference/sleec-language.md §9.2)

    # ------------------------------------------------------------------ solving
    def check(self, assumptions: Sequence[Z3]) -> z3.CheckSatResult:
        """Solve under ``assumptions`` (rule and relation literals, goal literals)."""
        assert self._unfolded, "unfold() first"
        if self.deadline is None:
            return self.solver.check(*assumptions)
        self.deadline.check()
        self.solver.set("timeout", question_ms(self.timeout_ms, self.deadline))
        answer = self.solver.check(*assumptions)
        if answer == z3.unknown and self.deadline.passed():
            raise OutOfTime  # the deadline, not the question's own limit, cut it short
        return answer

    def _on_time(self) -> None:
        """Stop building once the run's deadline has passed (:class:`OutOfTime`)."""
        if self.deadline is not None:
            self.deadline.check()

    def fresh(self, name: str) -> Z3:
        """A new assumption literal."""
        return z3.Bool(f"{name}!{next(self._fresh)}", self.ctx)


@dataclass(frozen=True)
class _Ban:
    """A prohibition a rule can raise at ``slot``: in force when ``active``, over ``[lo, hi]``."""

    slot: Slot
    active: Z3
    lo: Z3
    hi: Z3 | None


class _FallbackStart:
    """Which occurrences count for an ``otherwise``: strictly after the deadline it follows;
    after the step that raised the obligation when its window closed at once (a negative
    deadline); after the refusal when a prohibition refused the obligation."""

    def __init__(
        self, at: Z3, closed_at_once: Z3, creation: Callable[[Slot], Z3], refused: Z3 | None, when: Z3
    ) -> None:
        self.at, self.closed_at_once, self.creation = at, closed_at_once, creation
        self.refused, self.when = refused, when

    def __call__(self, y: Slot) -> Z3:
        """``y`` comes after the fallback's start."""
        plain = z3.If(self.closed_at_once, self.creation(y), y.t > self.at)
        if self.refused is None:
            return plain
        by_refusal = z3.Or(y.t > self.when, z3.And(y.t == self.when, self.creation(y)))
        return z3.If(self.refused, by_refusal, plain)


def clause_items(resp: A.Response) -> Iterator[tuple[int, A.ResponseItem]]:
    """The top-level items of each clause of a rule's response: (clause, item)."""
    for it in resp.items:
        yield 0, it
    for k, d in enumerate(resp.defeaters, 1):
        if d.response is not None and not d.response.defeaters:
            for it in d.response.items:
                yield k, it


def as_float(v: Z3) -> float:
    """A z3 numeral (integer, rational, or an algebraic number rounded) as a float: the one
    reading of a model's numbers, for witnesses, situations and range checks."""
    if z3.is_int_value(v):
        return float(v.as_long())
    if z3.is_rational_value(v):
        return float(v.numerator_as_long()) / float(v.denominator_as_long())
    if z3.is_algebraic_value(v):
        return float(v.approx(12).as_decimal(12).rstrip("?"))
    raise ValueError(f"not a number: {v}")


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


def _before(z: Slot, y: Slot) -> Z3:
    """``z`` comes before ``y`` in the trace."""
    return z3.Or(z.t < y.t, z3.And(z.t == y.t, z.pos < y.pos))


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
