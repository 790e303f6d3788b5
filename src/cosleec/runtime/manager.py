"""The Manager: rules, context, layers, decisions and obligations, in one process.

It plays the paper's *Manager* role (owns the rules and the context) and hosts the COP
*Layer Manager* (:mod:`cosleec.runtime.layers`); a *Context Listener* feeds it from the
robot's topics (``cosleec.nodes``).

Every state change happens in one *step* under one lock, so a trigger is always decided
against a context that no update has half-changed. A step ends, still under the lock, by
writing its records to the audit log (flushed) and then committing what it changed to the
journal (one SQLite transaction) together with the log's new length: a change is kept only
with its records, and records past the committed length (a kill in between) are set aside
on the next start -- no change without its record, no record without its change, and
records in the order the changes were made. Observers then hear the records in that same
order. Implementations run outside the lock, so a slow or failing task never blocks it;
what they did is recorded by a step of its own (``task-done``/``task-failed``).

What happens when the runtime does not know (each a documented policy, fail closed):

- *an unknown measure*: conditions are three-valued (Kleene). A clause choice that stays
  unknown makes the decision **undetermined**: nothing runs, and the prohibitions of every
  clause that could apply are enforced (so not knowing never allows what one reading of
  the rules forbids). The same policy applies to the trigger condition, to the ``unless``
  of a braced inner response and to ``otherwise`` responses.
- *a deadline that depends on an unknown measure*: an obligation's deadline is read as now
  (the strictest), a prohibition's as :data:`~cosleec.runtime.model.MAX_WINDOW_S` (in
  force, in effect, until the Manager is restarted without it).
- *an event no declaration names*: :meth:`Manager.event` and :meth:`Manager.request` raise
  ContextError (``unknown_events="raise"``, the default) or refuse it and record why
  (``"refuse"``: ``event`` does nothing, ``request`` answers False).
- *a failed journal*: the Manager stops deciding (JournalError), and ``request`` refuses
  (:meth:`Manager.permission` says why, as it does for every refusal).

When rules demand E and forbid it at once (a *conflict*), the Manager records a
``conflict`` and resolves it by the declared priorities, or else lets the prohibition win
(:mod:`cosleec.runtime.priorities`). Each action of a decision is dispatched on its own: one
that is forbidden for now is held until it is allowed while the others run. Whether an
action may start is checked again where its implementation is started, under the lock
``request`` takes: a prohibition that took force since the decision stops it (a
``refused`` record; it is held again), so ``request(E)`` and what the Manager dispatches
never disagree, whatever other threads or observers do in between.

The rules themselves can change while the Manager runs (:meth:`Manager.reload`): the swap
is one step, so every trigger is decided wholly by the old rules or wholly by the new;
what the new rules still have stays in force, what they do not is withdrawn, each with its
record, and the journal keeps the result as any other step.
"""

from __future__ import annotations

import bisect
import dataclasses
import datetime
import difflib
import functools
import itertools
import json
import logging
import math
import sys
import threading
import time
import uuid
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any, TypeVar

from cosleec.bulk import paused_gc
from cosleec.cop import Snapshot
from cosleec.errors import CosleecError, clip, show
from cosleec.lang import (
    CANCEL,
    CONFLICT_AWARE,
    HedgeSemantics,
    Printer,
    Specification,
    Unknowns,
    candidates,
    choose,
)
from cosleec.lang import ast as A
from cosleec.lang import pairs as priority_pairs
from cosleec.records import RuntimeEvent
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock, MonotonicClock, VirtualClock
from cosleec.runtime.context import Context
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError, ConfigurationError, ContextError, ReloadError
from cosleec.runtime.implementations import Capability, Implementations, Ran
from cosleec.runtime.journal import Change, Journal, JournalError, Saved, lost, verify
from cosleec.runtime.layers import LayerManager, LayerSwitch, evaluate
from cosleec.runtime.model import MAX_WINDOW_S, CompiledRule, ItemSpec, Obligation, ResponseSpec
from cosleec.runtime.obligations import CANCELLED, PENDING, REFUSED, Outcome, Tracked, Tracker
from cosleec.runtime.priorities import (
    PossibleConflict,
    Priorities,
    covers,
    forced,
    possible_conflicts,
)
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.tasks import Task
from cosleec.runtime.views import View, ViewFactory, load_view

E = TypeVar("E", bound=StrEnum)
log = logging.getLogger("cosleec.runtime")


class UnknownEvents(StrEnum):
    """What :meth:`Manager.event` and :meth:`Manager.request` do with an event no declaration names."""

    RAISE = "raise"  # ContextError naming the event and the closest declared names
    REFUSE = "refuse"  # record it as rejected; request answers False, event does nothing


def _option(kind: type[E], value: object, name: str) -> E:
    """``value`` as a member of the option enum ``kind``, or ConfigurationError listing the choices."""
    if isinstance(value, str):
        try:
            return kind(value)
        except ValueError:
            pass
    choices = ", ".join(repr(str(k)) for k in kind)
    raise ConfigurationError(f"{name} must be one of {choices}, not {show(value)}")


@dataclass(frozen=True)
class Permission:
    """The answer of :meth:`Manager.permission`: may ``event`` happen now, and if not, why not.

    ``rules`` names the rules whose prohibitions forbid it now (empty when it is permitted,
    and when it is refused for another reason: an undeclared event, a Manager that has
    stopped); ``reason`` says it in one sentence a person can read (an operator's screen,
    an ``ExplainWhy``). True as a condition exactly when permitted, so that
    ``if manager.permission(e):`` means what it says.
    """

    event: str
    permitted: bool
    rules: tuple[str, ...]
    reason: str

    def __bool__(self) -> bool:
        return self.permitted


@dataclass(frozen=True)
class Reloaded:
    """What :meth:`Manager.reload` changed (its ``reloaded`` record says the same).

    The hashes are :attr:`RuleSet.digest` (sha256 of the canonical text) before and after;
    ``added``/``removed``/``changed`` are rule names (changed: in both, with a different
    canonical text); ``withdrawn`` the ids of the obligations and prohibitions that ended
    because what they came from is gone.
    """

    previous_hash: str
    current_hash: str
    added: tuple[str, ...]
    removed: tuple[str, ...]
    changed: tuple[str, ...]
    withdrawn: tuple[int, ...]


class _Step:
    """What one locked step changed: its records, in order, and the journal's share of it.

    ``now`` is the clock read once, under the lock, when the step began: every record of the
    step is stamped with it (a decision's own ``time`` aside), so the audit log's times never
    go back in ``seq`` order, however many threads take steps.
    """

    __slots__ = ("_change", "events", "more", "now")

    def __init__(self, now: float = 0.0) -> None:
        self.now = now
        self.events: list[RuntimeEvent] = []
        self._change: Change | None = None  # made on first use: most steps without a journal need none
        self.more = False  # a batched tick left deadlines for the next batch

    @property
    def change(self) -> Change:
        """What the journal must keep of this step."""
        if self._change is None:
            self._change = Change()
        return self._change

    def changed(self) -> bool:
        """Did the step change anything the journal keeps?"""
        return self._change is not None and bool(self._change)


class _Scope:
    """``with manager._step() as step``: the lock, then the commit, then delivery to observers."""

    __slots__ = ("manager", "step")

    def __init__(self, manager: Manager) -> None:
        self.manager = manager

    def __enter__(self) -> _Step:
        m = self.manager
        if m._broken is not None or m._closed:
            raise m._refusal()
        m._lock.acquire()
        if m._broken is not None or m._closed:  # the step it waited behind failed, or closed
            m._lock.release()
            raise m._refusal()
        self.step = _Step(m.clock.now())  # read under the lock: steps' times follow their order
        return self.step

    def __exit__(self, *exc: object) -> None:
        m = self.manager
        try:
            m._commit(self.step)  # every change made, even by a step that raised, with its records
        finally:
            m._lock.release()
            m._deliver()


@dataclass(eq=False, slots=True)
class _Job:
    """A decision to hand to its implementation once the step is over (or once allowed).

    ``composition`` is the rule's COP composition at the trigger (None: an ``otherwise``
    fallback); ``items`` what the decision put in force; ``record`` its decision record,
    annotated within the step when the dispatch differs from the decision;
    ``implementations`` those bound when it was decided (a reload since binds the new
    rules' own: a decision runs as it was decided, under the rule it was decided by).

    Each action (an obligation of ``items`` that requires an event) runs on its own: when
    some are forbidden for now, the others run and these wait. ``sent`` holds the ids of
    the actions already handed to the implementation; a *part* -- the job a dispatch runs
    -- shares it with the decision's job, and its ``items`` are the actions it runs (and
    the decision's prohibitions).
    """

    rule: CompiledRule
    decision: Decision
    composition: Snapshot | None
    items: list[Tracked]
    record: dict[str, Any] | None = None
    implementations: Implementations | None = None
    sent: set[int] = field(default_factory=set)


@dataclass
class _Issued:
    """The obligations of a response, or -- undetermined -- the prohibitions it might impose."""

    obligations: tuple[Obligation, ...]
    missing: tuple[str, ...] = ()
    determined: bool = True


