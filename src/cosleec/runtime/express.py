"""The express lane: a trigger or a context update in the common, quiet case, as straight-line code.

Most triggers meet a quiet runtime: nothing in force names the event, nothing is
forbidden or held, no deadline is due, every condition the rules read is known and no
priority is declared. Then the general path's stages -- time passing, the occurrence
meeting what is in force, the decider, the enforcer's settling, the gate -- each find
nothing to do, and what is left is what the guarantees require: the occurrence, each
triggered rule's decision and its obligations put in force, each with its record. This
lane does exactly that in one pass, without the stages' calls (:meth:`Express.occur`, in
the general path's step, for what the event's plan leaves: :mod:`cosleec.runtime.plans`
takes the usual case itself, in a step of its own when records are read, without one when
nobody reads them).

A context update meets the same quiet runtime when no journal keeps the state: then time
passing, the gate and the runner each find nothing to do, and what is left is the values
validated, stored and stamped, and the rules that read them re-evaluated
(:meth:`Express.update`) -- when nobody reads records, without a step (nothing to record,
commit or deliver); else in one, with the records the general path makes. An update that
is rejected is recorded by the general path, with the reason the lane found.

It is a second implementation of that case, so it decides nothing the general path
would not: it first checks, before changing anything, that every stage would find
nothing to do (:meth:`Express.occur` returns None otherwise, and the general path takes
the trigger), and a property test holds the two equal, record for record, on generated
rule sets and traces (``tests/unit/runtime/test_express_generated.py``; hand-made cases in
``test_express.py``). It never runs with a
journal (a decision's outbox entry and its commit are the general path's), so the kill
campaigns exercise the general path. ``COSLEEC_EXPRESS=0`` turns it off, for the suite
to run against the general path alone.
"""

from __future__ import annotations

import os
from collections.abc import Collection, Mapping

from cosleec.records import Kind
from cosleec.runtime.core import Core
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import ContextError
from cosleec.runtime.gate import Gate
from cosleec.runtime.jobs import Job
from cosleec.runtime.layers import LayerSwitch
from cosleec.runtime.model import CompiledRule, Obligation
from cosleec.runtime.steps import Step


def enabled() -> bool:
    """Is the express lane on (``COSLEEC_EXPRESS`` unset or not ``0``)? Read when a Manager is built."""
    return os.environ.get("COSLEEC_EXPRESS", "1").strip() != "0"


