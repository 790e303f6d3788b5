"""The core: the state every part of the runtime reads and changes, under one lock.

The rules in force and what is computed from them (context, Layer Manager, priorities,
implementations, issuer, decider), the obligations in force (the tracker), the decisions
kept, the counts, and the :class:`~cosleec.runtime.steps.Steps` that number, commit and
deliver records. One object, so that a reload swaps the rules for every part at once
(:mod:`cosleec.runtime.reload`), and so that a part can be built and tested without a
Manager (``Core.build(RuleSet.from_text(...))``).

It also records what every part records the same way: a decision (and its outbox entry
in the journal), an obligation's new state, layer switches, values gone stale.
"""

from __future__ import annotations

import functools
from collections import deque
from typing import Any, Generic, TypeVar, overload

from cosleec.lang import CONFLICT_AWARE, HedgeSemantics, Reading, Specification, Unknowns
from cosleec.records import Kind
from cosleec.runtime.clock import Clock, VirtualClock, boot
from cosleec.runtime.context import Context
from cosleec.runtime.decider import Decider
from cosleec.runtime.decision import Decision
from cosleec.runtime.explanations import Explanations
from cosleec.runtime.implementations import Implementations
from cosleec.runtime.issuer import Issuer
from cosleec.runtime.layers import LayerManager, LayerSwitch
from cosleec.runtime.obligations import PENDING, Tracked, Tracker
from cosleec.runtime.priorities import Priorities
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.stats import Stats
from cosleec.runtime.steps import Step, Steps, weakly

T = TypeVar("T")


class InForce(Generic[T]):
    """A read-only attribute of an object with a ``core``: what the core has in force now
    (a reload swaps it), by name -- so a façade shows the core's parts, typed, without
    keeping copies that a reload would leave stale."""

    def __init__(self, name: str, doc: str) -> None:
        self.name = name
        self.__doc__ = doc

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> InForce[T]: ...
    @overload
    def __get__(self, obj: object, owner: type | None = None) -> T: ...
    def __get__(self, obj: object | None, owner: type | None = None) -> T | InForce[T]:
        if obj is None:  # on the class: the descriptor itself (help(), documentation tools)
            return self
        value: T = getattr(getattr(obj, "core"), self.name)  # noqa: B009 -- any façade with a core
        return value

    def __set__(self, obj: object, value: object) -> None:
        raise AttributeError(f"{self.name} is what the rules in force have: reload() changes it")


