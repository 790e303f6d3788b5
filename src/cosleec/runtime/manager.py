"""The Manager: rules, context, layers, decisions and obligations, in one process.

It plays the paper's *Manager* role (parses and evaluates rules, owns the context) and
hosts the *COP Layer Manager*; a *Context Listener* (see listener.py) feeds it. Every
state change happens under one lock, so a trigger is always decided against a context
that no update has half-changed; implementations run outside the lock, so a slow or
failing task never blocks the Manager.
"""

from __future__ import annotations

import itertools
import logging
import re
import threading
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosleec.lang import SleecError, Specification, analyse, analyse_file
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock, MonotonicClock
from cosleec.runtime.context import Context
from cosleec.runtime.decision import Decision
from cosleec.runtime.dispatcher import Capability, TaskDispatcher
from cosleec.runtime.errors import ContextError
from cosleec.runtime.layers import LayerManager, evaluate, select, switch_records, switches_json
from cosleec.runtime.model import CompiledRule, Obligation, ResponseSpec, RuleSet, compile_rules
from cosleec.runtime.obligations import Outcome, Tracked, Tracker
from cosleec.runtime.tasks import Task


@dataclass(frozen=True)
class RuntimeEvent:
    """What observers (terminal display, ROS publishers, tests) are told, in order."""

    kind: str  # context | layers | decision | obligation | refused | rejected | task-failed
    time: float
    data: dict[str, Any] = field(default_factory=dict)


def _looks_like_rules(text: str) -> bool:
    """SLEEC text rather than a file name: it has a rule (a file name has no spaces around `when`)."""
    return re.search(r"(?i)(\brule_start\b|\swhen\s)", text) is not None


def load_rules(source: Specification | str | Path, infer_defs: bool = False) -> tuple[Specification, Any]:
    """A checked specification and its symbol table, from a Specification, a path or text."""
    if isinstance(source, Specification):
        from cosleec.lang.printer import format_spec

        result = analyse(format_spec(source), source.path, infer_defs=True)
    elif isinstance(source, Path) or not _looks_like_rules(source):
        result = analyse_file(source, infer_defs=infer_defs)
    else:
        result = analyse(str(source), infer_defs=infer_defs)
    if not result.ok or result.spec is None:
        raise SleecError(result.diagnostics, result.source)
    return result.spec, result.symbols


