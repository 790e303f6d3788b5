"""The Manager: rules, context, layers, decisions and obligations, in one process.

It plays the paper's *Manager* role (owns the rules and the context) and hosts the COP
*Layer Manager* (:mod:`cosleec.runtime.layers`); a *Context Listener* feeds it from the
robot's topics (``cosleec.nodes``). Every state change happens under one lock, so a
trigger is always decided against a context that no update has half-changed;
implementations run outside the lock, so a slow or failing task never blocks it.
"""

from __future__ import annotations

import itertools
import logging
import threading
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any, TypeVar

from cosleec.cop import Snapshot
from cosleec.lang import HedgeSemantics, Specification, Unknowns, choose
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock, MonotonicClock
from cosleec.runtime.context import Context
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import ConfigurationError, ContextError
from cosleec.runtime.implementations import Capability, Implementations
from cosleec.runtime.layers import LayerManager, LayerSwitch, evaluate
from cosleec.runtime.model import CompiledRule, Obligation, ResponseSpec
from cosleec.runtime.obligations import Outcome, Tracked, Tracker
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.tasks import Task

E = TypeVar("E", bound=StrEnum)


def _option(kind: type[E], value: object, name: str) -> E:
    """``value`` as a member of the option enum ``kind``, or ConfigurationError listing the choices."""
    if isinstance(value, str):
        try:
            return kind(value)
        except ValueError:
            pass
    choices = ", ".join(repr(str(k)) for k in kind)
    raise ConfigurationError(f"{name} must be one of {choices}, not {value!r}")


@dataclass(frozen=True)
class RuntimeEvent:
    """What observers (terminal display, ROS publishers, the audit log, tests) are told, in order.

    ``kind`` is one of context, layers, decision, obligation, refused, rejected, task-failed.
    """

    kind: str
    time: float
    data: dict[str, Any] = field(default_factory=dict)


