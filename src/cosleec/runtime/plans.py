"""Plans: what a quiet trigger does, made once per rule set and run as straight-line code.

Most triggers meet a quiet runtime (:mod:`cosleec.runtime.express` says when: nothing in
force names the event, nothing is forbidden, held or due, every condition the rules read
is known, no priority acts) and no journal keeps the state. What the guarantees leave to do then
is the same for every occurrence of an event, except for the values read: each rule it
triggers reads its condition and the clause the Layer Manager keeps, and its decision puts
that clause's obligations in force, with their records, before its implementation runs
under the clause's COP layer. A *plan* is that, made for an event the first time it occurs:
per rule, its condition, where its status is kept, a reader of the values its decision
keeps; per clause, at its first decision, the obligations with their windows' lengths
(``untimed`` applied) when they do not depend on measures, the fields every decision of
the clause shares, the layers its implementation runs under. A trigger then runs the
plan: the checks, the choice, the records, the implementation -- one pass over what the
plan holds, no part asked again what it already said. When nobody reads records it needs
no step (only the lock: nothing to record, commit or deliver); when observers or the audit
log read them, the usual case -- one rule, one plain event -- runs in a step of its own
with the records the express lane makes, and any other goes the general way.

A plan is made from the rules in force, the semantics and the sentences for people: a
reload (a new decider), ``set_semantics`` or ``explain`` makes a new one at the next
trigger. It is a second implementation of the express lane's trigger, checked before it
changes anything the same way (the trigger returns None and the general path takes the
occurrence), held equal to the general path record for record by the express
lane's tests (``tests/unit/runtime/test_express.py``, ``test_express_generated.py``), and off with the lane
(``COSLEEC_EXPRESS=0``).
"""

from __future__ import annotations

from collections.abc import Callable
from operator import itemgetter
from typing import Any

from cosleec.cop import Layer, Snapshot
from cosleec.lang import Untimed
from cosleec.records import Kind
from cosleec.runtime.compile import always
from cosleec.runtime.core import Core
from cosleec.runtime.decider import Decider
from cosleec.runtime.decision import Decision
from cosleec.runtime.gate import Gate
from cosleec.runtime.implementations import Implementations
from cosleec.runtime.jobs import Job
from cosleec.runtime.model import CompiledRule, Obligation, ResponseSpec
from cosleec.runtime.obligations import PENDING, Tracked
from cosleec.runtime.runner import Runner
from cosleec.runtime.timer import Timer

OCCURRENCE = Kind.OCCURRENCE
Reader = Callable[[Any], tuple[Any, ...]]
# per clause: (obligations, None when made at the trigger; the spec; their windows' lengths;
# the decision's common fields; the composition; its layers); None: never quiet
_Clause = tuple[
    tuple[Obligation, ...] | None,
    ResponseSpec | None,
    tuple[float | None, ...],
    dict[str, Any],
    Snapshot,
    tuple[Layer, ...],
]
# per rule: (rule, its condition or None when always true, its status slot, its reader, per clause)
_Rule = tuple[CompiledRule, Callable[[Any], Any] | None, int, Reader, list[Any]]
# the inline case, per clause of the one rule an event triggers: (the decision's common
# fields, the obligations, the one among them, its window's length, the layers, the
# composition); None where it does not apply
_Inline = tuple[dict[str, Any], tuple[Obligation, ...], Obligation, float | None, tuple[Layer, ...], Snapshot]
# the one rule: (rule, condition, status slot, reader, value names, name, per clause)
_One = tuple[CompiledRule, Callable[[Any], Any] | None, int, Reader, tuple[str, ...], str, list[Any]]
# (the decider it was made with, the semantics, the sentences for people; per rule, None when
# no decision of the rules in force is quiet; the inline case or None)
_Plan = tuple[Decider, Any, Any, tuple[_Rule, ...] | None, _One | None]
# a decision on its way: (rule, decision, what it put in force, composition, layers, implementations)
_Job = tuple[CompiledRule, Decision, list[Tracked], Snapshot, tuple[Layer, ...], Implementations]
_Chosen = tuple[CompiledRule, int, _Clause, tuple[Obligation, ...], tuple[float | None, ...], Reader]


