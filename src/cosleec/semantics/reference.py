"""The reference semantics: a rule set's verdicts on a finite timed trace.

Written straight from the language reference (``docs/reference/sleec-language.md`` §6, §7, §10, §13),
sharing no code with :mod:`cosleec.runtime`, and simple rather than fast: a step looks at
every obligation it can settle, one by one (:mod:`cosleec.semantics.inforce` finds them by
event, instance and deadline, so that a long trace costs time linear in its length: issue
28). It is the oracle the runtime is tested against and what ``cosleec conforms`` runs.
The conventions, each a decision of the reference:

Time and order
    Times are seconds. Steps are taken in trace order; steps at the same time are in
    causal order. An occurrence counts for an obligation only if it comes *after* the step
    that created the obligation (the trigger itself never fulfils its own response).

Snapshots
    A trigger reads the values set by earlier steps (a value set at the same time but
    earlier in the trace is read). An ``otherwise`` that starts at a deadline ``h`` reads
    the values set by every step at a time ``<= h``; one that starts at a prohibition's
    violation reads the values as the violating occurrence found them. Deadlines are
    computed once, on the snapshot of the moment their response starts.

Clauses (§7)
    ``last-wins``: the last clause whose condition holds; ``nested``: the longest prefix of
    conditions that all hold. Braced inner responses choose among their own clauses in the
    same way, when they start. A condition over a measure with no value is unknown
    (Kleene logic); when the choice depends on it the firing is *undetermined* and imposes
    nothing here (what a robot does then is runtime policy, not language semantics).

Windows (§6.4, §10)
    ``E within T`` started at ``t`` is fulfilled by an occurrence in ``[t, t+T]`` (closed at
    both ends) and violated at ``t+T`` once time has passed it; ``within [a, b]`` ignores
    occurrences before ``t+a``. Untimed ``E`` has no deadline (or ``Reading.untimed``:
    ``immediate`` or seconds); ``E eventually`` none. ``not E within T`` is violated by an
    occurrence in ``[t, t+T]`` and respected once time passes ``t+T``; untimed ``not E``
    covers the instant ``[t, t]``; ``not E eventually`` is never respected. A window whose
    end comes before its start (a negative deadline computed from measures) is already
    closed: an obligation is violated at once, a prohibition respected at once.

``otherwise`` (§6.5)
    Starts at the deadline of a missed obligation, or at the occurrence that violates a
    prohibition; its windows count from there. ``otherwise`` after an untimed occurrence
    reads it as ``within 0 seconds``.

``else`` (§6.6)
    ``P else Q``: Q's own clauses are chosen at the trigger; the obligation is fulfilled by
    P in P's window, or when every item of Q has occurred in its own window (anchored at
    the trigger). It is violated when the last of these windows has closed. A branch that
    contains a prohibition never fulfils (fail closed); ``otherwise`` and ``else`` inside Q
    are not read; the ``else`` of a prohibition is ignored (the prohibition binds).

Conflicts (issue 12, no priority)
    When an obligation's whole remaining window ``[max(lo, now), hi]`` lies inside the
    window of a prohibition of the same event that is in force, the rules cannot both be
    met: the prohibition wins. The obligation is *refused* at that moment (a violation by
    conflict) and its ``otherwise`` starts then. Obligations with an ``else`` never
    conflict (the alternative may meet them). A prohibition that covers only part of the
    window is no conflict: the robot can wait.

Priorities (§13; ``H > L``, closed transitively)
    An *instance* is one firing of a rule, active while any of its obligations or
    prohibitions (``otherwise`` included) is pending. ``cancel``: whenever an instance of H
    and one of L are active together, the L instance is cancelled at once (whichever came
    first). ``conflict-aware``: L is kept as long as possible; it is cancelled at the
    deadline ``d`` of an obligation that one of the two owes and the other's prohibition
    forbids at ``d`` (an H obligation forbidden by L; or an L obligation forbidden by H, so
    that L is not violated by respecting H), minus ``Reading.priority_lead`` seconds, and
    before anything else happens at that instant. A cancelled instance imposes nothing
    more: no violation, no ``otherwise``.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from cosleec.lang import (
    CANCEL,
    CONFLICT_AWARE,
    HedgeSemantics,
    Reading,
    Specification,
    closure,
    deeply,
    pairs,
    visit,
)
from cosleec.lang import ast as A
from cosleec.semantics.inforce import InForce, Item
from cosleec.semantics.trace import Step, Value
from cosleec.semantics.verdicts import (
    BLOCKED,
    CANCELLED,
    FULFILLED,
    PENDING,
    RESPECTED,
    VIOLATED,
    Conflict,
    Firing,
    Judgement,
    Verdict,
)

MAX_SECONDS = 1e10  # a window longer than this (about 317 years) is out of range, read as unknown
_AS_SLEEC = Reading()  # SLEEC-TK's reading: last-wins, untimed responses without a deadline, cancel


class _Unknown(Exception):
    """A measure the expression reads has no value."""


def judge(spec: Specification, trace: Iterable[Step], reading: Reading = _AS_SLEEC) -> Judgement:
    """The verdicts of ``spec`` on ``trace`` up to the trace's last time, reading the rules as
    ``reading`` says (its ``priorities`` are added to the rule file's; its ``unknown`` plays
    no part: a firing that depends on a value nobody gave is undetermined here).

    ``spec`` must be checked (names resolved: :func:`cosleec.lang.load`); the trace's names
    are taken as given (:func:`cosleec.semantics.trace.check_trace` checks them).
    """
    steps = list(trace)
    # evaluation recurses once per level of an expression (but along an and/or chain), as
    # the checker's passes do: an expression `cosleec check` accepts is judged in a deep thread
    return deeply(lambda: _Judge(spec, reading).run(steps))


# ---------------------------------------------------------------------------- expressions
class _Eval:
    """Three-valued evaluation of conditions and durations on one snapshot."""

    def __init__(self, spec: Specification) -> None:
        self.measures = {m.name: m.type for m in spec.measures}
        raw = {c.name: c.value for c in spec.definitions if isinstance(c, A.ConstantDecl)}
        self.constants: dict[str, int] = {}
        for name in raw:
            seen: set[str] = set()
            v: int | str = raw[name]
            while isinstance(v, str) and v not in seen:
                seen.add(v)
                v = raw.get(v, v)
            if isinstance(v, int):
                self.constants[name] = v

    def truth(self, e: A.Expr | None, values: Mapping[str, Value]) -> bool | None:
        """True, False, or None when an unknown value decides it (Kleene)."""
        if e is None:
            return True
        if isinstance(e, A.Not):
            x = self.truth(e.operand, values)
            return None if x is None else not x
        if isinstance(e, A.BinOp) and e.op in ("and", "or"):
            # a chain `a and b and ...` read as one n-ary operator, without recursion: a
            # generated condition of 50,000 terms is as deep (issue 28). Kleene: a false
            # term decides `and`, a true one `or`; else an unknown term makes it unknown.
            decides = e.op == "or"
            unknown = False
            for term in visit.terms(e):
                x = self.truth(term, values)
                if x is decides:
                    return decides
                unknown = unknown or x is None
            return None if unknown else not decides
        try:
            return bool(self.value(e, values))
        except _Unknown:
            return None

    def value(self, e: A.Expr, values: Mapping[str, Value], scale: str | None = None) -> object:
        """The value of ``e``; a scale measure or literal is its position (lowest 0)."""
        if isinstance(e, A.BoolLit | A.IntLit):
            return e.value
        if isinstance(e, A.Name):
            if e.name in self.measures:
                if values.get(e.name) is None:
                    raise _Unknown(e.name)
                x = values[e.name]
                t = self.measures[e.name]
                return t.literals.index(str(x)) if isinstance(t, A.ScaleType) else x
            if e.name in self.constants:
                return self.constants[e.name]
            assert scale is not None, f"{e.name} is neither a measure, a constant nor a literal"
            t = self.measures[scale]
            assert isinstance(t, A.ScaleType)
            return t.literals.index(e.name)
        if isinstance(e, A.Not | A.BinOp) and (not isinstance(e, A.BinOp) or e.op in ("and", "or")):
            truth = self.truth(e, values)
            if truth is None:
                raise _Unknown("")
            return truth
        if isinstance(e, A.BinOp):
            a, b = self.value(e.left, values), self.value(e.right, values)
            assert isinstance(a, int | float) and isinstance(b, int | float)
            return a + b if e.op == "+" else a - b if e.op == "-" else a * b
        if isinstance(e, A.Compare):
            s = self._scale(e.left) or self._scale(e.right)
            a, b = self.value(e.left, values, s), self.value(e.right, values, s)
            compare: Callable[[Any, Any], bool] = {
                "<": operator.lt,
                "<=": operator.le,
                ">": operator.gt,
                ">=": operator.ge,
                "=": operator.eq,
                "<>": operator.ne,
            }[e.op]
            return compare(a, b)
        raise AssertionError(f"cannot evaluate {e!r}")

    def _scale(self, e: A.Expr) -> str | None:
        if isinstance(e, A.Name) and isinstance(self.measures.get(e.name), A.ScaleType):
            return e.name
        return None

    def seconds(self, d: A.Duration, values: Mapping[str, Value]) -> float:
        """A duration in seconds (raises _Unknown)."""
        x = self.value(d.value, values)
        assert isinstance(x, int | float)
        try:
            seconds = float(x * A.TIME_UNITS[d.unit])
        except OverflowError:
            raise _Unknown("") from None
        if not -MAX_SECONDS <= seconds <= MAX_SECONDS:  # too long to keep (also NaN): not a deadline
            raise _Unknown("")
        return seconds

    def reads(self, e: A.Expr | None) -> set[str]:
        """The measures ``e`` reads."""
        return {n.name for n in visit.names(e) if n.name in self.measures}


def choose(values: Sequence[bool | None], semantics: HedgeSemantics) -> int | None:
    """§7: the clause that applies (0: the default), None when an unknown value decides it."""
    if semantics == HedgeSemantics.LAST_WINS:
        for i in range(len(values), 0, -1):  # the last clause whose condition holds
            if values[i - 1] is None:
                return None
            if values[i - 1]:
                return i
        return 0
    k = 0  # nested: the longest prefix of conditions that all hold
    for x in values:
        if x is None:
            return None
        if not x:
            break
        k += 1
    return k


# ---------------------------------------------------------------------------- the judge
class _Undetermined(Exception):
    def __init__(self, missing: set[str]) -> None:
        self.missing = missing


class _Judge:
    def __init__(self, spec: Specification, reading: Reading) -> None:
        self.spec = spec
        self.reading = reading
        self.untimed = reading.untimed_seconds  # the deadline of an untimed response (None: none)
        self.eval = _Eval(spec)
        self.rules = {r.name: r for r in spec.rules}
        self.triggered: dict[str, list[A.Rule]] = {}  # event -> the rules it triggers, in file order
        for r in spec.rules:
            self.triggered.setdefault(r.trigger.event, []).append(r)
        self.above = closure([*reading.priorities, *pairs(spec)])
        self.related: dict[str, list[str]] = {}  # rule -> the rules a priority orders it with
        for high, low in sorted(self.above):
            self.related.setdefault(high, []).append(low)
            self.related.setdefault(low, []).append(high)
        self.live = InForce()  # the items in force, indexed (each step touches only its own)
        self.values: dict[str, Value] = {}
        self.items: list[Item] = []
        self.seq = 0
        self.ids = itertools.count(1)
        self.instances = itertools.count(1)
        self.instance_rule: dict[int, str] = {}
        self.keys: dict[int, str] = {}  # an otherwise response (by id) -> its item key prefix
        self.out = Judgement(end=0.0)

    # -------------------------------------------------------------- driver
    def run(self, steps: list[Step]) -> Judgement:
        end = 0.0
        for n, step in enumerate(steps):
            end = step.t
            self.advance(step.t)
            for name, x in step.values.items():
                if x is None:
                    self.values.pop(name, None)
                else:
                    self.values[name] = x
            if step.event is not None:
                self.occur(n, step.t, step.event)
        self.advance(end)
        self.out.end = end
        self.out.verdicts = [i.v for i in self.items]
        return self.out

    # -------------------------------------------------------------- time passing
    def advance(self, now: float) -> None:
        """Everything that happens at times up to ``now`` before the step at ``now``, earliest
        first: conflict-aware cancellations at times <= now (before anything else at their
        instant), and windows closing at times < now -- every window that ends at the same
        instant closes together, then the ``otherwise`` of each miss starts, in order."""
        while True:
            first = self.live.next_deadline(now)
            cuts = sorted((at, victim.v.id, victim, by) for at, victim, by in self.forced() if at <= now)
            if cuts and (first is None or cuts[0][0] <= first):
                at, _, victim, by = cuts[0]
                self.cancel(victim.v.instance, at, by)
            elif first is not None:
                self.close(self.live.due(first), first)
            else:
                return

    def close(self, items: list[Item], d: float) -> None:
        """The windows of ``items`` ended at ``d`` and time has passed it."""
        missed = []
        for item in items:
            v = item.v
            if v.negated:
                v.status, v.at = RESPECTED, d
            else:
                v.status, v.at = VIOLATED, d
                missed.append(item)
        self.seq += 1
        for item in missed:
            if item.otherwise is not None:
                v = item.v
                self.start(item.otherwise, d, self.seq, v.instance, v.rule, v.clause, v.depth + 1)

    def forced(self) -> list[tuple[float, Item, str]]:
        """Conflict-aware: (time, an item of the lower instance, the higher rule) for every
        obligation whose deadline finds it forbidden by a prioritised rule's prohibition."""
        if self.reading.priority_semantics != CONFLICT_AWARE or not self.above:
            return []
        out = []
        for event in self.live.events():  # an obligation and a prohibition of one event in force
            out += self.forced_on(event)
        return out

    def forced_on(self, event: str) -> list[tuple[float, Item, str]]:
        """:meth:`forced` for the obligations and prohibitions of ``event``."""
        out = []
        bans = self.live.of_event(event, True)
        for o in self.live.of_event(event, False):
            d = o.v.window[1]
            if d is None or o.branches:
                continue
            for p in bans:
                if p.v.instance == o.v.instance:
                    continue
                lo, hi = p.v.window
                if not (lo <= d and (hi is None or d <= hi)):
                    continue
                at = max(d - self.reading.priority_lead, o.v.start, lo)
                if (o.v.rule, p.v.rule) in self.above:
                    out.append((at, p, o.v.rule))
                elif (p.v.rule, o.v.rule) in self.above:
                    out.append((at, o, p.v.rule))
        return out

    def cancel(self, instance: int, at: float, by: str) -> None:
        for i in self.live.of_instance(instance):
            i.v.status, i.v.at, i.v.by = CANCELLED, at, by

    # -------------------------------------------------------------- occurrences
    def occur(self, step: int, now: float, event: str) -> None:
        self.seq += 1
        seq = self.seq
        broken = []
        for item in self.live.touched_by(event):  # the others: nothing an occurrence of it changes
            if item.created >= seq:
                continue
            v = item.v
            lo, hi = v.window
            inside = lo <= now and (hi is None or now <= hi)
            if v.negated:
                if v.event == event and inside:
                    v.status, v.at, v.by = VIOLATED, now, event
                    broken.append(item)
                continue
            if v.event == event and inside:
                v.status, v.at, v.by = FULFILLED, now, event
                continue
            for b, met in zip(item.branches, item.met):
                for j, (ev, blo, bhi) in enumerate(b):
                    if ev == event and blo <= now and (bhi is None or now <= bhi):
                        met.add(j)
                if len(met) == len(b):
                    v.status, v.at, v.by = FULFILLED, now, event
                    break
        for item in broken:  # the otherwise of each prohibition it broke starts now, in order
            v = item.v
            if item.otherwise is not None:
                self.start(item.otherwise, now, seq, v.instance, v.rule, v.clause, v.depth + 1)
        for rule in self.triggered.get(event, ()):  # in file order
            self.fire(step, now, seq, rule)

    def fire(self, step: int, now: float, seq: int, rule: A.Rule) -> None:
        fired = self.eval.truth(rule.trigger.condition, self.values)
        if fired is None:
            missing = self.eval.reads(rule.trigger.condition) - self.values.keys()
            self.out.firings.append(
                Firing(step, now, rule.name, rule.trigger.event, None, None, None, _sorted(missing))
            )
            return
        if not fired:
            self.out.firings.append(Firing(step, now, rule.name, rule.trigger.event, False, None, None))
            return
        top = rule.response
        k = choose([self.eval.truth(d.condition, self.values) for d in top.defeaters], self.reading.semantics)
        if k is None:
            missing = set().union(*(self.eval.reads(d.condition) for d in top.defeaters)) - self.values.keys()
            self.out.firings.append(
                Firing(step, now, rule.name, rule.trigger.event, True, None, None, _sorted(missing))
            )
            return
        if k == 0:
            response: A.Response | None = A.Response(top.items, ())
            key = rule.name
        else:
            response, key = top.defeaters[k - 1].response, f"{rule.name}.{k}"
        instance = next(self.instances)
        try:
            planned = self.plan(response, key, now)
        except _Undetermined as u:
            self.out.firings.append(
                Firing(step, now, rule.name, rule.trigger.event, True, None, None, _sorted(u.missing))
            )
            return
        self.out.firings.append(Firing(step, now, rule.name, rule.trigger.event, True, k, instance))
        self.instance_rule[instance] = rule.name
        self.add(planned, now, seq, instance, rule.name, k, 0)

    # -------------------------------------------------------------- responses
    def start(
        self, response: A.Response, now: float, seq: int, instance: int, rule: str, clause: int, depth: int
    ) -> None:
        """Start an ``otherwise`` at ``now`` (its key prefix is carried in the plan)."""
        try:
            planned = self.plan(response, "", now)
        except _Undetermined as u:
            self.out.undetermined.append(
                f"{rule}: the otherwise starting at {now:g} needs {', '.join(_sorted(u.missing))}"
            )
            return
        self.add(planned, now, seq, instance, rule, clause, depth)

    def plan(self, response: A.Response | None, key: str, now: float) -> list[tuple[str, Item]]:
        """The items ``response`` imposes when it starts at ``now`` (inner clauses chosen now).

        ``key`` is the runtime's name for the response (``R1``, ``R1.2``); an ``otherwise``
        carries its own key in ``self.keys``.
        """
        if response is None:
            return []
        if not key:
            key = self.keys[id(response)]
        if response.defeaters:
            vals = [self.eval.truth(d.condition, self.values) for d in response.defeaters]
            chosen = choose(vals, self.reading.semantics)
            if chosen is None:
                raise _Undetermined(
                    set().union(*(self.eval.reads(d.condition) for d in response.defeaters))
                    - self.values.keys()
                )
            if chosen:
                return self.plan(response.defeaters[chosen - 1].response, f"{key}~{chosen}", now)
        out = []
        for n, it in enumerate(response.items):
            k = f"{key}:{n}"
            occ = it.occurrence
            lo, hi = self.window(occ, it.otherwise is not None, now)
            branches: list[list[tuple[str, float, float | None]]] = []
            if it.alternative is not None and not occ.negated:
                branch = self.branch(it.alternative, f"{k}/e", now)
                if branch is not None:
                    branches.append(branch)
            if it.otherwise is not None:
                self.keys[id(it.otherwise)] = f"{k}/o"
            verdict = Verdict(
                id=0, instance=0, rule="", clause=0, key=k, event=occ.event, negated=occ.negated,
                start=now, window=(lo, hi),
            )  # fmt: skip
            out.append((k, Item(verdict, 0, it.otherwise, branches, [set() for _ in branches])))
        return out

    def branch(
        self, response: A.Response, key: str, now: float
    ) -> list[tuple[str, float, float | None]] | None:
        """An ``else`` alternative's windows (its clauses chosen now); None when it can never fulfil."""
        if response.defeaters:
            k = choose(
                [self.eval.truth(d.condition, self.values) for d in response.defeaters],
                self.reading.semantics,
            )
            if k is None:
                return None  # unknown: it cannot be counted on (fail closed)
            if k:
                sub = response.defeaters[k - 1].response
                return None if sub is None else self.branch(sub, f"{key}~{k}", now)
        out = []
        for it in response.items:
            if it.occurrence.negated:
                return None
            lo, hi = self.window(it.occurrence, it.otherwise is not None, now)
            out.append((it.occurrence.event, lo, hi))
        return out or None

    def window(self, occ: A.Occurrence, has_otherwise: bool, now: float) -> tuple[float, float | None]:
        """The absolute window of an occurrence starting at ``now``."""
        try:
            if occ.limit is not None:
                hi = now + self.eval.seconds(occ.limit.hi, self.values)
                lo = now + self.eval.seconds(occ.limit.lo, self.values) if occ.limit.lo is not None else now
                return lo, hi
        except _Unknown:
            assert occ.limit is not None
            reads = self.eval.reads(occ.limit.hi.value)
            if occ.limit.lo is not None:
                reads |= self.eval.reads(occ.limit.lo.value)
            raise _Undetermined(reads - self.values.keys()) from None
        if occ.eventually:
            return now, None
        if occ.negated:
            return now, now  # untimed `not E`: the trigger instant
        if has_otherwise:
            return now, now  # `otherwise` after an untimed occurrence: within 0 seconds
        return now, None if self.untimed is None else now + self.untimed

    def add(
        self,
        planned: list[tuple[str, Item]],
        now: float,
        seq: int,
        instance: int,
        rule: str,
        clause: int,
        depth: int,
    ) -> None:
        """Put a response's items in force, then apply priorities and conflicts."""
        fresh = []
        for _, item in planned:
            item.v.id, item.v.instance, item.v.rule, item.v.clause, item.v.depth = (
                next(self.ids), instance, rule, clause, depth,
            )  # fmt: skip
            item.created = seq
            self.items.append(item)
            self.live.add(item)
            fresh.append(item)
        for item in fresh:  # a window that ends before it starts is already closed
            hi = item.deadline
            if item.v.status == PENDING and hi is not None and hi < item.v.window[0] and not item.branches:
                if item.v.negated:
                    item.v.status, item.v.at = RESPECTED, now
                else:
                    item.v.status, item.v.at = VIOLATED, now
                    item.v.note = "its window closed before it opened (a negative deadline)"
                    if item.otherwise is not None:
                        self.start(item.otherwise, now, seq, instance, rule, clause, depth + 1)
        if depth == 0 and self.reading.priority_semantics == CANCEL:
            self.prioritise(instance, rule, now)
        for item in fresh:
            if item.v.status == PENDING:
                self.conflicts(item, now, seq)

    def prioritise(self, instance: int, rule: str, now: float) -> None:
        """Cancellation-based priority: a new instance meets every active one (of a rule a
        priority orders it with: the others it leaves alone)."""
        related = self.related.get(rule)
        if not related or not self.live.of_instance(instance):
            return  # no priority orders it with another rule, or it imposes nothing (not active)
        for other in self.live.active(related):
            if other == instance:
                continue
            orule = self.instance_rule[other]
            if (rule, orule) in self.above:
                self.settled(instance, other, now, rule)
                self.cancel(other, now, rule)
            elif (orule, rule) in self.above:
                self.settled(instance, other, now, orule)
                self.cancel(instance, now, orule)
                return

    def settled(self, a: int, b: int, now: float, winner: str) -> None:
        """Record the conflicts a cancellation settles: the clashes between instances ``a`` and ``b``."""
        both = sorted([*self.live.of_instance(a), *self.live.of_instance(b)], key=lambda i: i.v.id)
        for o in both:
            for p in both:
                if (
                    not o.v.negated
                    and p.v.negated
                    and o.v.event == p.v.event
                    and o.v.instance != p.v.instance
                    and _covers(o, p, now)
                ):
                    self.out.conflicts.append(
                        Conflict(
                            now,
                            o.v.event,
                            o.v.id,
                            p.v.id,
                            (o.v.rule, p.v.rule),
                            (o.v.clause, p.v.clause),
                            CANCEL,
                            winner,
                        )
                    )

    def conflicts(self, item: Item, now: float, seq: int) -> None:
        """A new item against those in force: an obligation whose whole window is forbidden."""
        if item.v.negated:
            for o in self.live.of_event(item.v.event, False):
                self.clash(o, item, now, seq)
        else:
            for p in self.live.of_event(item.v.event, True):
                if item.v.status == PENDING:
                    self.clash(item, p, now, seq)

    def clash(self, o: Item, p: Item, now: float, seq: int) -> None:
        if o.v.status != PENDING or not _covers(o, p, now):
            return  # some instant of the obligation's window is allowed: the robot can wait
        pair = (o.v.rule, p.v.rule)
        if self.reading.priority_semantics == CONFLICT_AWARE and (
            pair in self.above or pair[::-1] in self.above
        ):
            winner = o.v.rule if pair in self.above else p.v.rule
            self.out.conflicts.append(
                Conflict(
                    now, o.v.event, o.v.id, p.v.id, pair, (o.v.clause, p.v.clause), CONFLICT_AWARE, winner
                )
            )
            return
        self.out.conflicts.append(
            Conflict(
                now, o.v.event, o.v.id, p.v.id, pair, (o.v.clause, p.v.clause), "prohibition-wins", p.v.rule
            )
        )
        o.v.status, o.v.at, o.v.by = BLOCKED, now, p.v.rule
        o.v.note = f"{p.v.rule} forbids {p.v.event} for the whole window"
        if o.otherwise is not None:
            self.start(o.otherwise, now, seq, o.v.instance, o.v.rule, o.v.clause, o.v.depth + 1)


def _covers(o: Item, p: Item, now: float) -> bool:
    """Does prohibition ``p`` forbid every instant left of obligation ``o``'s window?"""
    if o.branches:
        return False  # an `else` alternative may still meet it
    olo, ohi = o.v.window
    plo, phi = p.v.window
    return plo <= max(olo, now) and (phi is None or (ohi is not None and ohi <= phi))


def _sorted(names: Iterable[str]) -> tuple[str, ...]:
    return tuple(sorted(names))