class Express:
    """Triggers ``core`` in the quiet case (see the module docstring); ``gate`` says what is held."""

    def __init__(self, core: Core, gate: Gate) -> None:
        self.core = core
        self.gate = gate
        self.taken = 0  # triggers it took (the tests read it: each guard sends some elsewhere)
        self.updated = 0  # updates it took

    def update(self, updates: Mapping[str, object]) -> list[LayerSwitch] | ContextError | None:
        """Apply ``updates`` and return the layer switches, when the runtime is quiet and no
        journal keeps it (records read: :meth:`_recorded`); None, having changed nothing,
        when the general path must; the
        ContextError, having changed nothing, when the update is rejected (the general path
        records the rejection with it: the values are not checked twice, and a value's
        ``repr`` runs as often as on the general path)."""
        core = self.core
        steps, context = core.steps, core.context
        if steps.observers or steps.audit is not None:
            return self._recorded(updates)
        with steps.lock:  # what the general path's step would check, under the same lock
            if (
                steps.broken is not None
                or steps.closed
                or steps.journal is not None
                or steps.before_commit is not None
                or steps.recording
                or context.aging
                or core.aware
                or self.gate.held
            ):
                return None
            now = steps.clock.now()  # read under the lock, as a step reads it
            if core.tracker.backlog(now):
                return None
            changed: Collection[str]
            known = context.apply_booleans(updates, now)
            if known is None:  # not only booleans: checked and stored as the general path does
                try:
                    stored = context.validate(updates)
                except ContextError as e:
                    return e
                changed = context.apply(stored, now)
            else:  # (booleans: the rules that read them judged again, if anything changed)
                changed = updates.keys() if known else ()
            core.stats.updates += 1
            self.updated += 1
            return core.layers.update(changed, context.values) if changed else []

    def _recorded(self, updates: Mapping[str, object]) -> list[LayerSwitch] | ContextError | None:
        """:meth:`update` when observers or the audit log read records (and no journal keeps
        the state): in a step, the values checked and applied with their records
        (:meth:`Core.apply`: the ``context`` record, the ``layers`` record of any switch), as
        the general path applies them; the general path's other stages -- time passing, the
        gate, the runner -- each find nothing to do in a quiet runtime, so none is asked."""
        core = self.core
        steps, context = core.steps, core.context
        if steps.broken is not None or steps.closed or steps.before_commit is not None:
            return None  # (a refusal, or a step another part adds to: the general way)
        with steps.step() as step:
            if (
                steps.journal is not None
                or not (steps.observers or steps.audit is not None)
                or context.aging
                or core.aware
                or self.gate.held
                or core.tracker.bans
                or core.tracker.backlog(step.now)
            ):
                return None
            try:
                stored = context.validate(updates)
            except ContextError as e:
                return e
            core.stats.updates += 1
            self.updated += 1
            return core.apply(stored, step)

    def occur(self, name: str, step: Step) -> tuple[list[Decision], list[Job]] | None:
        """(In ``step``: records are read.) Event ``name`` occurred: its decisions and the jobs
        that run them, when the case is quiet; None, having changed nothing, when the general
        path must take it. (The event's plan takes the usual quiet case before any step is
        begun: :mod:`cosleec.runtime.plans`; this is the rest.)"""
        chosen = self._quiet(name, step.now)
        if chosen is None:
            return None
        self.taken += 1
        return self._put_in_force(name, chosen, step.now, step)

    def _quiet(self, name: str, now: float) -> list[tuple[CompiledRule, int, tuple[Obligation, ...]]] | None:
        """(Under the lock.) What the rules ``name`` triggers decide, when every stage of the
        general path would find nothing to do at ``now``; None otherwise."""
        if type(name) is not str:  # (a lookalike or unhashable name: the general path refuses it)
            return None
        core = self.core
        rules = core.ruleset.by_trigger.get(name)
        tracker = core.tracker
        if (
            rules is None
            or core.steps.journal is not None
            or tracker.bans
            or self.gate.held
            or core.priorities.above
            or core.context.aging
            or tracker.backlog(now)
            or tracker.waits_for(name)
            or core.decider.speaks
        ):
            return None
        return self._choose(rules)

    def _choose(
        self, rules: tuple[CompiledRule, ...]
    ) -> list[tuple[CompiledRule, int, tuple[Obligation, ...]]] | None:
        """The rules that fire, each with its clause and obligations; None when some rule's
        decision is not quiet (an unknown value, an inner choice, a prohibition, an interval
        that opens later or a window closed at its start): nothing is changed to find out."""
        core = self.core
        v = core.context.values
        status = core.layers.status
        issuer = core.issuer
        chosen = []
        for rule in rules:
            try:
                if not rule.condition(v):
                    continue
            except KeyError:  # unknown: the decider reads it with the `unknown` policy
                return None
            clause = status[rule.index].clause
            if clause is None:
                return None
            spec = rule.response_of(clause)
            obligations: tuple[Obligation, ...] = ()
            if spec is not None:
                if spec.clauses:
                    return None
                obligations = issuer.items(spec, rule.name)
                for ob in obligations:
                    if (
                        ob.negated
                        or ob.alternatives
                        or ob.from_s
                        or (ob.within_s is not None and ob.within_s < 0)
                    ):
                        return None
            chosen.append((rule, clause, obligations))
        return chosen

    def _put_in_force(
        self,
        name: str,
        chosen: list[tuple[CompiledRule, int, tuple[Obligation, ...]]],
        now: float,
        step: Step,
    ) -> tuple[list[Decision], list[Job]]:
        """(Under the lock.) The occurrence at ``now``, then each rule's decision and its
        obligations, with their records in ``step``, in the order the general path makes
        them (the plans take the usual case, and every case when nobody reads records:
        cosleec.runtime.plans)."""
        core = self.core
        steps, tracker = core.steps, core.tracker
        core.stats.events += 1
        counters = steps.counters
        seq = counters["seq"]
        counters["seq"] = seq + 1
        if steps.recording:
            step.emit(Kind.OCCURRENCE, {"event": name, "causal": seq}, now)
        decider, status = core.decider, core.layers.status
        decisions: list[Decision] = []
        jobs: list[Job] = []
        for rule, clause, obligations in chosen:
            did = counters["decision"]
            counters["decision"] = did + 1
            d = decider.at_trigger(
                did, rule, name, now, clause, True, status[rule.index].values, obligations, ()
            )
            decisions.append(d)
            started = [tracker.start(did, clause, ob, now, seq, 0, did) for ob in obligations]
            rec = core.record(d, step, queue=True)
            for t in started:
                core.track(t, step)
            jobs.append(Job(rule, d, rule.compositions[clause], started, rec, core.implementations))
        return decisions, jobs