class Manager:
    def __init__(
        self,
        rules: Specification | str | Path,
        *,
        semantics: str = "last-wins",
        clock: Clock | None = None,
        unknown: str = "undetermined",
        untimed: str | float = "none",
        audit: str | Path | AuditLog | None = None,
        max_age: Mapping[str, float] | None = None,
        infer_defs: bool = False,
        history: int = 10_000,
        dispatch: bool = True,
    ) -> None:
        spec, symbols = load_rules(rules, infer_defs)
        self.spec = spec
        self.ruleset: RuleSet = compile_rules(spec, symbols, dict(max_age or {}))
        self.clock: Clock = clock or MonotonicClock()
        self.context = Context(self.ruleset.measures)
        self.layers = LayerManager(self.ruleset, semantics, unknown)
        self.tracker = Tracker(untimed)
        self.dispatcher = TaskDispatcher(self.ruleset)
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

    @property
    def semantics(self) -> str:
        return self.layers.semantics

    # ------------------------------------------------------------------ wiring
    def bind(self, *tasks: Task) -> Manager:
        for t in tasks:
            self.dispatcher.bind(t)
            t.manager = self
        return self

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        return self.dispatcher.capability(event)

    def subscribe(self, fn: Callable[[RuntimeEvent], None]) -> Callable[[], None]:
        self._observers.append(fn)
        return lambda: self._observers.remove(fn)

    def start(self, *, check: bool = True, timer: bool = False) -> Manager:
        """Check that every clause has an implementation; optionally run deadlines on a thread."""
        if check and self.dispatch_locally:
            self.dispatcher.check()
        if self.dispatch_locally:
            self.dispatcher.warm()
        if timer and self._timer is None:
            self._timer = threading.Thread(target=self._run_timer, name="cosleec-deadlines", daemon=True)
            self._timer.start()
        return self

    def close(self) -> None:
        self._stop.set()
        with self._wake:
            self._wake.notify_all()
        if self._timer is not None:
            self._timer.join(5)
        if self.audit is not None:
            self.audit.close()

    # ------------------------------------------------------------------ context
    def update(
        self, values: Mapping[str, object] | None = None, /, **kw: object
    ) -> list[tuple[str, str | None, str | None]]:
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
            switches = self.layers.update(changed, self.context.values) if changed else []
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
        with self._lock:
            return self.context.external()

    def active_layers(self) -> list[str]:
        with self._lock:
            return self.layers.active_layers()

    def set_semantics(self, semantics: str) -> None:
        with self._lock:
            self.layers.set_semantics(semantics, self.context.values)

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
            decisions = []
            for rule in self.ruleset.by_trigger.get(name, ()):
                d = self._decide(rule, name, now)
                if d is None:
                    continue
                decisions.append((rule, d))
                self._record(d, events)
                for ob in d.obligations:
                    t = self.tracker.start(d.id, ob, now, seq)
                    if self._listening:
                        self._emit_later(events, "obligation", t.to_json())
        self._flush(events)
        self._notify_timer()
        if self.dispatch_locally:
            for rule, d in decisions:
                if d.clause is not None and not self.dispatcher.dispatch(rule, d):
                    self._flush([RuntimeEvent("task-failed", now, {"rule": rule.name, "decision": d.id})])
            for rule, d in followups:
                self.dispatcher.dispatch_fallback(rule, d)
        return [d for _, d in decisions]

    trigger = event
    report = event

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
                self.dispatcher.dispatch_fallback(rule, d)
        return [d for _, d in followups]

    def outstanding(self) -> list[Tracked]:
        with self._lock:
            return self.tracker.outstanding()

    # ------------------------------------------------------------------ internals (under the lock)
    def _advance(self, now: float, events: list[RuntimeEvent]) -> list[tuple[CompiledRule, Decision]]:
        gone = self.context.expire(now)
        if gone:
            switches = self.layers.update(gone, self.context.values)
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

    def _switched(
        self, switches: list[tuple[CompiledRule, int | None, int | None]], events: list[RuntimeEvent]
    ) -> list[tuple[str, str | None, str | None]]:
        """The layer switches as ``(rule, old layer, new layer)``, announced to observers."""
        result = switch_records(switches)
        if result and self._listening:
            self._emit_later(
                events,
                "layers",
                {
                    "switches": switches_json(result),
                    "active": self.layers.active_layers(),
                },
            )
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
                next(self._ids),
                start,
                "otherwise",
                rule.name,
                self._clause_of(t),
                None,
                self.semantics,
                {},
                (),
                obligations,
                (),
                why,
                self.context.version,
                {"violated": t.id},
            )
            self._record(d, events)
            for o in obligations:
                nt = self.tracker.start(d.id, o, start, seq, t.depth + 1)
                self._emit_later(events, "obligation", nt.to_json())
            followups.append((rule, d))
        return followups

    def _clause_of(self, t: Tracked) -> int | None:
        for d in reversed(self.decisions):
            if d.id == t.decision_id:
                return d.clause
        return None

    def _decide(self, rule: CompiledRule, event: str, now: float) -> Decision | None:
        v = self.context.values
        missing: tuple[str, ...] = ()
        try:
            fired: bool | None = bool(rule.condition(v))
        except KeyError as e:
            fired, missing = None, (str(e.args[0]),)
        if fired is False:
            return None
        status = self.layers.status[rule.index]
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
            next(self._ids),
            now,
            event,
            rule.name,
            clause,
            rule.layer_of(clause) if clause else None,
            self.semantics,
            values,
            conds,
            obligations,
            missing,
            "",
            self.context.version,
        )

    def _issue(self, spec: ResponseSpec | None, rule: str) -> tuple[Obligation, ...]:
        """The concrete obligations of a response, starting now (deadlines on this snapshot)."""
        if spec is None:
            return ()
        v = self.context.values
        if spec.clauses:  # a braced inner response: its own hedges, read when it starts
            vals, _ = evaluate(spec.clauses, v)
            k = select(vals, self.semantics, self.layers.unknown)
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
                Obligation(it.event, it.negated, hi, lo or 0.0, it.eventually, alts, it.otherwise, rule)
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