class Core:
    """The runtime's state (see the module docstring); its parts hold it, not copies of it."""

    def __init__(
        self,
        rules: RuleSet,
        steps: Steps,
        *,
        layers: LayerManager,
        tracker: Tracker,
        priorities: Priorities,
        max_age: dict[str, float] | None = None,
        history: int = 10_000,
        dispatch: bool = True,
    ) -> None:
        self.steps = steps
        self.max_age = dict(max_age or {})  # kept whole: a reload applies it to the measures declared then
        self.tracker = tracker
        self.stats = Stats()
        self.decisions: deque[Decision] = deque(maxlen=history)
        self.dispatch = dispatch
        steps.meta, steps.rules = weakly(self.meta), weakly(self.digest)  # (no cycle: see weakly)
        self.explanations: Explanations | None = None  # sentences for people (explain()); a reload keeps them
        self.install(rules, Context(rules.measures, max_age), layers, priorities, Implementations(rules))

    @classmethod
    def build(
        cls,
        rules: RuleSet,
        *,
        clock: Clock | None = None,
        semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
        unknown: Unknowns = Unknowns.UNDETERMINED,
        priorities: Priorities | None = None,
        untimed: str | float = "none",
    ) -> Core:
        """A core with no journal, no audit log and no Manager: for a part's own tests."""
        prio = priorities or Priorities.build((r.name for r in rules.rules), [], "cancel", 0.0)
        core = cls(
            rules,
            Steps(clock or VirtualClock(), run_id="test"),
            layers=LayerManager(rules, semantics, unknown),
            tracker=Tracker(untimed),
            priorities=prio,
        )
        core.index()
        return core

    def install(
        self,
        rules: RuleSet,
        context: Context,
        layers: LayerManager,
        priorities: Priorities,
        implementations: Implementations,
    ) -> None:
        """Put ``rules`` and what is computed from them in force (construction, a reload)."""
        self.ruleset = rules
        self.context = context
        self.layers = layers
        self.priorities = priorities
        self.implementations = implementations
        self.issuer = Issuer(context, layers, self.tracker)
        self.decider = Decider(
            context, layers, self.issuer, functools.partial(self.steps.count, "decision"), self.stats
        )
        self.decider.explain_with(self.explanations, rules.rules)

    def explain(self, explanations: Explanations | None) -> None:
        """Give decisions from now on the sentences for people ``explanations`` (checked against
        the rules by the caller); after a reload, sentences of rules or clauses the new rules
        no longer have are never said, and a measure they no longer declare reads ``unknown``."""
        self.explanations = explanations
        self.decider.explain_with(explanations, self.ruleset.rules)

    def index(self) -> None:
        """Index the tracker as the priorities need (priorities act on activations)."""
        above = bool(self.priorities.above)
        self.tracker.reindex(above, self.priorities.semantics == CONFLICT_AWARE and above)

    @property
    def spec(self) -> Specification:
        """The specification of the rules in force."""
        return self.ruleset.spec

    @property
    def journal(self) -> bool:
        """Is there a journal to keep each step's change in?"""
        return self.steps.journal is not None

    @property
    def aware(self) -> bool:
        """Do conflict-aware priorities act (declared, and some rule outranks another)?"""
        return self.priorities.semantics == CONFLICT_AWARE and bool(self.priorities.above)

    def digest(self) -> str:
        """The digest of the rules in force (``RuleSet.digest``): what heads each audit record."""
        return self.ruleset.digest

    def record(self, d: Decision, step: Step, *, queue: bool = False) -> dict[str, Any] | None:
        """Record a decision; ``queue`` puts its implementation in the journal's outbox until it ran.

        Returns the record (None when nobody records), which the step may still annotate:
        the whole record when it is made at once, else what the step adds to it, which the
        record gets when it is made (:meth:`Step.emit_later`: only when someone reads it).
        """
        self.decisions.append(d)
        self.stats.decisions += 1
        rec = None
        if self.steps.recording:
            if queue and self.journal and not self.dispatch:  # kept whole in the outbox: made now
                rec = d.to_json()
                step.emit(Kind.DECISION, rec)
            else:  # made when someone reads it; ``rec`` holds what the step adds (its dispatch)
                rec = {}
                step.emit_later(Kind.DECISION, functools.partial(_decision_record, d, rec))
            if queue and self.journal:
                entry: dict[str, Any] = {"decision": d.id, "rule": d.rule, "event": d.event}
                if not self.dispatch:  # a Manager node publishes it: kept whole, to publish again
                    entry["record"] = rec
                step.change.outbox[d.id] = entry
        return rec

    def track(self, t: Tracked, step: Step) -> None:
        """Record an obligation's new state (and keep it in the journal while it is pending)."""
        tracker = self.tracker
        if self.steps.recording:
            if self.journal:  # pending, or missed and waiting for its late event: kept now
                rec = t.to_json()
                step.emit(Kind.OBLIGATION, rec)
                keep = t.status == PENDING or tracker.waits_late(t)
                step.change.obligations[t.id] = rec if keep else None
                for gone in tracker.forgotten:
                    step.change.obligations[gone] = None
            else:  # made when someone reads it, from what it keeps of the obligation now
                step.emit_later(Kind.OBLIGATION, t.record_of())
        tracker.forgotten.clear()

    def switched(self, switches: list[LayerSwitch], step: Step) -> list[LayerSwitch]:
        """Announce layer switches to observers; returns them."""
        if switches and self.steps.recording:
            # (the state is a value: its record is made when someone reads it)
            step.emit_later(Kind.LAYERS, self.layers.record_of(switches))
        return switches

    def apply(self, stored: dict[str, Any], step: Step) -> list[LayerSwitch]:
        """(In ``step``.) Apply validated values (``Context.validate``); the layer switches they cause."""
        now, context = step.now, self.context
        changed = context.apply(stored, now)
        if self.journal:
            step.change.context.update((n, (x, now)) for n, x in context.external(stored).items())
        switches = self.layers.update(changed, context.values) if changed else []
        if changed and self.steps.recording:  # (made when someone reads it, from what it keeps)
            step.emit_later(Kind.CONTEXT, context.record_of(stored, changed))
        return self.switched(switches, step)

    def options_record(self) -> dict[str, Any]:
        """The ``options`` record: how the rules are read now (``set_semantics`` may have changed
        it since the Manager was built), what a run's verdicts depend on."""
        prio = self.priorities
        return Reading(
            semantics=self.layers.semantics,
            unknown=self.layers.unknown,
            untimed=self.tracker.untimed,
            priorities=tuple(prio.declared),
            priority_semantics=prio.semantics,
            priority_lead=prio.lead,
        ).to_json()

    def meta(self) -> dict[str, Any]:
        """What the journal keeps beside each commit: counters, rules, run, clock."""
        steps = self.steps
        counters = {
            **steps.counters,
            "obligation": self.tracker.next_id,
            "version": self.context.version,
            "layers": self.layers.version,  # the version of the next `layers` record goes on too
        }
        return {
            "rules": self.ruleset.digest,
            "run": steps.run_id,
            "lineage": steps.lineage,
            "clock_kind": type(steps.clock).__name__,
            "boot": boot(),  # a monotonic clock counts from boot: another boot, another origin
            "counters": counters,
        }

    def expire(self, now: float, step: Step) -> None:
        """Values past their ``max_age`` become unknown (a ``context`` record; layers follow)."""
        gone = self.context.expire(now)
        if gone:
            switches = self.layers.update(gone, self.context.values)
            step.emit(Kind.CONTEXT, {"values": dict.fromkeys(sorted(gone)), "stale": sorted(gone)})
            for n in gone:
                step.change.context[n] = None
            self.switched(switches, step)


def _decision_record(d: Decision, added: dict[str, Any]) -> dict[str, Any]:
    """The record of decision ``d`` with what its step ``added`` (how it was dispatched)."""
    out = d.to_json()
    out.update(added)
    return out
