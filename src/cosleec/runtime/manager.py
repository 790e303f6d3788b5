"""The Manager: rules, context, layers, decisions and obligations, in one process.

It plays the paper's *Manager* role (owns the rules and the context) and hosts the COP
*Layer Manager* (:mod:`cosleec.runtime.layers`); a *Context Listener* feeds it from the
robot's topics (``cosleec.nodes``). It is a façade: each public method takes one step
(:mod:`~cosleec.runtime.steps`: one lock; the step's records written and its change
committed together) over parts that each do one job and are tested alone, all reading one
:class:`~cosleec.runtime.core.Core`: the decider and issuer (a trigger becomes a decision
and its obligations), the enforcer (obligations begin, meet events, fall due, conflict),
the gate (what is forbidden for now waits; ``request`` and dispatch never disagree), the
runner (implementations run outside the lock), the timer, reload and restore.

When the runtime does not know, it fails closed, each case a documented policy: an
unknown measure makes a decision *undetermined* (nothing runs; every prohibition that
could apply is enforced); a deadline over an unknown measure is now for an obligation and
:data:`~cosleec.runtime.model.MAX_WINDOW_S` for a prohibition; an undeclared event raises
ContextError or is refused (``unknown_events``); a failed journal stops every decision and
``request`` refuses (``docs/runtime.md``, "What the runtime guarantees").
"""

from __future__ import annotations

import itertools
import logging
import threading
import uuid
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from cosleec.bulk import paused_gc
from cosleec.errors import clip, show
from cosleec.lang import HedgeSemantics, Specification, clause_semantics_for, one_of
from cosleec.records import Kind, RuntimeEvent
from cosleec.runtime import express
from cosleec.runtime import reload as reloading
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import MonotonicClock, VirtualClock
from cosleec.runtime.context import Context
from cosleec.runtime.core import Core, InForce
from cosleec.runtime.decision import Decision
from cosleec.runtime.enforcer import Enforcer
from cosleec.runtime.errors import BindingError, ConfigurationError, ContextError
from cosleec.runtime.express import Express
from cosleec.runtime.gate import Gate
from cosleec.runtime.implementations import Capability, Implementations
from cosleec.runtime.jobs import Job
from cosleec.runtime.journal import Journal, JournalError
from cosleec.runtime.layers import LayerManager, LayerSwitch
from cosleec.runtime.obligations import Tracked, Tracker
from cosleec.runtime.options import Options, UnknownEvents, explanations_of
from cosleec.runtime.permission import Answers, Permission, undeclared
from cosleec.runtime.plans import Plans
from cosleec.runtime.priorities import PossibleConflict, Priorities, warn_conflicts, warn_lead
from cosleec.runtime.reload import Reloaded
from cosleec.runtime.restore import open_journal
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.runner import Runner
from cosleec.runtime.steps import Step, Steps, weakly
from cosleec.runtime.tasks import Task
from cosleec.runtime.timer import Timer
from cosleec.runtime.watch import ClockWatch

log = logging.getLogger("cosleec.runtime")

__all__ = ["Manager", "Permission", "Reloaded", "RuntimeEvent", "UnknownEvents"]