class Manager:
    """Runs a rule set in one process: the embedded CO-SLEEC runtime.

    Use it to enforce SLEEC rules inside a Python program (the ROS Manager node wraps
    one). Build it from a :class:`RuleSet` or with :meth:`from_file` / :meth:`from_text`;
    bind tasks (:meth:`bind`) or capabilities (:meth:`capability`), :meth:`start` it, then
    feed it measures (:meth:`update`) and events (:meth:`event`), and ask before acting
    (:meth:`request`).

    Options: ``semantics`` (``"last-wins"`` or ``"nested"``, :class:`HedgeSemantics`);
    ``clock`` -- a :class:`Clock` (monotonic by default; a VirtualClock for tests);
    ``unknown`` -- how a clause condition over a measure with no value is read
    (``"undetermined"``, the fail-closed default: the decision is undetermined and nothing
    runs; ``"false"``/``"true"``); ``untimed`` -- the deadline of an untimed response
    (``"none"``, ``"immediate"`` or seconds); ``max_age`` -- seconds after which a
    measure's value is stale; ``audit`` -- a JSON Lines audit log; ``history`` -- how
    many decisions :attr:`decisions` keeps; ``dispatch=False`` decides without running
    implementations (the ROS Manager node, ``cosleec decide``).
    """

    def __init__(
        self,
        rules: RuleSet,
        *,
        semantics: HedgeSemantics | str = HedgeSemantics.LAST_WINS,
        clock: Clock | None = None,
        unknown: Unknowns | str = Unknowns.UNDETERMINED,
        untimed: str | float = "none",
        audit: str | Path | AuditLog | None = None,
        max_age: Mapping[str, float] | None = None,
        history: int = 10_000,
        dispatch: bool = True,
    ) -> None:
        if not isinstance(rules, RuleSet):
            raise TypeError(
                f"Manager needs a RuleSet, not {type(rules).__name__}: "
                "use Manager.from_file(path), Manager.from_text(text) or Manager(RuleSet.from_spec(spec))"
            )
        self.ruleset = rules
        self.spec = rules.spec
        self.clock: Clock = clock or MonotonicClock()
        self.context = Context(rules.measures, max_age)
        self.layer_manager = LayerManager(
            rules, _option(HedgeSemantics, semantics, "semantics"), _option(Unknowns, unknown, "unknown")
        )
        self.tracker = Tracker(untimed)
        self.implementations = Implementations(rules)
        self.dispatch_locally = dispatch
        self.audit = audit if isinstance(audit, AuditLog) else AuditLog(audit) if audit else None
        self.decisions: deque[Decision] = deque(maxlen=history)
        self.stats = {"updates": 0, "rejected": 0, "events": 0, "decisions": 0, "refused": 0, "violations": 0}
        self._lock = threading.RLock()
        self._seq = itertools.count(1)
        self._ids = itertools.count(1)
        self._observers: list[Callable[[RuntimeEvent], None]] = []
        self._wake = threading.Condition()
        self._timer: threading.Thread | None = None
        self._stop = threading.Event()

    @classmethod
    def from_file(cls, path: str | Path, *, infer_defs: bool = False, **options: Any) -> Manager:
        """A Manager for the rules in ``path``; ``options`` as for the constructor."""
        return cls(RuleSet.from_file(path, infer_defs=infer_defs), **options)

    @classmethod
    def from_text(cls, text: str, *, infer_defs: bool = False, **options: Any) -> Manager:
        """A Manager for SLEEC ``text``; ``options`` as for the constructor."""
        return cls(RuleSet.from_text(text, infer_defs=infer_defs), **options)

    @classmethod
    def from_spec(cls, spec: Specification, *, infer_defs: bool = False, **options: Any) -> Manager:
        """A Manager for a Specification built in Python; ``options`` as for the constructor."""
        return cls(RuleSet.from_spec(spec, infer_defs=infer_defs), **options)

    @property
    def semantics(self) -> HedgeSemantics:
        """How clauses combine: last-wins (SLEEC) or nested (the paper's formula)."""
        return self.layer_manager.semantics

    # ------------------------------------------------------------------ wiring
    def bind(self, *tasks: Task) -> Manager:
        """Bind paper-style tasks, one per rule, and make this Manager their reporter (``task.manager``).

        BindingError when a task names no rule, an unknown rule, or a clause its rule does
        not have; a second task for the same rule replaces the first. Bind before
        :meth:`start`: its completeness check sees only what is bound. Returns ``self``.
        """
        for t in tasks:
            self.implementations.bind(t)
            t.manager = self
        return self

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        """Decorator: register ``fn(obligation, decision)`` as the way the robot performs ``event``.

        Use it for actions many rules share: a rule without a task, and every ``otherwise``
        fallback, runs the capability of each event its decision obliges. A second
        registration for the same event replaces the first.
        """
        return self.implementations.capability(event)

    def subscribe(self, fn: Callable[[RuntimeEvent], None]) -> Callable[[], None]:
        """Call ``fn`` with every :class:`RuntimeEvent` from now on; returns the function that unsubscribes.

        Observers run in order on the thread that caused the event, once the state change is
        complete; one that raises is logged and ignored. Keep them quick: they delay the
        caller (the Manager node publishes on its topics from one). While anyone listens,
        the Manager builds event payloads it otherwise skips.
        """
        self._observers.append(fn)
        return lambda: self._observers.remove(fn)

    def start(self, *, check: bool = True, timer: bool = False) -> Manager:
        """Check that every clause has an implementation; optionally run deadlines on a thread.

        The check raises BindingError listing what is missing; it is skipped with
        ``check=False`` or when the Manager does not dispatch. With ``timer=True`` a daemon
        thread judges deadlines and stale values as time passes; without it, call
        :meth:`tick` yourself (as tests with a VirtualClock do). Returns ``self``.
        """
        if check and self.dispatch_locally:
            self.implementations.check()
        if self.dispatch_locally:
            self.implementations.prepare()  # start-up work, not the first trigger's latency
        if timer and self._timer is None:
            self._timer = threading.Thread(target=self._run_timer, name="cosleec-deadlines", daemon=True)
            self._timer.start()
        return self

    def close(self) -> None:
        """Stop the timer thread (waiting up to 5 s) and close the audit log.

        Call it once, when done: with an audit log, a Manager used after closing fails on
        its next record.
        """
        self._stop.set()
        with self._wake:
            self._wake.notify_all()
        if self._timer is not None:
            self._timer.join(5)
        if self.audit is not None:
            self.audit.close()

    # ------------------------------------------------------------------ context
    def update(self, values: Mapping[str, object] | None = None, /, **kw: object) -> list[LayerSwitch]:
        """Set measure values atomically; returns the layer switches ``(rule, old, new)``.

        A wrong type, unknown measure or value outside a scale raises ContextError with the
        reason, and nothing changes.
        """
        updates = {**(values or {}), **kw}
        events: list[RuntimeEvent] = []
        with self._lock:
            try:
                stored = self.context.validate(updates)
            except ContextError as e:
                self.stats["rejected"] += 1
                self._emit_later(
                    events, "rejected", {"reason": str(e), "update": {k: repr(v) for k, v in updates.items()}}
                )
                self._flush(events)
                raise
            now = self.clock.now()
            self.stats["updates"] += 1
            self._advance(now, events)
            changed = self.context.apply(stored, now)
            switches = self.layer_manager.update(changed, self.context.values) if changed else []
            if changed and self._listening:
                self._emit_later(
                    events,
                    "context",
                    {"values": self.context.external(sorted(changed)), "version": self.context.version},
                )
            result = self._switched(switches, events)
        self._flush(events)
        return result

    def values(self) -> dict[str, Any]:
        """Every measure's value as users see it (scale literals by name), None when unknown.

        A copy, safe to take from any thread. A value past its ``max_age`` shows as unknown
        once the next update, event, request or tick has noticed it.
        """
        with self._lock:
            return self.context.external()

    def active_layers(self) -> list[str]:
        """The active clause layers in rule order (``["R1.1", ...]``); a rule at its default has none."""
        with self._lock:
            return self.layer_manager.active_layers()

    def set_semantics(self, semantics: HedgeSemantics | str) -> None:
        """Switch clause semantics at run time; every rule's layer is re-evaluated."""
        with self._lock:
            self.layer_manager.set_semantics(_option(HedgeSemantics, semantics, "semantics"), self.context.values)

    # ------------------------------------------------------------------ events
    def event(self, name: str) -> list[Decision]:
        """An event occurred: it may fulfil or violate obligations, and it triggers rules.

        Returns the decisions of the rules it triggered (whose trigger condition held).
        """
        events: list[RuntimeEvent] = []
        followups: list[tuple[CompiledRule, Decision]] = []
        with self._lock:
            if name not in self.ruleset.events:
                self.stats["rejected"] += 1
                self._emit_later(events, "rejected", {"reason": f"unknown event {name!r}"})
                self._flush(events)
                raise ContextError(f"unknown event {name!r}")
            now = self.clock.now()
            seq = next(self._seq)
            self.stats["events"] += 1
            followups += self._advance(now, events)
            out = self.tracker.occur(name, now, seq)
            followups += self._settle(out, now, seq, events)
            decisions: list[tuple[CompiledRule, Decision, Snapshot | None]] = []
            for rule in self.ruleset.by_trigger.get(name, ()):
                d = self._decide(rule, name, now)
                if d is None:
                    continue
                # the rule's composition as the Layer Manager has it at this trigger: the
                # dispatch runs under it, whatever the context does in the meantime
                decisions.append((rule, d, self.layer_manager.composition_of(rule) if d.clause is not None else None))
                self._record(d, events)
                for ob in d.obligations:
                    t = self.tracker.start(d.id, d.clause, ob, now, seq)
                    if self._listening:
                        self._emit_later(events, "obligation", t.to_json())
        self._flush(events)
        self._notify_timer()
        if self.dispatch_locally:
            for rule, d, composition in decisions:
                if composition is not None and not self.implementations.dispatch(rule, d, composition):
                    self._flush([RuntimeEvent("task-failed", now, {"rule": rule.name, "decision": d.id})])
            for rule, d in followups:
                self.implementations.dispatch_fallback(rule, d)
        return [d for _, d, _ in decisions]

    def request(self, name: str) -> bool:
        """May ``name`` happen now? False (and the attempt recorded) while a prohibition holds."""
        events: list[RuntimeEvent] = []
        with self._lock:
            now = self.clock.now()
            self._advance(now, events)
            forbidding = self.tracker.forbidding(name, now)
            for t in forbidding:
                t.refused += 1
            if forbidding:
                self.stats["refused"] += 1
                self._emit_later(
                    events,
                    "refused",
                    {
                        "event": name,
                        "by": [t.rule for t in forbidding],
                        "obligations": [t.id for t in forbidding],
                    },
                )
        self._flush(events)
        return not forbidding

    def tick(self) -> list[Decision]:
        """Process deadlines and stale values up to now (the timer thread calls this too)."""
        events: list[RuntimeEvent] = []
        with self._lock:
            followups = self._advance(self.clock.now(), events)
        self._flush(events)
        if self.dispatch_locally:
            for rule, d in followups:
                self.implementations.dispatch_fallback(rule, d)
        return [d for _, d in followups]

    def outstanding(self) -> list[Tracked]:
        """Pending obligations that require an event (prohibitions left out): what the robot still owes.

        The records are live: read them, do not change them.
        """
        with self._lock:
            return self.tracker.outstanding()

    # ------------------------------------------------------------------ internals (under the lock)
    def _advance(self, now: float, events: list[RuntimeEvent]) -> list[tuple[CompiledRule, Decision]]:
        gone = self.context.expire(now)
        if gone:
            switches = self.layer_manager.update(gone, self.context.values)
            self._emit_later(
                events, "context", {"values": dict.fromkeys(sorted(gone)), "stale": sorted(gone)}
            )
            self._switched(switches, events)
        followups: list[tuple[CompiledRule, Decision]] = []
        for _ in range(1000):  # a chain of otherwise fallbacks can expire within one advance
            out = self.tracker.due(now)
            if not out.changed:
                break
            followups += self._settle(out, now, next(self._seq), events)
        return followups

    def _switched(self, switches: list[LayerSwitch], events: list[RuntimeEvent]) -> list[LayerSwitch]:
        """Announce layer switches to observers; returns them."""
        result = switches
        if result and self._listening:
            self._emit_later(events, "layers", self.layer_manager.state(result).to_json())
        return result

    def _settle(
        self, out: Outcome, now: float, seq: int, events: list[RuntimeEvent]
    ) -> list[tuple[CompiledRule, Decision]]:
        followups = []
        for t in out.changed:
            if t.status == "violated" and not t.late:
                self.stats["violations"] += 1
            self._emit_later(events, "obligation", t.to_json())
        for t, start in out.fallbacks:
            ob = t.obligation
            assert ob.otherwise is not None
            rule = self.ruleset.rule(t.rule)
            obligations = self._issue(ob.otherwise, rule.name)
            why = f"{rule.name}: {ob.describe()} was violated at {start:g}; otherwise " + (
                " and ".join(o.describe() for o in obligations) or "nothing is required"
            )
            d = Decision(
                id=next(self._ids),
                time=start,
                event="otherwise",
                rule=rule.name,
                clause=t.clause,
                layer=None,
                semantics=self.semantics,
                values={},
                conditions=(),
                obligations=obligations,
                reason=why,
                context_version=self.context.version,
                violated=t.id,
            )
            self._record(d, events)
            for o in obligations:
                nt = self.tracker.start(d.id, d.clause, o, start, seq, t.depth + 1)
                self._emit_later(events, "obligation", nt.to_json())
            followups.append((rule, d))
        return followups

    def _decide(self, rule: CompiledRule, event: str, now: float) -> Decision | None:
        v = self.context.values
        missing: tuple[str, ...] = ()
        try:
            fired: bool | None = bool(rule.condition(v))
        except KeyError as e:
            fired, missing = None, (str(e.args[0]),)
        if fired is False:
            return None
        status = self.layer_manager.status[rule.index]
        clause = status.clause if fired else None
        if clause is None and not missing:
            missing = status.missing
        obligations = self._issue(rule.response_of(clause), rule.name) if clause is not None else ()
        conds = ((0, rule.trigger_text, fired), *zip(rule.clause_ids, rule.clause_texts, status.values))
        values = {
            n: (lits[x] if lits is not None and x is not None else x)
            for n, lits in rule.value_specs
            for x in (v.get(n),)
        }
        # the explanation is computed from these parts when first read (Decision.explanation)
        return Decision(
            id=next(self._ids),
            time=now,
            event=event,
            rule=rule.name,
            clause=clause,
            layer=rule.layer_of(clause) if clause else None,
            semantics=self.semantics,
            values=values,
            conditions=conds,
            obligations=obligations,
            missing=missing,
            context_version=self.context.version,
            unknowns=self.layer_manager.unknowns,
        )

    def _issue(self, spec: ResponseSpec | None, rule: str) -> tuple[Obligation, ...]:
        """The concrete obligations of a response, starting now (deadlines on this snapshot)."""
        if spec is None:
            return ()
        v = self.context.values
        if spec.clauses:  # a braced inner response: its own hedges, read when it starts
            vals, _ = evaluate(spec.clauses, v)
            k = choose(vals, self.semantics, self.layer_manager.unknowns)
            if k:
                return self._issue(spec.clauses[k - 1].response, rule)
        out = []
        for it in spec.items:
            hi = lo = None
            try:
                hi = it.hi(v) if it.hi is not None else None
                lo = it.lo(v) if it.lo is not None else None
            except KeyError:
                hi = 0.0  # a deadline that depends on an unknown measure: the strictest reading
            alts = tuple(a.event for a in it.alternative.items) if it.alternative is not None else ()
            out.append(
                Obligation(
                    event=it.event,
                    negated=it.negated,
                    within_s=hi,
                    from_s=lo or 0.0,
                    eventually=it.eventually,
                    alternatives=alts,
                    otherwise=it.otherwise,
                    rule=rule,
                )
            )
        return tuple(out)

    def _record(self, d: Decision, events: list[RuntimeEvent]) -> None:
        self.decisions.append(d)
        self.stats["decisions"] += 1
        if self._listening:
            self._emit_later(events, "decision", d.to_json())

    def _emit_later(self, events: list[RuntimeEvent], kind: str, data: dict[str, Any]) -> None:
        events.append(RuntimeEvent(kind, self.clock.now(), data))

    @property
    def _listening(self) -> bool:
        """Does anyone read runtime events? If not, no event payload is built."""
        return bool(self._observers) or self.audit is not None

    # ------------------------------------------------------------------ outside the lock
    def _flush(self, events: Iterable[RuntimeEvent]) -> None:
        for ev in events:
            if self.audit is not None:
                self.audit.write({"kind": ev.kind, "time": ev.time, **ev.data})
            for fn in list(self._observers):
                try:
                    fn(ev)
                except Exception:  # an observer must never break the runtime
                    logging.getLogger("cosleec.runtime").exception("observer failed")

    def _notify_timer(self) -> None:
        if self._timer is not None:
            with self._wake:
                self._wake.notify_all()

    def _run_timer(self) -> None:
        while not self._stop.is_set():
            with self._lock:
                nxt = self.tracker.next_deadline()
                exp = self.context.next_expiry()
            times = [t for t in (nxt, exp) if t is not None]
            wait = None if not times else max(0.0, min(times) - self.clock.now() + 1e-3)
            with self._wake:
                self._wake.wait(timeout=0.5 if wait is None else min(wait, 0.5))
            if not self._stop.is_set():
                self.tick()