class Manager:
    """Runs a rule set in one process: the embedded CO-SLEEC runtime.

    Use it to enforce SLEEC rules inside a Python program (the ROS Manager node wraps
    one). Build it from a :class:`RuleSet` or with :meth:`from_file` / :meth:`from_text`;
    bind tasks (:meth:`bind`) or capabilities (:meth:`capability`), :meth:`start` it, then
    feed it measures (:meth:`update`) and events (:meth:`event`), and ask before acting
    (:meth:`request`; :meth:`permission` also says why not). :meth:`reload` puts new rules
    in force while it runs.

    Options: ``semantics`` (``"last-wins"`` or ``"nested"``, :class:`HedgeSemantics`);
    ``clock`` -- a :class:`Clock` (monotonic by default; a VirtualClock for tests);
    ``unknown`` -- how a clause condition over a measure with no value is read
    (``"undetermined"``, the fail-closed default, see the module docstring;
    ``"false"``/``"true"``); ``unknown_events`` -- ``"raise"`` or ``"refuse"``;
    ``untimed`` -- the deadline of an untimed response (``"none"``, ``"immediate"`` or
    seconds); ``priorities`` -- ``"H > L"`` strings or ``(H, L)`` pairs, added to the rule
    file's ``priority`` block; ``priority_semantics`` -- ``"cancel"`` (the default) or
    ``"conflict-aware"``; ``priority_lead`` -- seconds before the forcing deadline a
    conflict-aware priority cancels the lower rule (0, as SLEEC-TK; give a real robot time
    to act); ``max_age`` -- seconds after which a measure's value is stale; ``audit`` --
    a JSON Lines audit log (one writer: a second Manager on it is refused); ``journal`` --
    a SQLite file the state survives a crash in (:mod:`cosleec.runtime.journal`), refused
    (JournalError) when it holds less than was committed; ``reset_journal=True`` -- start
    afresh from such a journal on purpose, once, recording what is lost as a
    ``journal-reset`` audit record (refused when the journal is sound); ``history`` -- how many decisions :attr:`decisions`
    keeps; ``max_depth`` -- how deeply implementations may trigger rules whose
    implementations trigger rules (a capability that triggers its own rule is stopped
    there, with a ``task-failed`` record); ``dispatch=False`` decides without running
    implementations (the ROS Manager node, ``cosleec decide``); ``web`` -- serve the live
    web view while the Manager runs (from :meth:`start` to :meth:`close`): a port (0 picks a
    free one; :attr:`web_url` says where it is) or options such as ``{"port": 8765,
    "host": "127.0.0.1", "allow_remote": False, "controls": False}``; read-only and for
    this machine only by default (``docs/runtime.md``, "The live web view"). It needs
    the ``web`` extra (``pip install 'cosleec[web]'``): without it the constructor raises
    ConfigurationError.
    """

    @paused_gc()
    def __init__(
        self,
        rules: RuleSet,
        *,
        semantics: HedgeSemantics | str = HedgeSemantics.LAST_WINS,
        clock: Clock | None = None,
        unknown: Unknowns | str = Unknowns.UNDETERMINED,
        unknown_events: UnknownEvents | str = UnknownEvents.RAISE,
        untimed: str | float = "none",
        audit: str | Path | AuditLog | None = None,
        journal: str | Path | Journal | None = None,
        reset_journal: bool = False,
        max_age: Mapping[str, float] | None = None,
        history: int = 10_000,
        max_depth: int = 16,
        dispatch: bool = True,
        priorities: Iterable[str | tuple[str, str]] | None = (),
        priority_semantics: str = CANCEL,
        priority_lead: float = 0.0,
        web: int | Mapping[str, Any] | None = None,
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
        self._max_age = dict(max_age or {})  # kept whole: a reload applies it to the measures declared then
        self.layer_manager = LayerManager(
            rules, _option(HedgeSemantics, semantics, "semantics"), _option(Unknowns, unknown, "unknown")
        )
        self.unknown_events = _option(UnknownEvents, unknown_events, "unknown_events")
        self.tracker = Tracker(_untimed(untimed))
        self.implementations = Implementations(rules)
        self.dispatch_locally = dispatch
        if isinstance(history, bool) or not isinstance(history, int) or history < 1:
            raise ConfigurationError(f"history must be a whole number of at least 1, not {show(history)}")
        deepest = _deepest()
        if isinstance(max_depth, bool) or not isinstance(max_depth, int) or not 1 <= max_depth <= deepest:
            raise ConfigurationError(
                f"max_depth must be a whole number from 1 to {deepest}, not {show(max_depth)}",
                hint=f"each level of implementations that trigger rules takes about {_FRAMES_PER_LEVEL} of "
                f"Python's {sys.getrecursionlimit()} stack frames (sys.getrecursionlimit()); 16 is the default",
            )
        self.max_depth = max_depth
        given = _given(priorities)
        self.priorities = Priorities.build(
            (r.name for r in rules.rules),
            [*priority_pairs(rules.spec), *given],
            priority_semantics,
            priority_lead,
        )
        self._given = given  # the caller's priorities (not the file's): a reload keeps them
        self.tracker.by_instance = bool(self.priorities.above)  # priorities act on activations
        self.tracker.keep_started = self.priorities.semantics == CONFLICT_AWARE and bool(
            self.priorities.above
        )
        self._held: dict[int, _Job] = {}  # decisions whose action is forbidden for now, by id
        # with a journal: the actions of a decision dispatched in parts that were handed to their
        # implementation and whose outcome is not recorded yet, by decision id (its outbox entry
        # names them: a restart records them task-interrupted, see _keep_held)
        self._running: dict[int, set[int]] = {}
        self._cut: tuple[int, tuple[float, Tracked, str] | None] | None = None  # (tracker version, forced())
        # held decisions as last examined: (tracker version, when the next interval opens)
        self._held_seen: tuple[int, float] = (-1, 0.0)
        # item pairs that oblige and forbid one event with no priority between them (start() warns)
        self.possible_conflicts: list[PossibleConflict] = []
        self.decisions: deque[Decision] = deque(maxlen=history)
        self.stats = {
            "updates": 0,
            "rejected": 0,
            "events": 0,
            "decisions": 0,
            "refused": 0,
            "violations": 0,
            "undetermined": 0,
            "task_failures": 0,
            "conflicts": 0,
            "cancelled": 0,
        }
        self.run_id = uuid.uuid4().hex[:12]
        # which history this Manager continues: its journal's (kept across restarts), else this run's
        self.lineage = self.run_id
        self._lock = threading.RLock()
        # the next decision id, causal sequence number (occurrences and obligations) and record number
        self._next = {"decision": 1, "seq": 1, "record": 1}
        self._observers: list[Callable[[RuntimeEvent], None]] = []
        self._delivery: deque[RuntimeEvent] = deque()
        self._delivering = threading.Lock()
        self._depth = threading.local()
        self._wake = threading.Condition()
        self._timer: threading.Thread | None = None
        # the timer's sleep (under _wake): the clock time it wakes by (inf while awake, or when
        # nothing is due), and whether a step asked it to look again before sleeping
        self._timer_due = math.inf
        self._poke = False
        self._stop = threading.Event()
        self._broken: JournalError | None = None
        self._closed = False
        self._check = False  # start() checked the bindings: a reload checks the new rules' too
        # the obligations of each fixed response (ResponseSpec.fixed), made on first use:
        # id(spec) -> (spec, obligations); the spec is kept, so its id is not reused meanwhile
        self._fixed: dict[int, tuple[ResponseSpec, tuple[Obligation, ...]]] = {}
        self._allowed: dict[str, Permission] = {}  # permission's answer for an event nothing forbids
        # decisions a journal held that were decided but perhaps never published (dispatch=False):
        # the Manager node publishes them again after a restart (task nodes run each id once)
        self.undelivered: list[dict[str, Any]] = []
        self._delivered: deque[int] = deque()  # published since the last commit: leave the outbox
        if not isinstance(reset_journal, bool) or (reset_journal and not journal):
            raise ConfigurationError(
                f"reset_journal must be True or False, and True only with a journal, not {show(reset_journal)}"
            )
        self._reset_journal = reset_journal
        # the live web view: found now (a missing extra is said at once, before any file is
        # opened or locked), served from start()
        self._web: tuple[ViewFactory, int | Mapping[str, Any]] | None = (
            None if web is None else (load_view("web"), web)
        )
        self.view: View | None = None
        self.audit = audit if isinstance(audit, AuditLog) else AuditLog(audit) if audit else None
        if self.audit is not None:  # sequence numbers go on from where the log ends
            self._next["record"] = self.audit.last_seq + 1
        self.journal: Journal | None = None
        try:
            self.journal = journal if isinstance(journal, Journal) else Journal(journal) if journal else None
            if self.journal is not None:
                self._open_journal(self.journal)
        except BaseException:  # refused: what this constructor opened is free again (the audit log's lock)
            if self.journal is not None and self.journal is not journal:
                self.journal.close()
            if self.audit is not None and self.audit is not audit:
                self.audit.close()
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
        registration for the same event replaces the first. BindingError, with the closest
        names, when no response of the rules names ``event``.
        """
        return self.implementations.capability(event)

    def subscribe(self, fn: Callable[[RuntimeEvent], None]) -> Callable[[], None]:
        """Call ``fn`` with every :class:`RuntimeEvent` from now on; returns the function that unsubscribes.

        Observers hear every record once, in the order the records were made, one at a time;
        usually on the thread that caused them, once the step is complete (under
        concurrency, possibly on another caller's thread, a moment later). One that raises
        is logged and ignored. Keep them quick: they delay the caller (the Manager node
        publishes on its topics from one). While anyone listens, the Manager builds event
        payloads it otherwise skips.
        """
        self._observers.append(fn)
        return lambda: self._observers.remove(fn)

    @paused_gc()
    def start(self, *, check: bool = True, timer: bool = False) -> Manager:
        """Check that every clause has an implementation; judge what happened while down; optionally
        run deadlines on a thread.

        Logs a warning when the rules can conflict (an item obliges an event another forbids,
        with no priority between their rules; :attr:`possible_conflicts` lists them).

        The check raises BindingError listing what is missing; it is skipped with
        ``check=False`` or when the Manager does not dispatch. With a journal, deadlines
        that passed while the Manager was down are judged now (their ``otherwise`` runs
        once). With ``timer=True`` a daemon thread judges deadlines and stale values as time
        passes; without it, call :meth:`tick` yourself (as tests with a VirtualClock do).
        With ``web``, the live web view starts serving here (after the check), and
        :attr:`web_url` says where; a start that fails after it (the audit log cannot be
        written, say) stops it again. Returns ``self``.
        """
        self._warn_conflicts()
        if check and self.dispatch_locally:
            self.implementations.check()
            self._check = True
        if self._web is not None and self.view is None and not self._closed:
            factory, options = self._web
            self.view = factory(self, options)  # it subscribes: it hears this start's records
        try:
            if self._recording:  # what the run's verdicts depend on: `cosleec conforms` reads it back
                with self._step() as step:
                    self._emit(
                        step,
                        "options",
                        {
                            "semantics": str(self.semantics),
                            "unknown": str(self.layer_manager.unknowns),
                            "untimed": self.tracker.untimed,
                            "priorities": sorted([h, lo] for h, lo in self.priorities.declared),
                            "priority_semantics": self.priorities.semantics,
                            "priority_lead": self.priorities.lead,
                        },
                    )
            if (
                self.priorities.semantics == CONFLICT_AWARE
                and self.priorities.above
                and not self.priorities.lead
                and not isinstance(self.clock, VirtualClock)
            ):
                log.warning(
                    "conflict-aware priorities with priority_lead=0 on a real clock: the lower rule is cancelled "
                    "at the higher rule's deadline, too late for the robot to act in time; give priority_lead "
                    "(seconds the robot needs)"
                )
            if self.dispatch_locally:
                self.implementations.prepare()  # start-up work, not the first trigger's latency
            self.tick()
            if timer and self._timer is None:
                self._timer = threading.Thread(target=self._run_timer, name="cosleec-deadlines", daemon=True)
                self._timer.start()
        except BaseException:
            view, self.view = self.view, None  # a start that failed serves nothing
            if view is not None:
                view.close()
            raise
        return self

    def _warn_conflicts(self, known: Iterable[PossibleConflict] = ()) -> None:
        """Find the pairs of items that can conflict (:attr:`possible_conflicts`); warn when there
        are any, other than those ``known`` (warned of before a reload)."""
        self.possible_conflicts = possible_conflicts(self.ruleset, self.priorities)
        if set(self.possible_conflicts) - set(known):
            shown = "; ".join(c.describe() for c in self.possible_conflicts[:5])
            more = len(self.possible_conflicts) - 5
            log.warning(
                "the rules can conflict (%s%s): the prohibition will win unless a priority is declared "
                "(a priority_start block, or Manager(priorities=[...]))",
                shown,
                f"; and {more} more" if more > 0 else "",
            )

    @property
    def web_url(self) -> str | None:
        """Where the live web view serves (``http://127.0.0.1:PORT/``), once started; None
        without ``web``, before :meth:`start` and after :meth:`close`. The view itself is
        :attr:`view` (a :class:`~cosleec.runtime.View`)."""
        return None if self.view is None else self.view.url

    def close(self) -> None:
        """Stop the web view (its port is free again), then the timer thread (waiting up to
        5 s), then close the journal and the audit log.

        Call it once, when done: a Manager used after closing fails on its next record.
        """
        view, self.view = self.view, None
        if view is not None:
            view.close()
        self._stop.set()
        with self._wake:
            self._wake.notify_all()
        if self._timer is not None:
            self._timer.join(5)
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                if self.journal is not None and self._delivered and self._broken is None:
                    self._commit(_Step())  # what was published leaves the outbox (JournalError if not)
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
        rejected: ContextError | None = None
        followups: list[_Job] = []
        self._catch_up()
        with self._step() as step:
            try:
                stored = self.context.validate(updates)
            except ContextError as e:
                self.stats["rejected"] += 1
                shown = {clip(str(k), 80): show(v) for k, v in itertools.islice(updates.items(), 20)}
                self._emit(step, "rejected", {"reason": clip(str(e), 300), "update": shown})
                rejected = e
            else:
                now = step.now
                self.stats["updates"] += 1
                followups = self._advance(now, step)
                changed = self.context.apply(stored, now)
                if self.journal is not None:
                    step.change.context.update(
                        (n, (x, now)) for n, x in self.context.external(stored).items()
                    )
                switches = self.layer_manager.update(changed, self.context.values) if changed else []
                if changed and self._recording:
                    self._emit(
                        step,
                        "context",
                        {"values": self.context.external(sorted(changed)), "version": self.context.version},
                        now,
                    )
                result = self._switched(switches, step)
                followups = self._ready(followups, now, step)
        self._dispatch(followups)  # an otherwise whose deadline this update noticed
        if rejected is not None:
            raise rejected
        return result

    def delivered(self, decision: int) -> None:
        """A decision made with ``dispatch=False`` has been handed on (the Manager node published
        it to the task nodes): with a journal, it leaves the outbox with the next step.

        Until then a restart hands it on again (:attr:`undelivered`); task nodes run each
        decision id once, so it runs once. Safe from any thread (observers call it).
        """
        if self.journal is not None:
            self._delivered.append(decision)

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

    def rule_layers(self) -> dict[str, str | None]:
        """Every rule's layer now, in rule order, as a :class:`LayerSwitch` names it: the active
        layer (``"R1.1"``), None at the rule's default, ``"?"`` when undetermined (a measure
        its clauses read has no value). A copy, safe to take from any thread: a view's table of
        rules, where :meth:`active_layers` cannot tell a default from an undetermined rule."""
        with self._lock:
            return self.layer_manager.by_rule()

    def set_semantics(self, semantics: HedgeSemantics | str) -> None:
        """Switch clause semantics at run time; every rule's layer is re-evaluated."""
        chosen = _option(HedgeSemantics, semantics, "semantics")
        with self._step() as step:
            before = self.active_layers()
            self.layer_manager.set_semantics(chosen, self.context.values)
            if self._recording:
                self._emit(
                    step,
                    "semantics",
                    {"semantics": str(chosen), "before": before, "active": self.active_layers()},
                )

    # ------------------------------------------------------------------ events
    def event(self, name: str, values: Mapping[str, object] | None = None) -> list[Decision]:
        """An event occurred: it may fulfil or violate obligations, and it triggers rules.

        Returns the decisions of the rules it triggered (whose trigger condition held, or
        might hold: an undetermined decision is returned too). An event no declaration
        names follows ``unknown_events``.

        ``values`` are measures observed with the event (one sensor message that gives a
        measure and fires a trigger): they are applied as one update just before it, with no
        other step between, so the rules decide on them and not on what came before. If
        they are rejected (ContextError), the event does not happen either; an event no
        declaration names takes none of them. Observers hear
        the update while the event still holds the Manager: one that waits for another
        thread's step waits until the event has happened.
        """
        if values and name in self.ruleset.events:  # (an unknown event takes no value: all or nothing)
            with self._lock:  # re-entrant: the two steps below take it too
                self.update(values)
                return self._occur(name)
        return self._occur(name)

    def _occur(self, name: str) -> list[Decision]:
        followups: list[_Job] = []
        decisions: list[Decision] = []
        self._catch_up()
        with self._step() as step:
            if self._unknown(name, "event", step) is not None:
                return []
            now = step.now
            self.stats["events"] += 1
            followups += self._advance(now, step)
            seq = self._count("seq")  # after what time's passing started: this occurrence counts for it
            if self._recording:
                self._emit(step, "event", {"event": name, "causal": seq}, now)
            out = self.tracker.occur(name, now, seq)
            followups += self._settle(out, now, seq, step)
            jobs: list[_Job] = []
            for rule in self.ruleset.by_trigger.get(name, ()):
                d = self._decide(rule, name, now)
                if d is None:
                    continue
                # the rule's composition as the Layer Manager has it at this trigger: the
                # dispatch runs under it, whatever the context does in the meantime
                composition = self.layer_manager.composition_of(rule) if d.clause is not None else None
                decisions.append(d)
                rec = self._record(d, step, queue=composition is not None)
                job = _Job(rule, d, composition, [], rec, self.implementations)
                followups += self._begin(job, d.obligations, now, seq, 0, d.id, step)
                if composition is not None:
                    jobs.append(job)
            followups = self._ready(jobs + followups, now, step)
            due = self._due_for_timer()
        self._notify_timer(due)
        self._dispatch(followups)
        return decisions

    def request(self, name: str) -> bool:
        """May ``name`` happen now? False (and the attempt recorded) while a prohibition holds.

        Also False when the Manager cannot keep its state (a failed journal), and for an
        event no declaration names under ``unknown_events="refuse"``. :meth:`permission`
        answers the same, and says why.
        """
        return self.permission(name).permitted

    def permission(self, name: str, *, source: str = "") -> Permission:
        """May ``name`` happen now, and if not, why not: ask before acting, and tell a person.

        The answer of :meth:`request`, with the same effects: a refusal is counted
        (``stats["refused"]``) and recorded (a ``refused`` record naming the prohibitions, the
        reason and ``source``, who asked: a task, a guarded topic), and each forbidding
        prohibition counts it. Not permitted, with the reason:

        - while a prohibition forbids it now (its window, ends included): ``rules`` names
          the rules whose prohibitions do, and the reason each one's window end and the
          decision that imposed it;
        - when the Manager can no longer keep its state (its journal or audit log failed,
          now or before) or is closed: nothing is recorded, there is nowhere to;
        - for an event no declaration names, under ``unknown_events="refuse"`` (recorded as
          ``rejected``); under ``"raise"`` it raises ContextError, as :meth:`event` does.
        """
        if not isinstance(source, str):
            raise TypeError(f"source names who asks, as a string, not {type(source).__name__}")
        if self._broken is not None or self._closed:
            return self._stopped(name)
        try:
            self._catch_up()
            with self._step() as step:
                unknown = self._unknown(name, "request", step)
                if unknown is not None:
                    return Permission(name, False, (), unknown)
                now = step.now
                followups = self._ready(self._advance(now, step), now, step)
                forbidding = self.tracker.forbidding(name, now)
                answer = self._allowed.get(name) if not forbidding else None
                if answer is None:
                    answer = self._forbidden_by(name, forbidding)
                for t in forbidding:
                    t.refused += 1
                    if self.journal is not None:  # the count is the prohibition's state: it is kept
                        step.change.obligations[t.id] = t.to_json()
                if forbidding:
                    self.stats["refused"] += 1
                    data: dict[str, Any] = {
                        "event": name,
                        "by": [t.rule for t in forbidding],
                        "obligations": [t.id for t in forbidding],
                        "reason": answer.reason,
                    }
                    if source:
                        data["source"] = clip(source, 200)
                    self._emit(step, "refused", data)
            self._dispatch(followups)
        except JournalError:  # this step could not be kept (or one it waited behind): fail closed
            return self._stopped(name)
        except ConfigurationError:
            if self._closed:  # closed while it waited for the lock
                return self._stopped(name)
            raise
        return answer

    def _stopped(self, name: str) -> Permission:
        """The answer of a Manager that takes no more steps: nothing is permitted."""
        what = clip(name, 80) if isinstance(name, str) else show(name)
        if self._broken is not None:
            why = f"the Manager can no longer keep its state ({self._broken}), so it permits nothing"
        else:
            why = "the Manager is closed"
        return Permission(name, False, (), f"{what} is not permitted: {why}")

    def _forbidden_by(self, name: str, forbidding: list[Tracked]) -> Permission:
        """The answer for ``name`` given the prohibitions that forbid it now (none: permitted)."""
        if not forbidding:  # the same answer every time: made once per event (declared events only)
            allowed = self._allowed.get(name)
            if allowed is None:
                allowed = Permission(
                    name, True, (), f"{name} is permitted: no prohibition in force forbids it now"
                )
                self._allowed[name] = allowed
            return allowed
        what = clip(name, 80)
        # one phrase per rule, however many of its activations forbid it: the one that ends
        # last says until when (a reason that grew with every trigger would fill the audit log)
        last: dict[str, Tracked] = {}
        for t in forbidding:
            held = last.get(t.rule)
            if held is None or (held.hi is not None and (t.hi is None or t.hi > held.hi)):
                last[t.rule] = t
        parts = []
        for t in last.values():
            until = "with no end" if t.hi is None else f"until {t.hi:g} s"
            why = self._why(t) or f"{t.rule}: {t.obligation.describe()} from {t.start:g} s"
            parts.append(f"by {t.rule} {until} ({clip(why, 300)})")
        rules = tuple(last)
        return Permission(name, False, rules, f"{what} is forbidden {' and '.join(parts)}")

    def _why(self, t: Tracked) -> str | None:
        """The explanation of the decision that put ``t`` in force, while :attr:`decisions` keeps it."""
        ds = self.decisions  # in the order of their ids: found by bisection
        i = bisect.bisect_left(ds, t.decision_id, key=lambda d: d.id)
        return ds[i].explanation if i < len(ds) and ds[i].id == t.decision_id else None

    def tick(self) -> list[Decision]:
        """Process deadlines and stale values up to now (the timer thread calls this too).

        Many deadlines due at once are judged in batches, releasing the lock between them,
        so triggers and requests are not held up. Returns the ``otherwise`` decisions started.
        """
        followups: list[_Job] = []
        more = True
        while more:
            with self._step() as step:
                now = step.now
                batch = self._advance(now, step, limit=1000)
                more = step.more
                batch = self._ready(batch, now, step)
            followups += batch
        self._dispatch(followups)
        return [j.decision for j in followups if j.composition is None]

    def _catch_up(self) -> None:
        """Judge a backlog of due deadlines in batches (:meth:`tick`) before a step that would
        otherwise judge them all while holding the lock (after a long pause, a restart)."""
        if self.tracker.backlog(self.clock.now()) > 1000:
            self.tick()

    def outstanding(self, *, prohibitions: bool = False) -> list[Tracked]:
        """Pending obligations that require an event (prohibitions left out): what the robot still owes.

        With ``prohibitions=True``, the prohibitions in force too (a view shows both). The
        records are live: read them, do not change them.
        """
        with self._lock:
            return self.tracker.active if prohibitions else self.tracker.outstanding()

    # ------------------------------------------------------------------ steps
    def _step(self) -> _Scope:
        """One locked step: what it changes is committed with its records when it ends, even
        when it ends by an exception (every change made so far has its record); observers
        hear the records after the lock is released, in order."""
        return _Scope(self)

    def _refusal(self) -> CosleecError:
        """Why this Manager takes no more steps (a failed journal or audit log, or closed)."""
        if self._broken is not None:
            return JournalError(str(self._broken), where=self._broken.where, hint=self._broken.hint)
        return ConfigurationError("this Manager is closed", hint="make a new Manager (with its journal)")

    def _count(self, name: str) -> int:
        """The next number of counter ``name`` (decision, seq, record), used up."""
        n = self._next[name]
        self._next[name] = n + 1
        return n

    def _commit(self, step: _Step) -> None:
        while self._delivered:  # published decisions leave the journal's outbox with this step
            done = self._delivered.popleft()
            if done in self._held or done in self._running:  # dispatched in parts: keep what still waits
                self._landed(done, list(self._running.get(done, ())), step)
            else:
                step.change.outbox[done] = None
        if not step.events and not step.changed():
            return
        lines: list[tuple[int, str]] = []
        if self.audit is not None:
            wall = datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds")
            mono = time.monotonic()
            head = (
                f',"wall":"{wall}","mono":{mono!r},"run":"{self.run_id}","rules":"{self.ruleset.digest[:16]}"'
            )
            for ev in step.events:
                data, t = ev.data, ev.time
                if "time" in data:  # a decision's own time (a fallback's is its deadline) is the record's:
                    t = data["time"]  # one "time" key, as a dict of the record has it, never two
                    data = {k: v for k, v in data.items() if k != "time"}
                body = json.dumps(data, default=str, separators=(",", ":"))
                lines.append(
                    (
                        ev.seq,
                        f'{{"seq":{ev.seq},"kind":"{ev.kind}","time":{_number(t)}{head}'
                        + (f",{body[1:]}" if len(body) > 2 else "}"),
                    )
                )
        try:
            end = self.audit.write_lines(text for _, text in lines) if self.audit is not None else None
        except (OSError, ValueError) as e:  # a full disk, a closed log: the state can no longer be kept
            self._broken = JournalError(
                f"cannot write the audit log: {getattr(e, 'strerror', None) or e}",
                where=str(self.audit.path) if self.audit is not None else "",
                hint="free space or give a writable path, then restart: the journal has the state",
            )
            log.error("audit log failed, the Manager stops deciding: %s", e)
            raise self._broken from None
        if self.journal is not None:
            meta = self._meta()
            if end is not None:
                meta["audit"] = end  # the records just written belong to this commit
            try:
                self.journal.commit(step.change, meta, self.clock.now())
            except JournalError as e:
                self._broken = e
                log.error("journal failed, the Manager stops deciding: %s", e)
                raise
            except BaseException as e:  # interrupted mid-commit: whether it landed is unknown
                self._broken = JournalError(
                    f"a journal commit was interrupted ({type(e).__name__})",
                    where=str(self.journal.path),
                    hint="restart the Manager: the journal has the last committed state",
                )
                raise
        if self._observers:
            self._delivery.extend(step.events)

    def _deliver(self) -> None:
        """Hand queued records to observers in order; whoever holds the delivery lock delivers for all."""
        while self._delivery:
            if not self._delivering.acquire(blocking=False):
                return  # another thread is delivering: it delivers ours too, in order
            try:
                while self._delivery:
                    ev = self._delivery.popleft()
                    for fn in list(self._observers):
                        try:
                            fn(ev)
                        except Exception:  # an observer must never break the runtime
                            log.exception("observer failed")
            finally:
                self._delivering.release()

    def _meta(self) -> dict[str, Any]:
        counters = {
            **self._next,
            "obligation": self.tracker.next_id,
            "version": self.context.version,
            "layers": self.layer_manager.version,  # the version of the next `layers` record goes on too
        }
        return {
            "rules": self.ruleset.digest,
            "run": self.run_id,
            "lineage": self.lineage,
            "clock_kind": type(self.clock).__name__,
            "boot": _boot(),  # a monotonic clock counts from boot: another boot, another origin
            "counters": counters,
        }

    # ------------------------------------------------------------------ internals (under the lock)
    def _unknown(self, name: str, what: str, step: _Step) -> str | None:
        """None when ``name`` is a declared event; else apply ``unknown_events`` (record, then
        raise, or return why it is refused)."""
        if isinstance(name, str) and name in self.ruleset.events:
            return None
        if not isinstance(name, str):
            self.stats["rejected"] += 1
            self._emit(
                step, "rejected", {"reason": f"an event is named by a string, not {type(name).__name__}"}
            )
            raise ContextError(f"an event is named by a string, not {type(name).__name__} {show(name)}")
        self.stats["rejected"] += 1
        close = difflib.get_close_matches(name, sorted(self.ruleset.events), n=3) if len(name) < 200 else []
        reason = f"unknown event {show(name)}"
        hint = f"did you mean {', '.join(close)}?" if close else "declare it in the rules' def block"
        self._emit(step, "rejected", {"reason": reason, "what": what, "hint": hint})
        if self.unknown_events == UnknownEvents.RAISE:
            raise ContextError(reason, hint=hint)
        return f"{clip(name, 80)} is not an event the rules declare ({hint})"

    def _advance(self, now: float, step: _Step, limit: int | None = None) -> list[_Job]:
        """Everything due up to ``now``, in time order: stale values, conflict-aware
        cancellations (at times <= now) and closing windows (deadlines < now), one deadline
        at a time so that each ``otherwise`` is in force before a later deadline is judged."""
        gone = self.context.expire(now)
        if gone:
            switches = self.layer_manager.update(gone, self.context.values)
            self._emit(step, "context", {"values": dict.fromkeys(sorted(gone)), "stale": sorted(gone)})
            for n in gone:
                step.change.context[n] = None
            self._switched(switches, step)
        followups: list[_Job] = []
        judged = 0
        aware = self.priorities.semantics == CONFLICT_AWARE and bool(self.priorities.above)
        while True:
            cut = self._forced() if aware else None
            if cut is not None and cut[0] <= now:
                nd = self.tracker.next_deadline()
                if nd is None or not nd < now or cut[0] <= nd:
                    at, victim, by = cut
                    if not self._cancel(victim.instance, at, by, step, "conflict-aware"):
                        log.error("conflict-aware cancellation of %s found nothing in force", victim.rule)
                        break  # a bug must not hang the Manager: judge the rest at the next step
                    continue
            out = self.tracker.due(now, None if limit is None else limit - judged)
            if not out.changed:
                break
            judged += len(out.changed)
            followups += self._settle(out, now, self._count("seq"), step)
            if limit is not None and judged >= limit:
                step.more = True
                break
        return followups

    def _switched(self, switches: list[LayerSwitch], step: _Step) -> list[LayerSwitch]:
        """Announce layer switches to observers; returns them."""
        if switches and self._recording:
            self._emit(step, "layers", self.layer_manager.state(switches).to_json())
        return switches

    def _track(self, t: Tracked, step: _Step) -> None:
        """Record an obligation's new state (and keep it in the journal while it is pending)."""
        if self._recording:
            rec = t.to_json()
            self._emit(step, "obligation", rec)
            if self.journal is not None:  # pending, or missed and waiting for its late event
                keep = t.status == PENDING or self.tracker.waits_late(t)
                step.change.obligations[t.id] = rec if keep else None
                for gone in self.tracker.forgotten:
                    step.change.obligations[gone] = None
        self.tracker.forgotten.clear()

    def _settle(self, out: Outcome, now: float, seq: int, step: _Step) -> list[_Job]:
        """Record what ``out`` changed and start the ``otherwise`` of each miss, in order."""
        followups: list[_Job] = []
        for t in out.changed:
            if t.status == "violated" and not t.late:
                self.stats["violations"] += 1
            self._track(t, step)
        for t, start in out.fallbacks:
            ob = t.obligation
            assert ob.otherwise is not None
            rule = self.ruleset.rule(t.rule)
            issued = self._issue(ob.otherwise, rule.name)
            what = " and ".join(o.describe() for o in issued.obligations) or "nothing is required"
            if not issued.determined:
                what = f"undetermined (no value for {', '.join(issued.missing)}); meanwhile {what}"
            why = f"{rule.name}: {ob.describe()} was violated at {start:g}; otherwise {what}"
            d = Decision.made(
                id=self._count("decision"),
                time=start,
                event="otherwise",
                rule=rule.name,
                clause=t.clause if issued.determined else None,
                layer=None,
                semantics=self.semantics,
                values={},
                conditions=(),
                obligations=issued.obligations,
                missing=issued.missing,
                reason=why,
                context_version=self.context.version,
                violated=t.id,
            )
            rec = self._record(d, step, queue=issued.determined)
            job = _Job(rule, d, None, [], rec, self.implementations)
            more = self._begin(job, issued.obligations, start, seq, t.depth + 1, t.instance, step)
            if issued.determined:
                followups.append(job)
            followups += more
        return followups

    def _begin(
        self,
        job: _Job,
        obligations: tuple[Obligation, ...],
        now: float,
        seq: int,
        depth: int,
        instance: int,
        step: _Step,
    ) -> list[_Job]:
        """Put a decision's obligations in force at ``now``, then settle what they meet, in the
        reference semantics' order: windows that close before they open, priorities (a new
        instance), conflicts. Returns the ``otherwise`` fallbacks this started."""
        d = job.decision
        started = [self.tracker.start(d.id, d.clause, ob, now, seq, depth, instance) for ob in obligations]
        job.items = started
        followups: list[_Job] = []
        for t in started:
            self._track(t, step)
        for t in started:
            if t.status == PENDING and self.tracker.closed_at_start(t):
                followups += self._settle(self.tracker.expire(t, now), now, seq, step)
        if (
            depth == 0
            and d.clause is not None
            and self.priorities.above
            and self.priorities.semantics == CANCEL
        ):
            self._prioritise(instance, d.rule, now, step)
        for t in started:
            if t.status != PENDING or not self.tracker.bans:
                continue
            if t.prohibition:  # a new prohibition against the obligations in force, oldest first
                for o in self.tracker.obliging(t.event):
                    if t.status == PENDING and o.status == PENDING:
                        followups += self._clash(o, t, now, seq, step)
            else:  # a new obligation against the prohibitions in force
                for p in self.tracker.banning(t.event):
                    if t.status == PENDING and p.status == PENDING:
                        followups += self._clash(t, p, now, seq, step)
        return followups

    def _prioritise(self, instance: int, rule: str, now: float, step: _Step) -> None:
        """Cancellation-based priority: a new instance against every active one."""
        if not self.tracker.of_instance(instance):
            return  # it imposes nothing: it is not active
        others = {i: r for r in self.priorities.related(rule) for i in self.tracker.instances_of(r)}
        for other in sorted(others.keys() - {instance}):
            higher = self.priorities.between(rule, others[other])
            if higher == rule:
                self._settled(instance, other, now, rule, step)
                self._cancel(other, now, rule, step, CANCEL)
            elif higher is not None:
                self._settled(instance, other, now, higher, step)
                self._cancel(instance, now, higher, step, CANCEL)
                return

    def _settled(self, a: int, b: int, now: float, winner: str, step: _Step) -> None:
        """Record the conflicts a cancellation settles: each obligation of one activation whose
        window a prohibition of the other forbids."""
        both = sorted([*self.tracker.of_instance(a), *self.tracker.of_instance(b)], key=lambda t: t.id)
        for o in both:
            for p in both:
                if (
                    not o.prohibition
                    and p.prohibition
                    and o.event == p.event
                    and o.instance != p.instance
                    and covers(o, p, now)
                ):
                    how = f"{winner} has priority (cancel): the other is cancelled"
                    self._conflict(o, p, now, CANCEL, winner, how, step)

    def _cancel(self, instance: int, at: float, by: str, step: _Step, how: str) -> bool:
        """Cancel everything activation ``instance`` has in force: priority ``by`` outranks it.

        Returns whether there was anything to cancel.
        """
        items = self.tracker.of_instance(instance)
        for t in items:
            self.tracker.finish(t, CANCELLED, at, by)
            self._track(t, step)
        if items:
            self.stats["cancelled"] += 1
            self._emit(
                step,
                "cancelled",
                {
                    "instance": instance,
                    "rule": items[0].rule,
                    "by": by,
                    "at": at,
                    "priority": how,
                    "obligations": [t.id for t in items],
                },
            )
        return bool(items)

    def _clash(self, o: Tracked, p: Tracked, now: float, seq: int, step: _Step) -> list[_Job]:
        """Obligation ``o`` meets prohibition ``p``: a conflict when ``p`` forbids all ``o`` has left."""
        if not covers(o, p, now):
            return []
        higher = self.priorities.between(o.rule, p.rule)
        if higher is not None and self.priorities.semantics == CONFLICT_AWARE:
            how = f"{higher} has priority ({CONFLICT_AWARE}): the other is kept as long as possible"
            self._conflict(o, p, now, CONFLICT_AWARE, higher, how, step)
            return []  # settled later, at the deadline that forces it (forced())
        how = "the prohibition forbids the whole window and wins: the obligation is refused"
        self._conflict(o, p, now, "prohibition-wins", p.rule, how, step)
        self.tracker.finish(o, REFUSED, now, p.rule)
        self.stats["violations"] += 1
        self._track(o, step)
        if o.obligation.otherwise is None:
            return []
        return self._settle(Outcome(fallbacks=[(o, now)]), now, seq, step)

    def _conflict(
        self, o: Tracked, p: Tracked, now: float, resolution: str, winner: str, how: str, step: _Step
    ) -> None:
        """Record that obligation ``o`` and prohibition ``p`` conflict, and how it is resolved."""
        self.stats["conflicts"] += 1
        until = "ever" if p.hi is None else f"{p.hi:g} s"
        self._emit(
            step,
            "conflict",
            {
                "event": o.event,
                "at": now,
                "obligation": o.id,
                "prohibition": p.id,
                "between": [o.rule, p.rule],  # the obligation's rule, the prohibition's
                "clauses": [o.clause, p.clause],
                "resolution": resolution,
                "winner": winner,
                "explanation": f"{o.rule} requires {o.obligation.describe()} and {p.rule} forbids {o.event} "
                f"until {until}: {how}",
            },
        )

    # ------------------------------------------------------------------ dispatch, held until allowed
    def _ready(self, jobs: list[_Job], now: float, step: _Step) -> list[_Job]:
        """Of ``jobs`` (and those held before), the parts that may run now; the rest is held.

        Each action of a decision is judged on its own (refused and cancelled ones are left
        out): one that names an event a prohibition forbids now, or whose interval has not
        opened (an earlier occurrence would not count), waits (a ``held`` record naming it;
        kept in the journal), so that nothing dispatched contradicts ``request``; the
        decision's other actions run now, as a part of it (a ``dispatch`` record). A waiting
        action runs once allowed (another ``dispatch`` record); one that ended while it
        waited never runs (``withheld``).
        """
        quiet = not self._held and not self.tracker.bans  # nothing is forbidden: the common case
        if quiet and all(
            t.status == PENDING and (t.prohibition or t.lo <= now) for job in jobs for t in job.items
        ):
            return jobs
        out: list[_Job] = []
        # a held decision can only become ready when something in force ends or an interval opens
        recheck = self.tracker.ended != self._held_seen[0] or now >= self._held_seen[1]
        opening = math.inf if recheck else self._held_seen[1]
        for job in [*(self._held.values() if recheck else ()), *jobs]:
            part, blocked = self._split(job, now, step)
            opening = min([opening, *(t.lo for t in blocked if t.lo > now)])
            if part is not None:
                out.append(part)
        self._held_seen = (self.tracker.ended, opening)
        return out

    def _split(self, job: _Job, now: float, step: _Step) -> tuple[_Job | None, list[Tracked]]:
        """The part of ``job`` that may run now (None: nothing), and the actions that must wait."""
        was_held = job.decision.id in self._held
        todo = [t for t in job.items if not t.prohibition and t.id not in job.sent]
        if not todo and (was_held or job.sent):  # every action was handed on: nothing waits
            self._held.pop(job.decision.id, None)
            return None, []
        live = [t for t in todo if t.status == PENDING]
        if todo and not live:  # refused, cancelled, closed at once, or met while it waited
            self._held.pop(job.decision.id, None)
            if job.record is not None and not was_held and not job.sent:
                job.record["dispatch"] = "withheld"  # a Manager node does not hand it on either
            self._emit(
                step,
                "withheld",
                {
                    "decision": job.decision.id,
                    "rule": job.decision.rule,
                    "reason": "nothing it required is still owed",
                },
            )
            if self.journal is not None:
                if job.decision.id in self._running:  # a part handed on before still runs
                    self._keep_held(job, step)
                else:
                    step.change.outbox[job.decision.id] = None
            return None, []
        blocked = [t for t in live if t.lo > now or self.tracker.forbidding(t.event, now)]
        ready = [t for t in live if t not in blocked]
        if blocked:
            if not was_held:
                self._hold(job, blocked, now, step, annotate=True)
            if not ready:
                return None, blocked
        else:
            self._held.pop(job.decision.id, None)
        ids = {t.id for t in ready}
        whole = not was_held and not blocked and not job.sent
        job.sent.update(ids)
        kept = [t for t in job.items if t.prohibition or t.id in ids]
        if whole and len(kept) == len(job.decision.obligations):
            return job, blocked  # as decided: the decision record says all
        part = dataclasses.replace(
            job,
            decision=dataclasses.replace(job.decision, obligations=tuple(t.obligation for t in kept)),
            items=kept,
        )
        if job.record is not None and whole:
            job.record["dispatch"] = "changed"
        if self.journal is not None and (blocked or was_held):
            self._handed_on(
                job.decision.id, ids
            )  # in flight until its outcome is recorded (or it is published)
            self._keep_held(job, step)  # what was handed on is not run (or published) again after a restart
        self._emit(step, "dispatch", {"decision": part.decision.to_json()})
        return part, blocked

    def _hold(self, job: _Job, blocked: list[Tracked], now: float, step: _Step, *, annotate: bool) -> None:
        """Hold ``job`` until its ``blocked`` actions are allowed, with a ``held`` record.

        ``annotate``: the decision's record is still being written (the step that made it):
        it says ``dispatch: held``, so a Manager node hands on each part by its ``dispatch`` record.
        """
        self._held[job.decision.id] = job
        if annotate and job.record is not None and "dispatch" not in job.record:
            job.record["dispatch"] = "held"
        opens = [t.lo for t in blocked if t.lo > now]
        self._emit(
            step,
            "held",
            {
                "decision": job.decision.id,
                "rule": job.decision.rule,
                "events": sorted({t.event for t in blocked}),
                "by": sorted({p.rule for t in blocked for p in self.tracker.forbidding(t.event, now)}),
                "opens": max(opens) if opens else None,
            },
        )
        if self.journal is not None:  # a restart holds it again (and runs it once allowed)
            self._keep_held(job, step)

    def _keep_held(self, job: _Job, step: _Step) -> None:
        """The journal's outbox entry of a decision dispatched in parts: whether actions of it
        are still held, those already handed on (``sent``: never run again) and those of them
        whose outcome is not recorded yet (``running``: a restart records the decision
        ``task-interrupted``)."""
        step.change.outbox[job.decision.id] = {
            "decision": job.decision.id,
            "rule": job.decision.rule,
            "event": job.decision.event,
            "held": job.decision.id in self._held,
            "running": sorted(self._running.get(job.decision.id, ())),
            "trigger": job.composition is not None,
            "record": job.decision.to_json(),
            "sent": sorted(job.sent),
        }

    def _handed_on(self, decision: int, actions: Iterable[int]) -> None:
        """(In a step.) ``actions`` of a decision dispatched in parts are handed to their
        implementation: in flight until :meth:`_landed`, named by its outbox entry meanwhile."""
        ids = set(actions)
        if ids and self.journal is not None:  # (a Manager node: handed on until it is published)
            self._running.setdefault(decision, set()).update(ids)

    def _landed(self, decision: int, actions: Iterable[int], step: _Step) -> None:
        """(In a step, with a journal.) ``actions`` of ``decision`` are no longer in flight
        (their outcome is recorded, they will not start, or -- a Manager node -- they were
        published): its outbox entry keeps what still waits or runs, and leaves when nothing does."""
        running = self._running.get(decision)
        if running is not None:
            running.difference_update(actions)
            if not running:
                del self._running[decision]
        held = self._held.get(decision)
        if held is not None:
            self._keep_held(held, step)
        elif decision not in self._running:
            step.change.outbox[decision] = None

    def _forced(self) -> tuple[float, Tracked, str] | None:
        """The next conflict-aware cancellation (:func:`forced`), kept while nothing in force ends
        (what starts meanwhile is weighed against the kept answer, not everything again)."""
        tr = self.tracker
        if self._cut is not None and self._cut[0] == tr.ended:
            if not tr.started:
                return self._cut[1]
            found = forced(tr, self.priorities, tr.started)
            kept = self._cut[1]
            if kept is None or (found is not None and (found[0], found[1].id) < (kept[0], kept[1].id)):
                kept = found
        else:
            kept = forced(tr, self.priorities)
        tr.started.clear()
        self._cut = (tr.ended, kept)
        return kept

    def _republish_part(self, rec: dict[str, Any], held: bool, step: _Step) -> None:
        """(Restore, a Manager node.) The part of a decision dispatched in parts that was
        handed on but not known to be published goes into :attr:`undelivered` again -- only
        its actions still owed, so held ones are not published before they are allowed (task
        nodes run each action of a decision once); it stays in the outbox until published.
        No ``dispatch`` record is made again: the one before the restart says it."""
        decision = int(rec["decision"])
        ids = {int(i) for i in rec.get("running", ()) if isinstance(i, int)}
        items = (
            self._held[decision].items
            if held
            else [t for t in self.tracker.active if t.decision_id == decision]
        )
        owed = [t for t in items if t.id in ids and t.status == PENDING and not t.prohibition]
        if owed:
            events = {t.event for t in owed}
            record = dict(rec["record"])
            record["obligations"] = [
                o for o in record.get("obligations", ()) if o.get("negated") or o.get("event") in events
            ]
            self.undelivered.append(record)
            self._running[decision] = {t.id for t in owed}
        if held:
            self._keep_held(self._held[decision], step)
        elif owed:
            step.change.outbox[decision] = {**rec, "running": sorted(self._running[decision])}
        else:
            step.change.outbox[decision] = None

    def _rehold(self, rec: dict[str, Any]) -> bool:
        """Hold again a decision the journal kept as held; False when it cannot be (its rule is gone)."""
        try:
            rule = self.ruleset.rule(str(rec["rule"]))
            d = Decision.from_json(rec["record"])
        except (KeyError, TypeError, ValueError):
            return False
        composition = (
            rule.compositions[d.clause]
            if rec.get("trigger") and d.clause is not None and 0 <= d.clause < len(rule.compositions)
            else None
        )
        items = [t for t in self.tracker.active if t.decision_id == d.id]
        sent = {int(i) for i in rec.get("sent", ()) if isinstance(i, int)}
        self._held[d.id] = _Job(rule, d, composition, items, None, self.implementations, sent)
        return True

    def _dispatch(self, jobs: list[_Job]) -> None:
        """Run each job's implementation (outside the lock), when this Manager dispatches.

        Each is admitted first (:meth:`_admit`), under the lock ``request`` takes: a
        prohibition that took force since the decision stops the actions it forbids.
        """
        if not self.dispatch_locally:
            return
        for given in jobs:
            admitted = self._admit(given)
            if admitted is None:
                continue
            job, checked = admitted
            impl = job.implementations if job.implementations is not None else self.implementations
            if job.composition is not None:
                call = functools.partial(impl.dispatch, job.rule, job.decision, job.composition)
            else:
                call = functools.partial(impl.dispatch_fallback, job.rule, job.decision)
            self._run(job.rule, job.decision, call, checked, [t.id for t in given.items if not t.prohibition])

    def _admit(self, job: _Job) -> tuple[_Job, int] | None:
        """``job`` as it may start now, with the ``seq`` of the last record before the check;
        None when nothing of it may.

        The check and what it reads happen under the lock ``request`` takes, so a dispatch
        and ``request`` never disagree: an action a prohibition forbids now is refused (a
        ``refused`` record, ``source`` the dispatch) and held again until allowed; one that
        ended since the decision (met, cancelled) is left out. A Manager that can no longer
        keep its state, or is closed, starts nothing.
        """
        with self._lock:
            if self._broken is not None or self._closed:
                return None
            if not self.tracker.bans and all(t.status == PENDING for t in job.items):
                return job, self._next["record"] - 1  # nothing can forbid it: the common case
            actions = [t for t in job.items if not t.prohibition]
            with self._step() as step:
                now = step.now
                gone = [t for t in actions if t.status != PENDING]
                stopped = [
                    t for t in actions if t.status == PENDING and self.tracker.forbidding(t.event, now)
                ]
                if stopped:
                    self._stop_at_start(job, stopped, now, step)
                if not gone and not stopped:
                    return job, self._next["record"] - 1
                left = {t.id for t in gone + stopped}
                kept = [t for t in job.items if t.id not in left]
                if gone and not stopped and all(t.id in left for t in actions):
                    self._emit(
                        step,
                        "withheld",
                        {
                            "decision": job.decision.id,
                            "rule": job.decision.rule,
                            "reason": "nothing it required is still owed",
                        },
                    )
                if actions and all(t.id in left for t in actions):
                    if self.journal is not None:
                        self._landed(job.decision.id, [t.id for t in actions], step)
                    return None  # every action it had waits, or is over
                part = dataclasses.replace(
                    job,
                    decision=dataclasses.replace(job.decision, obligations=tuple(t.obligation for t in kept)),
                    items=kept,
                )
                self._emit(step, "dispatch", {"decision": part.decision.to_json()})
            return part, self._next["record"] - 1

    def _stop_at_start(self, job: _Job, stopped: list[Tracked], now: float, step: _Step) -> None:
        """Refuse the ``stopped`` actions of ``job`` (a prohibition took force since it was
        decided) and hold them until allowed, as :meth:`_ready` holds an action."""
        for t in stopped:
            t.refused += 1
            job.sent.discard(t.id)
            if self.journal is not None:
                step.change.obligations[t.id] = t.to_json()
        for event in sorted({t.event for t in stopped}):
            forbidding = self.tracker.forbidding(event, now)
            self.stats["refused"] += 1
            self._emit(
                step,
                "refused",
                {
                    "event": event,
                    "by": [p.rule for p in forbidding],
                    "obligations": [p.id for p in forbidding],
                    "reason": self._forbidden_by(event, forbidding).reason,
                    "source": f"dispatch of decision {job.decision.id} ({job.decision.rule})",
                },
            )
        held = self._held.get(job.decision.id)
        if held is None:  # the part waits as the decision's job: the rest of it has been handed on
            job.sent.update(t.id for t in job.items if not t.prohibition and t not in stopped)
            self._handed_on(
                job.decision.id,
                (t.id for t in job.items if not t.prohibition and t not in stopped and t.status == PENDING),
            )
            self._hold(job, stopped, now, step, annotate=False)
        elif self.journal is not None:
            self._keep_held(held, step)
        self._held_seen = (-1, 0.0)  # look at the held decisions again at the next step

    def _decide(self, rule: CompiledRule, event: str, now: float) -> Decision | None:
        v = self.context.values
        missing: tuple[str, ...] = ()
        try:
            fired: bool | None = bool(rule.condition(v))
        except KeyError:
            x = rule.trigger_kleene(v)
            fired = None if x is None else bool(x)
            if fired is None and self.layer_manager.unknowns != Unknowns.UNDETERMINED:
                fired = self.layer_manager.unknowns == Unknowns.TRUE  # the policy reads it so
            if fired is None:
                missing = tuple(sorted(n for n in rule.trigger_reads if n not in v))
        if fired is False:
            return None
        status = self.layer_manager.status[rule.index]
        clause = status.clause if fired else None
        if fired and clause is None:
            missing = status.missing
        if clause is not None:
            issued = self._issue(rule.response_of(clause), rule.name)
            if not issued.determined:  # an inner response's own `unless` is unknown
                clause, missing = None, issued.missing
        else:
            issued = self._forbidden(rule, status.values)
        if clause is None:
            self.stats["undetermined"] += 1
        conds = ((0, rule.trigger_text, fired), *zip(rule.clause_ids, rule.clause_texts, status.values))
        names = rule.value_names
        values = dict(zip(names, map(v.get, names)))
        for n, lits in rule.scale_values:  # scale positions back to their literals
            x = values[n]
            if x is not None:
                values[n] = lits[x]
        # the explanation is computed from these parts when first read (Decision.explanation)
        return Decision.made(
            id=self._count("decision"),
            time=now,
            event=event,
            rule=rule.name,
            clause=clause,
            layer=rule.layer_of(clause) if clause else None,
            semantics=self.semantics,
            values=values,
            conditions=conds,
            obligations=issued.obligations,
            missing=missing,
            context_version=self.context.version,
            unknowns=self.layer_manager.unknowns,
        )

    def _forbidden(self, rule: CompiledRule, values: tuple[bool | None, ...]) -> _Issued:
        """An undetermined decision's obligations: the prohibitions of every clause that could apply."""
        clauses = candidates(values, self.semantics) if values else frozenset({0})
        out: list[Obligation] = []
        for k in sorted(clauses):
            spec = rule.response_of(k)
            if spec is not None:
                out += _prohibitions(self._issue(spec, rule.name).obligations)
        return _Issued(tuple(out), determined=False)

    def _issue(self, spec: ResponseSpec | None, rule: str) -> _Issued:
        """The concrete obligations of a response, starting now (deadlines on this snapshot).

        A braced inner response chooses among its own clauses here; when that choice is
        undetermined, the result is undetermined and holds the prohibitions of every inner
        clause that could apply.
        """
        if spec is None:
            return _Issued(())
        v = self.context.values
        if spec.clauses:  # a braced inner response: its own hedges, read when it starts
            vals, missing = evaluate(spec.clauses, v)
            k = choose(vals, self.semantics, self.layer_manager.unknowns)
            if k is None:
                out: list[Obligation] = []
                for j in sorted(candidates(vals, self.semantics)):
                    sub = self._issue(spec.clauses[j - 1].response, rule) if j else None
                    out += _prohibitions(sub.obligations if sub is not None else self._items(spec, rule))
                return _Issued(tuple(out), missing, determined=False)
            if k:
                return self._issue(spec.clauses[k - 1].response, rule)
        return _Issued(self._items(spec, rule))

    def _items(self, spec: ResponseSpec, rule: str) -> tuple[Obligation, ...]:
        if spec.fixed:  # the same obligations every time: made once (immutable values, shared)
            made = self._fixed.get(id(spec))
            if made is not None and made[0] is spec:
                return made[1]
            obligations = self._make_items(spec, rule)
            self._fixed[id(spec)] = (spec, obligations)
            return obligations
        return self._make_items(spec, rule)

    def _make_items(self, spec: ResponseSpec, rule: str) -> tuple[Obligation, ...]:
        v = self.context.values
        out = []
        for it in spec.items:
            try:
                hi = it.hi(v) if it.hi is not None else None
            except KeyError:  # unknown (or out of range): an obligation is due now, a prohibition holds on
                hi = MAX_WINDOW_S if it.negated else 0.0
            try:
                lo = it.lo(v) if it.lo is not None else None
            except KeyError:  # a prohibition from the earliest start; an obligation due now
                lo = 0.0
                if not it.negated:
                    hi = 0.0
            alts = self._branch(it.alternative) if it.alternative is not None and not it.negated else None
            out.append(
                Obligation(
                    event=it.event,
                    negated=it.negated,
                    within_s=hi,
                    from_s=lo or 0.0,
                    eventually=it.eventually,
                    alternatives=(alts,) if alts else (),
                    otherwise=it.otherwise,
                    rule=rule,
                    item=it.key,
                )
            )
        return tuple(out)

    def _branch(self, spec: ResponseSpec) -> tuple[tuple[str, float, float | None], ...] | None:
        """An ``else`` alternative as windows from now (its own clauses chosen now), or None when
        it can never fulfil: it holds a prohibition, or an unknown value decides it (fail closed)."""
        v = self.context.values
        if spec.clauses:
            vals, _ = evaluate(spec.clauses, v)
            k = choose(vals, self.semantics, self.layer_manager.unknowns)
            if k is None:
                return None
            if k:
                sub = spec.clauses[k - 1].response
                return None if sub is None else self._branch(sub)
        out = []
        for it in spec.items:
            if it.negated:
                return None  # reading a prohibition as fulfilment would let the forbidden event count
            try:
                lo = it.lo(v) if it.lo is not None else 0.0
                hi = it.hi(v) if it.hi is not None else None
            except KeyError:
                return None
            if hi is None and not it.eventually:
                u = self.tracker.untimed
                hi = None if u == "none" else self.tracker.tolerance if u == "immediate" else float(u)
            out.append((it.event, lo, hi))
        return tuple(out) or None

    def _record(self, d: Decision, step: _Step, *, queue: bool = False) -> dict[str, Any] | None:
        """Record a decision; ``queue`` puts its implementation in the journal's outbox until it ran.

        Returns the record (None when nobody records), which the step may still annotate.
        """
        self.decisions.append(d)
        self.stats["decisions"] += 1
        rec = None
        if self._recording:
            rec = d.to_json()
            self._emit(step, "decision", rec)
            if queue and self.journal is not None:
                entry: dict[str, Any] = {"decision": d.id, "rule": d.rule, "event": d.event}
                if not self.dispatch_locally:  # a Manager node publishes it: kept whole, to publish again
                    entry["record"] = rec
                step.change.outbox[d.id] = entry
        return rec

    def _emit(self, step: _Step, kind: str, data: dict[str, Any], at: float | None = None) -> None:
        """Add a record to the step; it is numbered now (every record of a step is committed).

        ``at`` is the time the step judged at, for the records a reader re-judges (occurrences,
        values): the clock may have moved since the step read it.
        """
        t = step.now if at is None else at
        step.events.append(RuntimeEvent.made(kind, t, data, self._count("record")))

    @property
    def _recording(self) -> bool:
        """Does anyone read runtime events (observers, audit log, journal)? If not, no payload is built."""
        return bool(self._observers) or self.audit is not None or self.journal is not None

    # ------------------------------------------------------------------ implementations (outside the lock)
    def _run(
        self,
        rule: CompiledRule,
        d: Decision,
        run: Callable[[], list[Ran]],
        checked: int = 0,
        actions: Iterable[int] = (),
    ) -> None:
        """Run a decision's implementation once, then record each outcome in a step of its own.

        ``checked`` is the ``seq`` of the last record before the dispatch was admitted: the
        outcome records carry it, so a reader can tell what was in force when it started.
        ``actions``: the ids of the actions it was handed (they are no longer in flight).
        """
        depth = getattr(self._depth, "n", 0)
        if depth >= self.max_depth:
            ran = [
                Ran(
                    "task",
                    None,
                    f"not run: implementations triggered rules {depth} deep (max_depth={self.max_depth}); "
                    f"does an implementation of {rule.name} trigger {rule.trigger} again?",
                )
            ]
            log.error("%s: %s", rule.name, ran[0].error)
        else:
            self._depth.n = depth + 1
            try:
                ran = run()
            finally:
                self._depth.n = depth
        failed = [r for r in ran if not r.ok]
        self.stats["task_failures"] += len(failed)
        if not self._recording:
            return
        with self._step() as step:
            for r in ran:
                kind = "task-done" if r.ok else "task-failed"
                self._emit(
                    step,
                    kind,
                    {
                        "rule": rule.name,
                        "decision": d.id,
                        "clause": d.clause,
                        **r.to_json(),
                        "checked": checked,
                    },
                )
            if self.journal is not None and self.dispatch_locally:
                self._landed(d.id, actions, step)  # (a decision with actions still held keeps its entry)

    def _due_for_timer(self) -> float | None:
        """(Under the lock, at the end of a step.) The earliest clock time the deadline timer
        must judge at because of what is in force now: the next deadline; -inf (wake it
        whatever it sleeps until) while decisions are held or conflict-aware priorities may
        cut; None when nothing is due and nothing waits."""
        if self._timer is None:
            return None
        if self._held or (self.priorities.semantics == CONFLICT_AWARE and self.priorities.above):
            return -math.inf
        return self.tracker.next_deadline()

    def _notify_timer(self, due: float | None = -math.inf) -> None:
        """Wake the deadline timer when something is due before the time it sleeps until.

        A step that left nothing due earlier than that does not wake it: on two cores, waking
        a thread for nothing costs a trigger as much as publishing its decision. Safe
        without the ``_wake`` lock: the timer commits to a wake-up time only after reading
        what is in force (under the Manager's lock), so a deadline added since is either seen
        by that reading, or earlier than the committed time and wakes it (``_run_timer``).
        """
        if self._timer is None or due is None or due >= self._timer_due:
            return
        with self._wake:
            self._poke = True
            self._wake.notify_all()

    def _run_timer(self) -> None:
        while not self._stop.is_set():
            with self._lock:
                nxt = self.tracker.next_deadline()
                exp = self.context.next_expiry()
                cut = self._forced()
                opening = self._held_seen[1] if self._held and self._held_seen[1] < math.inf else None
            times = [t for t in (nxt, exp, cut[0] if cut else None, opening) if t is not None]
            wait = None if not times else max(0.0, min(times) - self.clock.now() + 1e-3)
            with self._wake:
                # a step that changed what is due since the reading above has poked: read again
                if not self._poke and not self._stop.is_set():
                    self._timer_due = min(times) if times else math.inf
                    self._wake.wait(timeout=0.5 if wait is None else min(wait, 0.5))
                self._poke = False
                self._timer_due = math.inf  # awake: every step that adds a deadline pokes
            if not self._stop.is_set():
                try:
                    self.tick()
                except JournalError:
                    return  # logged where it happened; the Manager refuses from now on
                except Exception:  # a bug must not stop deadlines from being judged
                    log.exception("judging deadlines failed; the timer goes on")

    # ------------------------------------------------------------------ reloading the rules
    @property
    def rules_hash(self) -> str:
        """The digest of the rules in force (:attr:`RuleSet.digest`, sha256 of their canonical text).

        The same digest heads every audit record (``rules``) and the journal (whose restore
        reports ``rules_changed`` against it); :meth:`reload` changes it.
        """
        return self.ruleset.digest

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

        For a deployment that adds, removes or edits rules while the robot runs (as
        SLEEC@run.time does). What fell due before is judged first, by the rules it fell
        due under; then, in one step under the lock -- between two decisions, never within
        one -- the rules are swapped:

        - *Obligations and prohibitions* in force (held decisions and pending ``otherwise``
          chains included) are kept when their rule still exists: a rule of the same name
          whose response still has the item they came from (the same item key with the same
          event and sense, or else the one item of the rule with that event and sense) --
          exactly what a restart on the journal with the new rules keeps, so a crash right
          after a reload changes nothing. A kept one keeps its window (it was decided under
          the old text) and takes the new item's ``otherwise``. The others are *withdrawn*
          (an ``obligation`` record with status ``withdrawn`` each): they can no longer be
          violated and their ``otherwise`` never runs; a decision of a removed rule not yet
          run (held, or an ``otherwise`` due at the reload) is ``withheld``; a miss waiting
          for its late event is ``dropped``. A decision already handed to its implementation
          runs as it was decided.
        - *Context*: the values of measures still declared are kept (a scale value by its
          literal); those of measures no longer declared are ``dropped`` (recorded); new
          measures start unknown. ``max_age`` applies to the measures declared now (kept for
          the others: a later reload that declares them again ages them again).
        - *Layers* are recomputed for the new rules under the current context (a ``layers``
          record: a rule added switches from the base, one removed to it).
        - *Priorities*: the new rules' own and the caller's (``priorities``; None keeps those
          given to the Manager); activations in force that a new priority orders meet now
          (cancellation), as after a restore.
        - *Implementations*: tasks bound to rules still there stay bound (``tasks`` binds more
          or replaces them, ``capabilities`` adds handlers for new response events); a task of
          a removed rule is unbound. A decision runs with the implementations bound when it
          was made.

        One ``reloaded`` record says what changed: ``previous_hash`` and ``current_hash``
        (:attr:`rules_hash`), rule names ``added``, ``removed`` and ``changed`` (in both, with
        another canonical text), the obligation ids ``withdrawn`` and ``relinked`` (kept, with
        a new item key), the decisions ``withheld``, measures added and removed, the
        priorities. With a journal it is one commit: a restart with the new rules restores
        what was kept and nothing withdrawn; a restart with the old rules is a restart with
        changed rules (``restored`` says ``rules_changed``; what they lack is ``dropped``).

        Refused with :class:`ReloadError` -- nothing changes, nothing is recorded, the old rules
        stay in force -- when the Manager could not enforce ``rules`` faithfully: a measure
        that holds a value and changes its type (boolean, numeric, scale), or a scale that
        loses the literal its value is; a priority naming a rule the new rules lack (or a
        cycle); a bound task naming a clause its rule no longer has, or a task or capability
        for a rule or event the new rules lack; and, when :meth:`start` checked the bindings,
        a rule, clause or ``otherwise`` left without an implementation. A Manager that is
        closed or whose journal failed raises as for any step. Returns :class:`Reloaded`.
        """
        if not isinstance(rules, RuleSet):
            raise TypeError(
                f"reload needs a RuleSet, not {type(rules).__name__}: "
                "use RuleSet.from_file(path), RuleSet.from_text(text) or RuleSet.from_spec(spec)"
            )
        try:
            given = self._given if priorities is None else _given(priorities)
        except ConfigurationError as e:
            raise ReloadError(f"reload refused, the rules in force stay: {e}") from None
        binding = list(tasks)
        handlers = dict(capabilities or {})
        self.tick()  # what fell due before the reload is judged by the rules it fell due under
        followups: list[_Job] = []
        with self._step() as step:
            prio, impl = self._bindings(rules, given, binding, handlers)
            self._carried(rules)  # refused before anything changes
            now = step.now
            followups = self._advance(now, step)  # (nothing, unless the clock moved since the tick)
            result, followups = self._swap(rules, prio, impl, followups, now, step)
            self._given = given  # the next reload keeps these
        for t in binding:
            t.manager = self
        self._warn_conflicts(self.possible_conflicts)
        if self.dispatch_locally:
            impl.prepare()  # start-up work, not the first trigger's latency
        self._notify_timer()
        self._dispatch(followups)
        return result

    def note(self, kind: str, data: Mapping[str, Any]) -> None:
        """Record what a front end refused, or was asked, before anything reached the rules.

        For the Manager node, whose inputs are decoded before the runtime sees them:
        ``rejected`` -- an input it could not use (a message that cannot be decoded, a call
        to a service turned off), counted in ``stats["rejected"]`` as the runtime's own
        rejections are; ``reload-attempt`` -- a request to reload rules, allowed or refused,
        with who asked and both rule hashes. One step of its own (numbered, in the audit
        log, heard by observers); nothing else changes. Raises as any step does once the
        Manager is closed or its journal failed; ConfigurationError for another ``kind``.
        """
        if kind not in ("rejected", "reload-attempt"):
            raise ConfigurationError(f"note records rejected or reload-attempt, not {show(kind)}")
        with self._step() as step:
            if kind == "rejected":
                self.stats["rejected"] += 1
            self._emit(step, kind, dict(data))

    def _bindings(
        self,
        rules: RuleSet,
        given: list[str | tuple[str, str]],
        tasks: list[Task],
        capabilities: dict[str, Capability],
    ) -> tuple[Priorities, Implementations]:
        """The priorities and implementations ``rules`` would run with, or ReloadError (under the lock)."""
        refused = "reload refused, the rules in force stay"
        try:
            prio = Priorities.build(
                (r.name for r in rules.rules),
                [*priority_pairs(rules.spec), *given],
                self.priorities.semantics,
                self.priorities.lead,
            )
        except ConfigurationError as e:
            raise ReloadError(
                f"{refused}: {e}",
                hint="give the priorities for the new rules: reload(rules, priorities=[...])",
            ) from None
        impl = Implementations(rules)
        # every capability is kept, even for an event no rule obliges now: a later reload may again
        impl.capabilities.update(self.implementations.capabilities)
        replaced = {t.rule for t in tasks}
        try:
            for t in self.implementations.tasks.values():
                if t.rule in rules.by_name and t.rule not in replaced:
                    impl.bind(t)
            for t in tasks:
                impl.bind(t)
            for event, fn in capabilities.items():
                impl.capability(event)(fn)
            if self._check:  # start() checked the rules it began with: the new ones are held to it too
                impl.check()
        except BindingError as e:
            raise ReloadError(
                f"{refused}: {e}",
                hint="bind the new rules' implementations in the reload: reload(rules, tasks=[...], "
                "capabilities={event: handler})",
            ) from None
        return prio, impl

    def _carried(self, rules: RuleSet) -> dict[str, Any]:
        """The values (stored form) the context keeps under ``rules``, or ReloadError when a
        value held cannot be read as the new measure's type (under the lock, changes nothing)."""
        out: dict[str, Any] = {}
        problems: list[str] = []
        for name, v in self.context.values.items():
            new = rules.measures.get(name)
            if new is None:
                continue  # no longer declared: dropped
            old = self.context.measures[name]
            shown = show(old.external(v), 40)
            if new.kind != old.kind:
                problems.append(
                    f"measure {name} holds {shown} as a {old.kind}, and the new rules make it {new.kind}"
                )
            elif new.kind == "scale":
                literal = old.literals[int(v)]
                if literal in new.literals:
                    out[name] = new.literals.index(literal)
                else:
                    problems.append(
                        f"measure {name} holds {shown}, a literal its new scale "
                        f"({', '.join(new.literals)}) does not have"
                    )
            else:
                out[name] = v
        if problems:
            raise ReloadError(
                f"reload refused, the rules in force stay: {'; '.join(problems)}",
                hint="keep the measure's type (and the literal its value is), or give the measure "
                "a new name: its value then starts unknown",
            )
        return out

    def _swap(
        self,
        rules: RuleSet,
        prio: Priorities,
        impl: Implementations,
        followups: list[_Job],
        now: float,
        step: _Step,
    ) -> tuple[Reloaded, list[_Job]]:
        """Put ``rules`` in force at ``now`` (under the lock, as part of ``step``; checked before)."""
        old = self.ruleset
        withdrawn: list[Tracked] = []
        kept: list[tuple[Tracked, ItemSpec]] = []
        for t in sorted(self.tracker.active, key=lambda t: t.id):
            item = self._item_of(t, rules)
            if item is None:
                withdrawn.append(t)
            else:
                kept.append((t, item))
        forgotten = [t for t in self.tracker.misses() if self._item_of(t, rules) is None]
        relinked = [t.id for t, item in kept if t.obligation.item != item.key]
        gone = [job for job in [*self._held.values(), *followups] if job.rule.name not in rules.by_name]
        values = self._carried(rules)
        dropped = sorted(n for n in self.context.values if n not in values)
        before, after = _texts(old), _texts(rules)
        result = Reloaded(
            previous_hash=old.digest,
            current_hash=rules.digest,
            added=tuple(n for n in after if n not in before),
            removed=tuple(n for n in before if n not in after),
            changed=tuple(n for n in after if n in before and before[n] != after[n]),
            withdrawn=tuple(t.id for t in withdrawn),
        )
        self._emit(
            step,
            "reloaded",
            {
                "previous_hash": result.previous_hash,
                "current_hash": result.current_hash,
                "added": list(result.added),
                "removed": list(result.removed),
                "changed": list(result.changed),
                "withdrawn": list(result.withdrawn),
                "relinked": relinked,
                "withheld": [job.decision.id for job in gone],
                "measures_added": sorted(rules.measures.keys() - old.measures.keys()),
                "measures_removed": sorted(old.measures.keys() - rules.measures.keys()),
                "priorities": sorted([h, lo] for h, lo in prio.declared),
            },
            now,
        )
        # the rules, and what is computed from them
        context = Context(rules.measures, {n: a for n, a in self._max_age.items() if n in rules.measures})
        context.values.update(values)
        context.stamps.update((n, self.context.stamps[n]) for n in values)
        context.version = self.context.version
        layers = LayerManager(rules, self.layer_manager.semantics, self.layer_manager.unknowns)
        layers.recompute_all(context.values)
        layers.version = self.layer_manager.version
        switches = _switches(old, self.layer_manager, rules, layers)
        newly = prio.above - self.priorities.above
        self.ruleset, self.spec = rules, rules.spec
        self._fixed.clear()  # (the old rules' responses: what the memo keeps alive)
        self.context, self.layer_manager = context, layers
        self.implementations, self.priorities = impl, prio
        self.tracker.reindex(bool(prio.above), prio.semantics == CONFLICT_AWARE and bool(prio.above))
        self._cut = None  # what conflict-aware priorities force: found again, for the new priorities
        self._held_seen = (-1, 0.0)  # every held decision is examined again
        # what is gone, each with its record
        for t in withdrawn:
            self.tracker.withdraw(t, now)
            self._track(t, step)
        for t, item in kept:
            moved = t.obligation.item != item.key
            t.obligation = dataclasses.replace(t.obligation, otherwise=item.otherwise, item=item.key)
            if moved and self.journal is not None:
                step.change.obligations[t.id] = t.to_json()
        for t in forgotten:
            self.tracker.forget(t)
            self._emit(
                step,
                "dropped",
                {
                    "what": f"obligation {t.id} ({t.rule}: {t.obligation.describe()}): the rules no longer have it"
                },
            )
            if self.journal is not None:
                step.change.obligations[t.id] = None
        for job in gone:
            was_held = self._held.pop(job.decision.id, None) is not None
            if job.record is not None and not was_held:
                job.record["dispatch"] = "withheld"
            self._emit(
                step,
                "withheld",
                {
                    "decision": job.decision.id,
                    "rule": job.decision.rule,
                    "reason": f"its rule {job.decision.rule} was removed by a reload",
                },
            )
            if self.journal is not None:
                step.change.outbox[job.decision.id] = None
        followups = [job for job in followups if job.rule.name in rules.by_name]
        for name in dropped:
            self._emit(step, "dropped", {"what": f"measure {name}: the rules no longer declare it"})
            if self.journal is not None:
                step.change.context[name] = None
        self._switched(switches, step)
        if newly and prio.semantics == CANCEL:
            self._meet(self.tracker.active, now, step)
        return result, self._ready(followups, now, step)

    # ------------------------------------------------------------------ restoring from a journal
    def _open_journal(self, journal: Journal) -> None:
        """Restore what the journal holds, once it is known to be all that was committed
        (:func:`~cosleec.runtime.journal.verify`, against the audit log): a journal that lost
        commits is refused -- or, with ``reset_journal=True``, emptied, and what was lost
        recorded (``journal-reset``) before this Manager starts a lineage of its own."""
        try:
            saved = journal.load()
            doubt = verify(journal, saved, self.audit)
        except JournalError as e:  # damaged: nothing can be restored
            saved, doubt = None, e.reason or str(e)
        if doubt is None and self._reset_journal:
            raise ConfigurationError(
                "reset_journal=True, but the journal holds all that was committed: there is nothing to reset",
                hint="start without reset_journal (it is for a journal the Manager refused, once)",
            )
        if doubt is not None and not self._reset_journal:
            raise journal.refusal(doubt, self.audit)
        reset = None if doubt is None else lost(journal.reset(), self.audit, doubt)
        journal.start()
        if saved is None or reset is not None:
            with self._step() as step:
                if reset is not None:
                    self._emit(step, "journal-reset", reset)
                self._emit(step, "restored", {"from": None, "lineage": self.lineage, "rules_changed": False})
            return
        self.lineage = saved.lineage or saved.run
        with self._step() as step:
            self._restore(saved, step)

    def _item_of(self, t: Tracked, rules: RuleSet | None = None) -> ItemSpec | None:
        """The response item of ``rules`` (default: the rules in force) an obligation came from,
        when it was made under other rules (a journal's, rules before a reload): by its key,
        or -- when the rule was edited around it -- the one item of its rule with the same
        event and sense. None when there is none: the rules no longer have it."""
        rules = self.ruleset if rules is None else rules
        item = rules.items.get(t.obligation.item)
        if item is not None and item.event == t.event and item.negated == t.prohibition:
            return item
        rule = rules.by_name.get(t.rule)
        if rule is None:
            return None
        same = [
            it
            for resp in rule.responses()
            for it in resp.walk()
            if it.event == t.event and it.negated == t.prohibition
        ]
        return same[0] if len(same) == 1 else None

    def _restore(self, saved: Saved, step: _Step) -> None:
        """Take back what the journal kept (under the lock, as one step)."""
        c = saved.counters
        for name in ("decision", "seq", "record"):
            self._next[name] = max(self._next[name], c.get(name, 1))
        uncommitted: list[dict[str, Any]] = []
        if self.audit is not None and saved.audit is not None:
            self._next["record"] = c.get("record", 1)  # the journal's count: seq goes on without a gap
            if self.audit.size > saved.audit:  # written for a step whose commit never happened
                try:
                    uncommitted = self.audit.cut(saved.audit)
                except ValueError as e:  # not where the journal says: edited by hand, or another log
                    self._emit(step, "audit-mismatch", {"reason": f"{e}; nothing was set aside"})
            elif self.audit.size < saved.audit:
                self._emit(
                    step,
                    "audit-mismatch",
                    {
                        "reason": f"the audit log is {saved.audit - self.audit.size} bytes shorter than "
                        "the journal committed: it was changed outside cosleec"
                    },
                )
        kind = type(self.clock).__name__
        if saved.clock_kind and saved.clock_kind != kind:
            raise JournalError(
                f"the journal was written on a {saved.clock_kind} and this Manager runs on a {kind}: "
                "every saved window would be misread",
                where=str(self.journal.path) if self.journal is not None else "",
                hint="restart with the same kind of clock, or give a new journal",
            )
        now = self.clock.now()
        if isinstance(self.clock, VirtualClock) and now < saved.clock:
            self.clock.set(saved.clock)  # virtual (simulated) time goes on from where it stopped
            now = step.now = saved.clock
        # a monotonic clock that started again (a reboot): shift saved clock times. How long
        # the Manager was down is known only from the wall clock, which may be wrong: each
        # reading is the stricter one -- obligations as if all that time passed (deadlines
        # due sooner), prohibitions as if none did (still in force)
        down = max(0.0, time.time() - saved.wall)
        restarted = not isinstance(self.clock, VirtualClock) and (
            now < saved.clock or (bool(saved.boot) and saved.boot != _boot())
        )
        shift = now - down - saved.clock if restarted else 0.0
        hold = now - saved.clock if restarted else 0.0  # for prohibitions
        changed = saved.rules != self.ruleset.digest
        dropped: list[str] = []
        values: dict[str, Any] = {}
        for name, (value, stamp) in saved.context.items():
            if name not in self.context.measures:
                dropped.append(f"measure {name}: the rules no longer declare it")
                continue
            try:
                values[name] = self.context.validate({name: value})[name]
            except ContextError as e:
                dropped.append(f"measure {name}: {e}")
                continue
            self.context.stamps[name] = stamp + shift
        self.context.values.update(values)
        self.context.version = max(c.get("version", 0), 1 if values else 0)
        self.layer_manager.version = max(self.layer_manager.version, c.get("layers", 0))
        self.layer_manager.update(set(values), self.context.values)
        kept = 0
        restored: list[Tracked] = []
        for rec in saved.obligations:
            t = Tracked.from_json(rec)
            item = self._item_of(t)
            if item is None:
                dropped.append(
                    f"obligation {t.id} ({t.rule}: {t.obligation.describe()}): the rules no longer have it"
                )
                continue
            t.obligation = dataclasses.replace(t.obligation, otherwise=item.otherwise, item=item.key)
            d = hold if t.prohibition else shift
            t.start += d
            t.lo += d
            t.hi = None if t.hi is None else t.hi + d
            restored.append(t)
            if t.status == PENDING:
                self.tracker.resume(t, c.get("obligation", 1))
                kept += 1
            else:  # missed: its late event is still reported, once
                self.tracker.missed(t)
        # obligation ids go on even when nothing was pending (resume sees only what it restores)
        self.tracker.resume_ids(c.get("obligation", 1))
        for gone in self.tracker.forgotten:
            step.change.obligations[gone] = None
        self.tracker.forgotten.clear()
        for rec in saved.outbox:
            held = bool(rec.get("held")) and self._rehold(rec)
            if held and not rec.get("running"):
                continue  # still waiting to be allowed: it runs (once) when it is
            if not self.dispatch_locally and rec.get("running") and isinstance(rec.get("record"), dict):
                self._republish_part(rec, held, step)  # a part perhaps never published: published again
                continue
            if not held and not self.dispatch_locally and isinstance(rec.get("record"), dict):
                self.undelivered.append(rec["record"])  # the Manager node publishes it again
                continue
            # decided (a part of it handed on), but perhaps never run: recorded, not run again
            self._emit(
                step,
                "task-interrupted",
                {
                    **{k: rec[k] for k in ("decision", "rule", "event") if k in rec},
                    "reason": "the Manager stopped before it was known to have run",
                },
            )
            if held:  # the rest still waits to be allowed; what was handed on is not run again
                self._keep_held(self._held[int(rec["decision"])], step)
            else:
                step.change.outbox[int(rec["decision"])] = None
        if uncommitted:
            self._emit(
                step,
                "uncommitted",
                {
                    "records": len(uncommitted),
                    "first": uncommitted[0].get("seq"),
                    "last": uncommitted[-1].get("seq"),
                    "to": f"{self.audit.path.name}.uncommitted" if self.audit is not None else None,
                },
            )
        for what in dropped:
            self._emit(step, "dropped", {"what": what})
        self._emit(
            step,
            "restored",
            {
                "from": saved.run,
                "lineage": self.lineage,
                "rules_changed": changed,
                "context": sorted(values),
                "obligations": kept,
                "dropped": len(dropped),
                "interrupted": len(saved.outbox),
                "shift": shift,
            },
        )
        if self.journal is not None:  # what was dropped leaves the journal in this same step
            for name in saved.context:
                if name not in values:
                    step.change.context[name] = None
            kept_ids = {t.id for t in restored}
            for rec in saved.obligations:
                if int(rec["id"]) not in kept_ids:
                    step.change.obligations[int(rec["id"])] = None
        if self.priorities.above and self.priorities.semantics == CANCEL:
            # priorities declared since (or changed): activations restored together meet now
            self._meet(restored, self.clock.now(), step)

    def _meet(self, items: Iterable[Tracked], now: float, step: _Step) -> None:
        """Cancellation-based priorities between activations that were in force together before
        the priorities between them were (a journal restored, a reload): in the order they began."""
        for t in sorted(items, key=lambda t: t.instance):
            if t.status == PENDING and t.clause is not None and self.tracker.of_instance(t.instance):
                self._prioritise(t.instance, t.rule, now, step)


#: Python stack frames one level of "an implementation triggers a rule" takes (measured: about
#: 12 for a capability; a task's own calls add some), and the frames kept for the caller
_FRAMES_PER_LEVEL = 16
_FRAMES_KEPT = 200


def _deepest() -> int:
    """The largest ``max_depth`` the interpreter's recursion limit allows: deeper, a trigger
    loop would end in RecursionError instead of the Manager's own ``task-failed`` record."""
    return max(1, (sys.getrecursionlimit() - _FRAMES_KEPT) // _FRAMES_PER_LEVEL)


def _given(priorities: Iterable[str | tuple[str, str]] | None) -> list[str | tuple[str, str]]:
    """The ``priorities`` option as a list (checked against the rules by Priorities.build)."""
    given = () if priorities is None else [priorities] if isinstance(priorities, str) else priorities
    try:
        return list(given)
    except TypeError:
        raise ConfigurationError(
            f"priorities must be a list of 'H > L' strings or (H, L) pairs, not {show(priorities)}"
        ) from None


def _texts(rules: RuleSet) -> dict[str, str]:
    """Each rule's canonical text, by name, in rule order: what a reload compares to tell a changed rule."""
    dialect = rules.spec.dialect if rules.spec.dialect is not A.Dialect.PAPER else A.Dialect.TK
    printer = Printer(rules.spec, dialect)
    return {r.name: printer.rule(r.ast) for r in rules.rules}


def _switches(old: RuleSet, was: LayerManager, new: RuleSet, now: LayerManager) -> list[LayerSwitch]:
    """The layer switches of a reload, by rule name: a rule added switches from the base (None),
    one removed to it; rules in the new order, then the removed ones."""
    before = {r.name: _layer(r, st.clause) for r, st in zip(old.rules, was.status)}
    after = {r.name: _layer(r, st.clause) for r, st in zip(new.rules, now.status)}
    names = [*after, *(n for n in before if n not in after)]
    return [LayerSwitch(n, before.get(n), after.get(n)) for n in names if before.get(n) != after.get(n)]


def _layer(rule: CompiledRule, clause: int | None) -> str | None:
    """A rule's active layer as a ``layers`` record names it: None the base, ``"?"`` undetermined."""
    return "?" if clause is None else rule.layer_of(clause)


@functools.cache
def _boot() -> str:
    """This boot of the machine (Linux's boot id), or "" where it cannot be told."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return ""


def _number(x: float) -> str:
    """A clock time as JSON: non-finite values (never from a checked clock) as null."""
    return repr(x) if isinstance(x, int | float) and math.isfinite(x) else "null"


def _prohibitions(obligations: tuple[Obligation, ...]) -> list[Obligation]:
    """What an undetermined decision enforces of ``obligations``: their prohibitions, and the
    prohibitions their ``otherwise`` would start (nothing runs, so every obligation may be
    missed), shifted to start at that deadline."""
    out = [o for o in obligations if o.negated]
    for o in obligations:
        if not o.negated and o.otherwise is not None:
            at = o.within_s or 0.0
            out += _after(o.otherwise, at, at, o.rule)
    return out


def _after(spec: ResponseSpec, first: float, last: float, rule: str) -> list[Obligation]:
    """The prohibitions ``spec`` (an ``otherwise``) could impose when it starts between ``first``
    and ``last`` seconds from now, down its own ``otherwise`` chain and across its inner
    clauses, read fail-closed: a bound that depends on an unknown value makes the window as
    wide as it could be."""
    out: list[Obligation] = []
    for it in spec.items:
        known = _seconds(it.hi)
        if it.negated:
            lo = _seconds(it.lo) if it.lo is not None else 0.0
            hi = MAX_WINDOW_S if known is None and it.hi is not None else (known or 0.0)
            out.append(
                Obligation(
                    event=it.event,
                    negated=True,
                    from_s=first + (lo or 0.0),
                    within_s=min(MAX_WINDOW_S, last + hi),
                    rule=rule,
                    item=it.key,
                )
            )
        elif it.otherwise is not None:
            unknown = it.hi is not None and known is None
            out += _after(
                it.otherwise,
                first + (known or 0.0),
                MAX_WINDOW_S if unknown else min(MAX_WINDOW_S, last + (known or 0.0)),
                rule,
            )
    for c in spec.clauses:
        if c.response is not None:
            out += _after(c.response, first, last, rule)
    return out


def _seconds(fn: Callable[[dict[str, Any]], float] | None) -> float | None:
    """A window bound with no context to read (an ``otherwise`` not started yet): its constant
    value, or None when it depends on a measure (the caller reads that fail-closed)."""
    if fn is None:
        return None
    try:
        return fn({})
    except KeyError:
        return None


def _untimed(value: str | float) -> str | float:
    """The ``untimed`` option checked: ``"none"``, ``"immediate"`` or a finite number of seconds >= 0."""
    if value in ("none", "immediate"):
        return value
    if isinstance(value, int | float) and not isinstance(value, bool) and 0 <= value <= MAX_WINDOW_S:
        return float(value)
    raise ConfigurationError(
        f"untimed must be 'none', 'immediate' or a number of seconds from 0 to {MAX_WINDOW_S:g}, "
        f"not {show(value)}"
    )