class Manager:
    """Runs a rule set in one process: the embedded CO-SLEEC runtime.

    Use it to enforce SLEEC rules inside a Python program (the ROS Manager node wraps
    one). Build it from a :class:`RuleSet` or with :meth:`from_file` / :meth:`from_text`;
    bind tasks (:meth:`bind`) or capabilities (:meth:`capability`), :meth:`start` it, then
    feed it measures (:meth:`update`) and events (:meth:`event`), and ask before acting
    (:meth:`request`, an attempt: a refusal is recorded; :meth:`permission`, a question:
    nothing is). :meth:`reload` puts new rules
    in force while it runs. The options (``semantics``, ``clock``, ``unknown``,
    ``unknown_events``, ``untimed``, ``audit``, ``journal``, ``reset_journal``, ``max_age``,
    ``history``, ``max_depth``, ``dispatch``, ``priorities``, ``priority_semantics``,
    ``priority_lead``, ``explanations``) are those of :class:`~cosleec.runtime.options.Options`, which says
    what each means; give them as keywords, or one ``options=Options(...)``.
    """

    @paused_gc()
    def __init__(self, rules: RuleSet, *, options: Options | None = None, **given: Any) -> None:
        if not isinstance(rules, RuleSet):
            raise TypeError(
                f"Manager needs a RuleSet, not {type(rules).__name__}: "
                "use Manager.from_file(path), Manager.from_text(text) or Manager(RuleSet.from_spec(spec))"
            )
        o = Options.build(**given) if options is None else options.replace(**given)
        self.clock = o.clock or MonotonicClock()
        self.unknown_events = o.unknown_events
        self.max_depth = o.max_depth
        self.dispatch = o.dispatch  # False: it decides, a Manager node publishes the decisions
        self.run_id = uuid.uuid4().hex[:12]
        prio = Priorities.build(
            (r.name for r in rules.rules), o.all_priorities(rules.spec), o.priority_semantics, o.priority_lead
        )
        self._given = list(o.priorities)  # the caller's priorities (not the file's): a reload keeps them
        self._semantics = o.semantics  # the caller's clause semantics (None: each rule file's own)
        steps = Steps(self.clock, run_id=self.run_id)
        core = Core(
            rules,
            steps,
            layers=LayerManager(rules, clause_semantics_for(rules.spec, o.semantics), o.unknown),
            tracker=Tracker(o.untimed),
            priorities=prio,
            max_age=dict(o.max_age or {}),
            history=o.history,
            dispatch=o.dispatch,
        )
        core.index()
        words = explanations_of(o.explanations)
        core.explain(None if words is None else words.check(rules))  # before anything is opened
        self.core, self.stats, self.decisions, self.tracker = core, core.stats, core.decisions, core.tracker
        self._answers = Answers(core)
        self._gate = Gate(core, self._answers)
        self.undelivered = self._gate.undelivered  # decisions to publish again after a restart
        self._enforcer = Enforcer(core)
        self._runner = Runner(core, self._gate, o.max_depth)
        self._express = Express(core, self._gate) if express.enabled() else None
        self._timer = Timer(core, self._enforcer, self._gate, weakly(self.tick))
        self._plans = Plans(core, self._gate, self._runner, self._timer) if express.enabled() else None
        self._planned = None if self._plans is None else self._plans.trigger_function()
        self.possible_conflicts: list[PossibleConflict] = []  # item pairs that can conflict (start() warns)
        self._check = False  # start() checked the bindings: a reload checks the new rules' too
        self._started = False  # start() ran, or the first event/update/request started it
        self._starting = threading.Lock()
        self._watch = ClockWatch(weakly(self._judge), core.steps)  # a virtual clock's moves judge
        self.audit: AuditLog | None = None
        self.journal: Journal | None = None
        self._open(o)  # last: what it opens (files, locks) is not left open by a refusal above

    def _open(self, o: Options) -> None:
        """Open the audit log and the journal, and restore what it holds; on refusal, free what was opened."""
        self.audit = o.audit if isinstance(o.audit, AuditLog) else AuditLog(o.audit) if o.audit else None
        self.core.steps.keep(self.audit)
        try:
            self.journal = (
                o.journal if isinstance(o.journal, Journal) else Journal(o.journal) if o.journal else None
            )
            if self.journal is not None:
                self.core.steps.journal = self.journal
                # what a Manager node published leaves the outbox as the next step commits
                self.core.steps.before_commit = weakly(self._gate.before_commit)
                open_journal(self.core, self._gate, self._enforcer, reset=o.reset_journal)
        except BaseException:  # refused: what this constructor opened is free again (the audit log's lock)
            if self.journal is not None and self.journal is not o.journal:
                self.journal.close()
            if self.audit is not None and self.audit is not o.audit:
                self.audit.close()
            # the parts refer to each other (a cycle the collector frees late): drop what
            # they hold now, so a caller's audit log is released as soon as the caller drops it
            self.audit = self.journal = self.core.steps.audit = self.core.steps.journal = None
            raise

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

    # ------------------------------------------------------------------ what is in force (reload swaps it)
    @property
    def ruleset(self) -> RuleSet:
        """The rules in force."""
        return self.core.ruleset

    spec: InForce[Specification] = InForce("spec", "The specification of the rules in force.")
    context: InForce[Context] = InForce("context", "The measures' values (read them with values()).")
    layer_manager: InForce[LayerManager] = InForce(
        "layers", "The COP Layer Manager: each rule's active layer."
    )
    implementations: InForce[Implementations] = InForce(
        "implementations", "The tasks and capabilities bound."
    )
    priorities: InForce[Priorities] = InForce("priorities", "The priorities between the rules in force.")

    @property
    def lineage(self) -> str:
        """The history this Manager continues: its journal's (kept across restarts), else this run's."""
        return self.core.steps.lineage

    @property
    def rules_hash(self) -> str:
        """The digest of the rules in force (:attr:`RuleSet.digest`); it heads every audit record."""
        return self.core.ruleset.digest

    @property
    def semantics(self) -> HedgeSemantics:
        """How clauses combine: last-wins (SLEEC) or nested (the paper's formula)."""
        return self.core.layers.semantics

    # ------------------------------------------------------------------ wiring
    def bind(self, *tasks: Task) -> Manager:
        """Bind paper-style tasks, one per rule, and make this Manager their reporter (``task.manager``).

        BindingError when a task names no rule, an unknown rule, or a clause its rule does
        not have; a second task for the same rule replaces the first. Bind before
        :meth:`start`: its completeness check sees only what is bound. Returns ``self``.
        """
        for t in tasks:
            self.core.implementations.bind(t)
            t.manager = self
        return self

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        """Decorator: register ``fn(obligation, decision)`` as the way the robot performs ``event``
        (for every rule without a task, and every ``otherwise``). BindingError, with the closest
        names, when no response of the rules names ``event``."""
        return self.core.implementations.capability(event)

    def subscribe(self, fn: Callable[[RuntimeEvent], None]) -> Callable[[], None]:
        """Call ``fn`` with every :class:`RuntimeEvent` from now on; returns the function that unsubscribes.

        Observers hear every record once, in the order made, after the step that made it (see
        :mod:`~cosleec.runtime.steps`). One that raises is removed, and its removal recorded
        (``observer-removed``). Keep them quick: they delay the caller. While anyone
        listens, the Manager builds record payloads it otherwise skips.
        """
        return self.core.steps.subscribe(fn)

    @paused_gc()
    def start(self, *, check: bool = True, timer: bool = False) -> Manager:
        """Check that every clause has an implementation; judge what happened while down; optionally
        run deadlines on a thread. Returns ``self``.

        Warns when the rules can conflict (:attr:`possible_conflicts`). The check raises
        BindingError listing what is missing (skipped with ``check=False`` or without
        dispatch). With a journal, deadlines that passed while down are judged now (their
        ``otherwise`` runs once). ``timer=True`` judges deadlines and stale values on a
        daemon thread; on a :class:`VirtualClock`, every ``advance``/``set`` of the clock
        judges what fell due (this Manager ticks); otherwise call :meth:`tick`.

        Call it before the first :meth:`event`, :meth:`update` or :meth:`request`: one of
        those on a Manager not started starts it (:meth:`_start_implicitly`), with a warning.
        """
        self._started = True
        core = self.core
        self.possible_conflicts = warn_conflicts(core.ruleset, core.priorities)
        if check and core.dispatch:
            core.implementations.check()
            self._check = True
        self._begin()
        if timer:
            self._timer.start(self.tick)  # held while it runs: close() stops it
        return self

    def _begin(self) -> None:
        """What every start does after the completeness check: the ``options`` record, the
        priority-lead warning, the handlers built, what fell due judged, the virtual clock watched."""
        core = self.core
        if core.steps.recording:  # what the run's verdicts depend on: `cosleec conforms` reads it back
            with core.steps.step() as step:
                step.emit(Kind.OPTIONS, core.options_record())
        warn_lead(core.priorities, not isinstance(self.clock, VirtualClock))
        if core.dispatch:
            core.implementations.prepare()  # start-up work, not the first trigger's latency
        self.tick()
        self._watch.begin(self.clock)  # moving a virtual clock judges what fell due

    def _start_implicitly(self, what: str) -> None:
        """The policy for ``event``/``update``/``request`` before :meth:`start`: start now.

        The Manager starts itself as ``start()`` would (the conflict warnings, the
        ``options`` record, what fell due judged, the virtual clock watched), and says so in
        a warning that names :meth:`start` -- with, when the implementations are incomplete,
        what the completeness check found: a warning here, not BindingError, so that code
        written before this policy keeps running, but never silently. Call ``start()``
        (or ``start(check=False)`` when nothing is implemented on purpose) to have no warning.
        """
        with self._starting:
            if self._started:
                return
            self._started = True
            core = self.core
            self.possible_conflicts = warn_conflicts(core.ruleset, core.priorities)
            missing = core.implementations.missing() if core.dispatch else []
            found = f"; the completeness check found an {BindingError(missing).message}" if missing else ""
            log.warning(
                "Manager.%s() before start(): the Manager started itself%s\n  hint: call start() before the "
                "first event, update or request (start(check=False) when no implementation is bound on purpose)",
                what,
                found,
            )
            self._begin()

    def close(self) -> None:
        """Stop the timer thread (waiting up to 5 s), then close the journal and the audit log.

        Call it once, when done: a Manager used after closing fails on its next record.
        """
        self._timer.stop()
        self._watch.stop()
        steps = self.core.steps
        with steps.lock:
            if steps.closed:
                return
            steps.closed = True
            try:
                if self.journal is not None and self._gate.pending_delivery and steps.broken is None:
                    steps.commit(Step())  # what was published leaves the outbox (JournalError if not)
            finally:  # the files are released whatever happened: neither close raises
                if self.journal is not None:
                    self.journal.close()
                if self.audit is not None:
                    self.audit.close()

    # ------------------------------------------------------------------ context
    def update(self, values: Mapping[str, object] | None = None, /, **kw: object) -> list[LayerSwitch]:
        """Set measure values atomically; returns the layer switches ``(rule, old, new)``.

        A wrong type, unknown measure, value outside a scale, non-finite or out-of-range
        number raises ContextError with the reason, and nothing changes (the rejection is
        recorded).
        """
        updates = {**(values or {}), **kw}
        core = self.core
        if not self._started:
            self._start_implicitly("update")
        known, context = None, core.context
        if self._express is not None:  # the quiet case straight through (cosleec.runtime.express)
            quiet = self._express.update(updates)
            if isinstance(quiet, ContextError):
                known = quiet  # rejected there: recorded here, as any rejection (not checked twice)
            elif quiet is not None:
                return quiet
        self._catch_up()
        with core.steps.step() as step:
            try:
                if known is not None and core.context is context:  # (a reload since: check again)
                    raise known
                stored = core.context.validate(updates)
            except ContextError as e:
                core.stats.rejected += 1
                shown = {clip(str(k), 80): show(v) for k, v in itertools.islice(updates.items(), 20)}
                data = {"reason": clip(e.message, 300), "update": shown}
                step.emit(Kind.REJECTED, {**data, "hint": clip(e.hint, 300)} if e.hint else data)
                rejected: ContextError | None = e
                followups: list[Job] = []
            else:
                rejected = None
                core.stats.updates += 1
                followups = self._advance(step)
                result = core.apply(stored, step)
                followups = self._gate.ready(followups, step.now, step)
        self._runner.dispatch(followups)  # an otherwise whose deadline this update noticed
        if rejected is not None:
            raise rejected
        return result

    def delivered(self, decision: int) -> None:
        """A decision made with ``dispatch=False`` was handed on (the Manager node published it):
        with a journal, it leaves the outbox with the next step; until then a restart hands it
        on again (:attr:`undelivered`). Safe from any thread."""
        self._gate.delivered(decision)

    def values(self) -> dict[str, Any]:
        """Every measure's value as users see it (scale literals by name), None when unknown; a copy."""
        with self.core.steps.lock:
            return self.core.context.external()

    def active_layers(self) -> list[str]:
        """The active clause layers in rule order (``["R1.1", ...]``); a rule at its default has none."""
        with self.core.steps.lock:
            return self.core.layers.active_layers()

    def rule_layers(self) -> dict[str, str | None]:
        """Every rule's layer now, in rule order: the active layer (``"R1.1"``), None at the
        rule's default, ``"?"`` when undetermined; a copy."""
        with self.core.steps.lock:
            return self.core.layers.by_rule()

    def set_semantics(self, semantics: HedgeSemantics | str) -> None:
        """Switch clause semantics at run time; every rule's layer is re-evaluated."""
        chosen = one_of(HedgeSemantics, semantics, "semantics")
        core = self.core
        with core.steps.step() as step:
            before = self.active_layers()
            core.layers.set_semantics(chosen, core.context.values)
            if core.steps.recording:
                active = self.active_layers()
                step.emit(Kind.SEMANTICS, {"semantics": str(chosen), "before": before, "active": active})

    # ------------------------------------------------------------------ events
    def event(self, name: str, values: Mapping[str, object] | None = None) -> list[Decision]:
        """An event occurred: it may fulfil or violate obligations, and it triggers rules.

        Returns the decisions of the rules it triggered (an undetermined decision too). An
        event no declaration names follows ``unknown_events``. ``values`` are measures
        observed with the event, applied as one update just before it with no other step
        between (all or nothing: rejected values, ContextError, and no event). Before
        :meth:`start`, the Manager starts itself first, with a warning (:meth:`_start_implicitly`).
        """
        if not self._started:
            self._start_implicitly("event")
        if values is None and self._planned is not None:  # the quiet case as planned (cosleec.runtime.plans)
            quiet = self._planned(name)
            if quiet is not None:
                return quiet
            return self._occur(name, planned=True)
        if values and isinstance(name, str) and name in self.core.ruleset.events:
            # (an unknown event, or a name that is no string, takes no value: all or nothing)
            with self.core.steps.lock:  # re-entrant: the two steps below take it too
                self.update(values)
                return self._occur(name)
        return self._occur(name)

    def _occur(self, name: str, *, planned: bool = False) -> list[Decision]:
        """Event ``name`` occurred (``planned``: its plan, if any, already declined it)."""
        core = self.core
        if not self._started:
            self._start_implicitly("event")
        if not planned and self._planned is not None:
            quiet = self._planned(name)
            if quiet is not None:
                return quiet
        timer = self._timer
        lane = self._express
        self._catch_up()
        with core.steps.step() as step:
            # the lane when records are read (for what the plan left), else the general path
            taken = lane.occur(name, step) if lane is not None and core.steps.recording else None
            if taken is None:
                taken = self._general(name, step)
                if taken is None:
                    return []
            decisions, followups = taken
            due = timer.due_at() if timer.thread is not None else None
        if due is not None:
            timer.notify(due)
        self._runner.dispatch(followups)
        return decisions

    def _general(self, name: str, step: Step) -> tuple[list[Decision], list[Job]] | None:
        """(In ``step``.) Event ``name`` occurred: its decisions and the jobs that may run now
        (None: an undeclared event, refused as ``unknown_events`` says)."""
        core = self.core
        if undeclared(core, name, "event", step, self.unknown_events) is not None:
            return None
        now = step.now
        core.stats.events += 1
        followups = self._advance(step)
        seq = core.steps.count("seq")  # after what time's passing started: this occurrence counts for it
        if core.steps.recording:
            step.emit(Kind.OCCURRENCE, {"event": name, "causal": seq}, now)
        followups += self._enforcer.occur(name, now, seq, step)
        decisions, jobs, more = self._enforcer.trigger(name, now, seq, step)
        return decisions, self._gate.ready(jobs + followups + more, now, step)

    def request(self, name: str, *, source: str = "") -> Permission:
        """The robot is about to do ``name``: may it, now? Call it for every real attempt.

        Returns the :class:`Permission` (true as a condition exactly when permitted, so
        ``if manager.request(e):`` acts only when allowed; ``.reason`` says why not, for a
        person). A refusal is counted (``stats["refused"]``) and recorded (a ``refused``
        record naming the prohibitions, the reason and ``source``, who asked); a permitted
        attempt records nothing. Not permitted while a prohibition forbids it now (its
        window, ends included); when the Manager can no longer keep its state or is closed
        (nothing is recorded); for an undeclared event under ``unknown_events="refuse"``
        (``rejected``). A question that is not an attempt (a screen, a status) is
        :meth:`permission`, which records nothing. Before :meth:`start`, the Manager
        starts itself first, with a warning.
        """
        if not isinstance(source, str):
            raise TypeError(f"source names who asks, as a string, not {type(source).__name__}")
        steps = self.core.steps
        if steps.broken is not None or steps.closed:
            return self._answers.stopped(name, steps.broken)
        try:
            if not self._started:
                self._start_implicitly("request")
            self._catch_up()
            with steps.step() as step:
                unknown = undeclared(self.core, name, "request", step, self.unknown_events)
                if unknown is not None:
                    return Permission(name, False, (), unknown)
                followups = self._gate.ready(self._advance(step), step.now, step)
                answer = self._answers.ask(name, source, step)
            self._runner.dispatch(followups)
        except JournalError:  # this step could not be kept (or one it waited behind): fail closed
            return self._answers.stopped(name, steps.broken)
        except ConfigurationError:
            if steps.closed:  # closed while it waited for the lock
                return self._answers.stopped(name, steps.broken)
            raise
        return answer

    def permission(self, name: str, **given: object) -> Permission:
        """Would ``name`` be permitted now, and if not, why not: a question, not an attempt.

        For what only looks (an operator's screen, a status, a planner weighing options):
        the answer :meth:`request` would give now, with the rules that forbid and a reason a
        person can read, but nothing is recorded or counted. Deadlines that fell due are
        judged first (that is time passing, recorded as always). An undeclared event raises
        ContextError under ``unknown_events="raise"``, else is not permitted. ``source=``
        is refused with a TypeError: naming who asks is for a real attempt, :meth:`request`.
        """
        if given:
            raise TypeError(
                f"permission() takes no {', '.join(map(repr, given))}: it is a question and records "
                "nothing; for a real attempt, call request(name, source=...), which records a refusal"
            )
        steps = self.core.steps
        if steps.broken is not None or steps.closed:
            return self._answers.stopped(name, steps.broken)
        if self._started and self.core.tracker.backlog(self.clock.now()):
            try:
                self.tick()  # what fell due by now is judged: an otherwise may forbid more
            except JournalError:
                return self._answers.stopped(name, steps.broken)
        with steps.lock:
            return self._answers.peek(name, self.clock.now(), self.unknown_events)

    # ------------------------------------------------------------------ time
    def tick(self) -> list[Decision]:
        """Process deadlines and stale values up to now (the timer thread calls this too), in
        batches that release the lock between them.

        Returns the ``otherwise`` decisions started since the last call: by this one, and by
        the moves of a virtual clock since (which tick this Manager themselves), so that
        ``clock.advance(61); started = m.tick()`` still sees what the move started (at most
        :data:`~cosleec.runtime.watch.UNCLAIMED` of them are kept for it, the latest).
        """
        started = self._judge()
        return self._watch.claim() + started

    def _judge(self) -> list[Decision]:
        """What :meth:`tick` does: the deadlines and stale values up to now, in batches; the
        ``otherwise`` decisions started."""
        followups: list[Job] = []
        more = True
        while more:
            with self.core.steps.step() as step:
                batch = self._advance(step, limit=1000)
                more = step.more
                followups += self._gate.ready(batch, step.now, step)
        self._runner.dispatch(followups)
        return [j.decision for j in followups if j.composition is None]

    def _advance(self, step: Step, limit: int | None = None) -> list[Job]:
        """(In ``step``.) Stale values, then every deadline due up to the step's time."""
        core = self.core
        if core.context.aging:
            core.expire(step.now, step)
        if not core.aware and not core.tracker.backlog(step.now):
            return []  # nothing is due: the common case
        return self._enforcer.advance(step.now, step, limit)

    def _catch_up(self) -> None:
        """Judge a backlog of due deadlines in batches (:meth:`tick`) before a step that would
        otherwise judge them all while holding the lock (after a long pause, a restart)."""
        if self.core.tracker.backlog(self.clock.now()) > 1000:
            self.tick()

    def outstanding(self, *, prohibitions: bool = False) -> list[Tracked]:
        """Pending obligations that require an event: what the robot still owes (with
        ``prohibitions=True``, the prohibitions in force too). Live records: read, do not change."""
        with self.core.steps.lock:
            return self.core.tracker.active if prohibitions else self.core.tracker.outstanding()

    # ------------------------------------------------------------------ reloading the rules
    @paused_gc()
    def reload(
        self,
        rules: RuleSet,
        *,
        priorities: Iterable[str | tuple[str, str]] | None = None,
        tasks: Iterable[Task] = (),
        capabilities: Mapping[str, Capability] | None = None,
    ) -> Reloaded:
        """Enforce ``rules`` from now on, in place of the rules in force, without a restart.

        What fell due before is judged first, by the rules it fell due under; then, in one
        step, the rules are swapped: obligations and prohibitions whose item the new rules
        still have are kept (with their window), the others withdrawn; values of measures
        still declared are kept; layers are recomputed; ``priorities`` (None keeps the
        caller's) and the new rules' own apply; ``tasks`` and ``capabilities`` bind more.
        One ``reloaded`` record says what changed. Refused with ReloadError -- nothing
        changes -- when the Manager could not enforce ``rules`` faithfully
        (:mod:`cosleec.runtime.reload` says each rule of it).
        """
        given = reloading.arguments(rules, priorities, self._given)
        binding, handlers = list(tasks), dict(capabilities or {})
        self.tick()  # what fell due before the reload is judged by the rules it fell due under
        core = self.core
        with core.steps.step() as step:
            prio, impl = reloading.check(core, rules, given, binding, handlers, checked=self._check)
            reloading.same_semantics(core, rules, self._semantics)
            followups = self._advance(step)  # (nothing, unless the clock moved since the tick)
            result, followups = reloading.swap(
                core, self._enforcer, self._gate, (rules, prio, impl), followups, step
            )
            self._given = given  # the next reload keeps these
        for t in binding:
            t.manager = self
        self.possible_conflicts = warn_conflicts(core.ruleset, core.priorities, self.possible_conflicts)
        if core.dispatch:
            impl.prepare()  # start-up work, not the first trigger's latency
        self._timer.notify()
        self._runner.dispatch(followups)
        return result

    def note(self, kind: str, data: Mapping[str, Any]) -> None:
        """Record what a front end refused, or was asked, before anything reached the rules.

        For the Manager node: ``rejected`` -- an input it could not use (counted in
        ``stats["rejected"]``); ``reload-attempt`` -- a request to reload rules, allowed or
        refused. One step of its own; nothing else changes. ConfigurationError for another ``kind``.
        """
        if kind not in ("rejected", "reload-attempt"):
            raise ConfigurationError(f"note records rejected or reload-attempt, not {show(kind)}")
        with self.core.steps.step() as step:
            if kind == "rejected":
                self.core.stats.rejected += 1
            step.emit(Kind(kind), dict(data))