UNMADE: Any = object()  # a clause's part of a plan not made yet (the parts are made when first needed)


def reader(names: tuple[str, ...]) -> Reader:
    """``tuple(map(values.__getitem__, names))`` in one C call (KeyError when one is unknown)."""
    if not names:
        return lambda v: ()
    if len(names) == 1:
        (n,) = names
        return lambda v: (v[n],)
    return itemgetter(*names)


class Plans:
    """The plans of ``core``'s events (see the module docstring), made as events occur;
    the function :meth:`trigger_function` makes runs them."""

    def __init__(self, core: Core, gate: Gate, runner: Runner, timer: Timer) -> None:
        self.core = core
        self.gate = gate
        self.runner = runner
        self.timer = timer
        self.taken = 0  # triggers it took (the tests read it)
        self._made: dict[str, _Plan] = {}

    # ------------------------------------------------------------------ making
    def _plan(self, name: str) -> _Plan | None:
        """(Under the lock.) The plan of event ``name`` for the rules, semantics and sentences
        in force (made now); None when it triggers no rule."""
        core = self.core
        decider = core.decider
        rules = core.ruleset.by_trigger.get(name)
        if rules is None:
            return None
        if len(self._made) > 4 * len(core.ruleset.by_trigger) + 64:  # (old rule sets' events: forgotten)
            self._made.clear()
        # what never changes while these rules are in force and sends every trigger elsewhere
        never = bool(core.priorities.above) or core.context.aging or decider.speaks
        planned = None if never else tuple(self._rule(rule) for rule in rules)
        one = self._one(planned[0]) if planned is not None and len(planned) == 1 else None
        plan = self._made[name] = (decider, core.layers.semantics, decider.explanations, planned, one)
        return plan

    def _rule(self, rule: CompiledRule) -> _Rule:
        """A rule's part of a plan; its clauses' parts are made when a decision first needs them
        (:meth:`clause_of`): an event's first trigger pays for one clause, not for all."""
        condition = None if rule.condition is always else rule.condition
        return rule, condition, rule.index, reader(rule.value_names), [UNMADE] * len(rule.layer_names)

    @staticmethod
    def _one(planned: _Rule) -> _One:
        """The inline case of an event that triggers one rule (its clauses' parts made when
        first needed: :meth:`inline_of`)."""
        rule, condition, index, reader, clauses = planned
        return rule, condition, index, reader, rule.value_names, rule.name, [UNMADE] * len(clauses)

    def clause_of(self, rule: CompiledRule, clause: int, clauses: list[Any]) -> _Clause | None:
        """(Under the lock.) The part of ``rule``'s plan for ``clause``, made now if not yet
        (kept in ``clauses``); None when no decision at it is quiet."""
        entry = clauses[clause]
        if entry is UNMADE:
            entry = clauses[clause] = self._clause(rule, clause)
        return entry  # type: ignore[no-any-return]

    def inline_of(self, rule: CompiledRule, clause: int, inline: list[Any]) -> _Inline | None:
        """(Under the lock.) The inline part of the one rule's plan for ``clause``, made now if
        not yet (kept in ``inline``): what a decision that requires one plain event made once
        needs; None when a decision at it is not that."""
        entry = inline[clause]
        if entry is UNMADE:
            made = self._clause(rule, clause)
            obligations = None if made is None else made[0]
            if made is None or obligations is None or len(obligations) != 1:
                entry = None
            else:
                _, _, offsets, fields, composition, layers = made
                fields = {**fields, "obligations": obligations}  # (every decision at it has them)
                entry = (fields, obligations, obligations[0], offsets[0], layers, composition)
            inline[clause] = entry
        return entry  # type: ignore[no-any-return]

    def _clause(self, rule: CompiledRule, clause: int) -> _Clause | None:
        """What every decision of ``rule`` at ``clause`` shares; None when none is quiet (an
        inner choice, or obligations that are never plain)."""
        core = self.core
        spec = rule.response_of(clause)
        obligations: tuple[Obligation, ...] | None = ()
        offsets: tuple[float | None, ...] = ()
        if spec is not None:
            if spec.clauses:
                return None
            obligations, offsets = None, ()
            if spec.fixed:
                obligations = core.issuer.items(spec, rule.name)
                found = self.windows(obligations)
                if found is None:
                    return None
                offsets = found
        fields = Decision.trigger_fields(
            rule,
            clause,
            semantics=core.layers.semantics,
            unknown=core.layers.unknown,
            explanations=core.decider.explanations,
        )
        composition = rule.compositions[clause]
        return obligations, spec, offsets, fields, composition, composition.layers

    def windows(self, obligations: tuple[Obligation, ...]) -> tuple[float | None, ...] | None:
        """Each plain obligation's window length from the trigger (``untimed`` applied; None:
        no deadline); None when one is not plain (a prohibition, an `else`, a window that
        opens later or closes before it starts): the general path puts those in force."""
        tracker = self.core.tracker
        out: list[float | None] = []
        for ob in obligations:
            if ob.negated or ob.alternatives or ob.from_s or (ob.within_s is not None and ob.within_s < 0):
                return None
            hi = ob.within_s
            if hi is None and not ob.eventually:  # what Tracker.start makes of an untimed response
                if tracker.untimed == Untimed.IMMEDIATE:
                    hi = tracker.tolerance
                elif isinstance(tracker.untimed, int | float) and not isinstance(tracker.untimed, bool):
                    hi = float(tracker.untimed)
            out.append(hi)
        return tuple(out)

    # ------------------------------------------------------------------ running
    def trigger_function(self) -> Callable[[str], list[Decision] | None]:
        """``trigger``, as a closure over what it reads (the parts a reload keeps); what a
        reload replaces is read through the plan, made for the rules in force. Its owner
        keeps it (this object does not: it would be a reference cycle).

        ``trigger(name)``: event ``name`` occurred, when the runtime is quiet and no journal
        keeps it: its decisions, once their implementations ran (as the general path runs
        them); None, having changed nothing, otherwise (the general path takes it). When
        nobody reads records it takes the runtime's lock without a step: a step would have
        nothing to record, commit or deliver, so what the lock alone guarantees -- this
        occurrence ordered with every other step -- is what is left. The usual case -- one
        rule, which fires, its clause requiring one plain event -- runs inline; any other,
        through :meth:`_choose`, :meth:`_put_in_force` and :meth:`_run`. When observers or
        the audit log read records, the usual case runs inline in a step, with the records
        the express lane makes (occurrence, decision, obligation; the outcome in a step of
        its own, as :meth:`Runner.finished` records it); any other goes the general way.
        """
        core, gate, timer, runner = self.core, self.gate, self.timer, self.runner
        steps, tracker, stats = core.steps, core.tracker, core.stats
        lock = steps.lock
        counters = steps.counters
        now_of = steps.clock.now
        made, plan_of = self._made, self._plan
        quiet_for, start_plain, forgotten = tracker.quiet_for, tracker.start_plain, tracker.forgotten
        history = core.decisions.append
        new_decision, set_dict = object.__new__, object.__setattr__
        choose, put_in_force, run = self._choose, self._put_in_force, self._run
        inline_of = self.inline_of
        local = runner.depth
        me = self

        def trigger(name: str) -> list[Decision] | None:
            if type(name) is not str:  # (a lookalike or unhashable name: the general path refuses it)
                return None
            # records read by observers or the audit log: in a step, made as the lane makes them
            recording = bool(steps.observers) or steps.audit is not None
            if recording and (steps.broken is not None or steps.closed or steps.before_commit is not None):
                return None  # (a refusal, or a step another part adds to: the general way)
            scope: Any = steps.step() if recording else lock  # (as `step`: the Step, or the lock's True)
            with scope as step:
                if (
                    steps.broken is not None
                    or steps.closed
                    or steps.journal is not None
                    or (bool(steps.observers) or steps.audit is not None) is not recording
                ):
                    return None  # (a refusal, a journal, or a reader come or gone since: the general way)
                decider = core.decider
                plan = made.get(name)
                if (
                    plan is None
                    or plan[0] is not decider
                    or plan[1] is not core.layers.semantics
                    or plan[2] is not decider.explanations
                ):
                    plan = plan_of(name)
                    if plan is None:
                        return None
                rules, one = plan[3], plan[4]
                if rules is None or gate.held:
                    return None
                now = step.now if recording else now_of()  # read under the lock, as a step reads it
                if not quiet_for(name, now):
                    return None
                if one is not None:  # one rule: it fires, its clause's one plain event, inline
                    rule, condition, index, reader, value_names, rname, clauses = one
                    context = core.context
                    v = context.values
                    try:
                        fired = condition is None or condition(v)
                    except KeyError:  # unknown: the decider reads it with the `unknown` policy
                        return None
                    status = core.layers.status[index]
                    clause = status[1]  # (RuleStatus.clause)
                    if clause is None:
                        entry = None
                    else:
                        entry = clauses[clause]
                        if entry is UNMADE:  # (the clause's first decision: its part made now)
                            entry = inline_of(rule, clause, clauses)
                    if not fired or entry is None:
                        one = None  # (the general way below: nothing, or what is not inline)
                    else:
                        fields, _, ob, off, layers, composition = entry
                        me.taken += 1
                        stats.events += 1
                        seq = counters["seq"]
                        counters["seq"] = seq + 1
                        did = counters["decision"]
                        counters["decision"] = did + 1
                        try:
                            read = reader(v)
                        except KeyError:  # an unknown value the condition did not need: None
                            read = tuple(map(v.get, value_names))
                        dd = fields.copy()  # (Decision.from_trigger_fields, its obligations in `fields`)
                        dd["id"] = did
                        dd["time"] = now
                        dd["event"] = name
                        dd["context_version"] = context.version
                        dd["_parts"] = (rule, read, True, status[0])
                        d = new_decision(Decision)
                        set_dict(d, "__dict__", dd)
                        t = start_plain(did, clause, rname, ob, now, None if off is None else now + off, seq)
                        if recording:
                            # the occurrence, the decision and its obligation, as the lane records them
                            step.emit(OCCURRENCE, {"event": name, "causal": seq}, now)
                            core.record(d, step, queue=True)
                            core.track(t, step)
                        else:
                            history(d)
                            stats.decisions += 1
                            forgotten.clear()  # (what Core.track does when nobody reads records)
                        impl = core.implementations
                if one is None:
                    if recording:  # (not inline: the lane makes its records, in the general path's step)
                        return None
                    chosen = choose(rules)
                    if chosen is None:
                        return None
                    me.taken += 1
                    jobs = put_in_force(name, chosen, now)
                due = None if timer.thread is None else timer.due_at()
            if due is not None:
                timer.notify(due)
            if one is None:
                if core.dispatch:
                    for job in jobs:
                        run(*job)
                return [job[1] for job in jobs]
            if not core.dispatch:
                return [d]
            with lock:  # admitted: what the gate's common case checks, under the lock
                if steps.broken is not None or steps.closed:
                    return [d]
                plain = not tracker.bans and t.status == PENDING
                checked = counters["record"] - 1  # (Steps.last_record)
            depth = getattr(local, "n", 0)
            if not plain or depth >= runner.max_depth or rname in impl.tasks:
                run(rule, d, [t], composition, layers, impl, admitted=plain, checked=checked)
                return [d]
            local.n = depth + 1
            try:
                ran = impl.capability_under(layers, rule, d, ob)
            finally:
                local.n = depth
            if len(ran) != 1 or ran[0].error is not None or steps.observers or steps.audit or steps.journal:
                runner.finished(rule, d, ran, checked)  # (a failure to count, or records to make)
            return [d]

        return trigger

    def _choose(self, rules: tuple[_Rule, ...]) -> list[_Chosen] | None:
        """(Under the lock.) The rules that fire, each with its clause and obligations; None
        when some rule's decision is not quiet (an unknown value, an inner choice, an
        obligation that is not plain): nothing is changed to find out."""
        core = self.core
        v = core.context.values
        status = core.layers.status
        chosen: list[_Chosen] = []
        for rule, condition, index, reader, clauses in rules:
            if condition is not None:
                try:
                    if not condition(v):
                        continue
                except KeyError:  # unknown: the decider reads it with the `unknown` policy
                    return None
            clause = status[index][1]  # (RuleStatus.clause)
            if clause is None:
                return None
            entry = clauses[clause]
            if entry is UNMADE:  # (the clause's first decision: its part made now)
                entry = self.clause_of(rule, clause, clauses)
            if entry is None:
                return None
            obligations, offsets = entry[0], entry[2]
            if obligations is None:  # obligations that depend on measures: made now
                spec = entry[1]
                assert spec is not None
                obligations = core.issuer.items(spec, rule.name)
                found = self.windows(obligations)
                if found is None:
                    return None
                offsets = found
            chosen.append((rule, clause, entry, obligations, offsets, reader))
        return chosen

    def _put_in_force(self, name: str, chosen: list[_Chosen], now: float) -> list[_Job]:
        """(Under the lock.) The occurrence at ``now``, then each rule's decision and its
        obligations, in the order the general path makes them; what runs each."""
        core = self.core
        tracker, counters, stats = core.tracker, core.steps.counters, core.stats
        v, status, version = core.context.values, core.layers.status, core.context.version
        impl = core.implementations
        stats.events += 1
        seq = counters["seq"]
        counters["seq"] = seq + 1
        made = []
        for rule, clause, entry, obligations, offsets, reader in chosen:
            did = counters["decision"]
            counters["decision"] = did + 1
            try:
                read = reader(v)
            except KeyError:  # an unknown value the condition did not need: None, as v.get gives it
                read = tuple(map(v.get, rule.value_names))
            d = Decision.from_trigger_fields(
                entry[3], did, now, name, obligations, (), version, (rule, read, True, status[rule.index][0])
            )
            rname = rule.name
            started = [
                tracker.start_plain(did, clause, rname, ob, now, None if off is None else now + off, seq)
                for ob, off in zip(obligations, offsets)
            ]
            core.decisions.append(d)
            stats.decisions += 1
            tracker.forgotten.clear()  # (what Core.track does when nobody reads records)
            made.append((rule, d, started, entry[4], entry[5], impl))
        return made

    def _run(
        self,
        rule: CompiledRule,
        d: Decision,
        started: list[Tracked],
        composition: Snapshot,
        layers: tuple[Layer, ...],
        impl: Implementations,
        *,
        admitted: bool | None = None,
        checked: int = 0,
    ) -> None:
        """Decision ``d``'s implementation, as :meth:`Runner.dispatch` runs its job: admitted
        under the lock (what the gate's common case checks; anything else, the gate
        itself), then run in the runner's depth guard with the clause's layers active, its
        outcome counted (and recorded, should someone read records by then). ``admitted``:
        the common case's check already made (its answer, with ``checked``)."""
        core = self.core
        steps = core.steps
        if admitted is None:
            with steps.lock:
                if steps.broken is not None or steps.closed:
                    return
                admitted = not core.tracker.bans and all([t.status == PENDING for t in started])
                checked = steps.counters["record"] - 1  # (Steps.last_record)
        runner = self.runner
        local = runner.depth
        depth = getattr(local, "n", 0)
        if not admitted:  # something may forbid or have ended it: the gate decides, as for any job
            runner.dispatch([Job(rule, d, composition, started, None, impl)])
        elif rule.name in impl.tasks or depth >= runner.max_depth:
            runner.run(rule, d, impl.dispatch, checked, (), (rule, d, composition))
        else:
            local.n = depth + 1
            try:
                if len(started) == 1:
                    ran = impl.capability_under(layers, rule, d, started[0].obligation)
                else:
                    ran = impl.capabilities_under(layers, rule, d)
            finally:
                local.n = depth
            runner.finished(rule, d, ran, checked)
