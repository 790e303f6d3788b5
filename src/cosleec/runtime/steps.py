"""Steps: the one lock every state change takes, its records, its commit, and delivery to observers.

Every state change of the runtime happens in one *step*::

    with steps.step() as s:       # the lock; the clock read once (s.now)
        s.emit(Kind.DECISION, {...})  # a record, numbered now
        s.change.obligations[7] = {...}  # what the journal keeps of the step
    # the records written to the audit log (flushed), then the journal committed, then the
    # lock released, then the records delivered to observers, in order

A step ends, still under the lock, by writing its records to the audit log and then
committing what it changed to the journal (one SQLite transaction) together with the log's
new length: a change is kept only with its records. A step that raises is committed too
(every change it made has its record). A failed write or commit *breaks* the steps: every
later step raises the failure (JournalError), so nothing is decided that cannot be kept.

Observers hear each record once, in the order the records were made, one at a time: on
the thread that made them once the step is complete, or (under concurrency) on another
caller's thread a moment later. An observer that raises is removed -- trio's habit: a
listener that fails once would fail again, and one kept silently hides its failure -- and
its removal is recorded (an ``observer-removed`` record, in a step of its own).

Used by the Manager (:mod:`cosleec.runtime.manager`) and by every collaborator that
records: they add records to the step they are given; only :class:`Steps` commits them.
"""

from __future__ import annotations

import logging
import threading
import weakref
from collections import deque
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

from cosleec.errors import CosleecError, clip
from cosleec.records import Kind, RuntimeEvent
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock
from cosleec.runtime.errors import ConfigurationError
from cosleec.runtime.journal import Change, Journal, JournalError

log = logging.getLogger("cosleec.runtime")

Observer = Callable[[RuntimeEvent], None]
P = ParamSpec("P")
R = TypeVar("R")


def weakly(method: Callable[P, R]) -> Callable[P, R]:
    """``method`` (a bound method) called through a weak reference to its object.

    For the hooks the steps call back (``meta``, ``rules``, ``before_commit``) and the
    timer's ``tick``: a strong one would make a reference cycle between the parts, and a
    Manager dropped without ``close()`` would then keep its rules, records and files until
    the cyclic collector ran -- late, and as a pause in someone's step. ReferenceError once
    the object is gone (nothing calls a hook of a part that no longer exists).
    """
    ref = weakref.WeakMethod(method)  # type: ignore[arg-type]
    name = getattr(method, "__qualname__", "a hook")  # (not the method itself: that would hold it)

    def call(*args: P.args, **kw: P.kwargs) -> R:
        fn = ref()
        if fn is None:
            raise ReferenceError(f"{name}: its object is gone")
        result: R = fn(*args, **kw)
        return result

    return call


class Step:
    """What one locked step changed: its records, in order, and the journal's share of it.

    ``now`` is the clock read once, under the lock, when the step began: every record of the
    step is stamped with it (a decision's own ``time`` aside), so the audit log's times never
    go back in ``seq`` order, however many threads take steps.
    """

    __slots__ = ("_change", "_counters", "events", "more", "now")

    def __init__(self, now: float = 0.0, counters: dict[str, int] | None = None) -> None:
        self.now = now
        self.events: list[RuntimeEvent] = []
        self._change: Change | None = None  # made on first use: most steps without a journal need none
        self._counters = {"record": 1} if counters is None else counters
        self.more = False  # a batched tick left deadlines for the next batch

    def emit(self, kind: Kind, data: dict[str, Any], at: float | None = None) -> None:
        """Add a record to the step; it is numbered now (every record of a step is committed).

        ``at`` is the time the step judged at, for the records a reader re-judges (occurrences,
        values): the clock may have moved since the step read it.
        """
        c = self._counters
        n = c["record"]
        c["record"] = n + 1
        self.events.append(RuntimeEvent.made(kind, self.now if at is None else at, data, n))

    def emit_later(self, kind: Kind, make: Callable[[], dict[str, Any]]) -> None:
        """Add a record whose data ``make`` makes when someone first reads it (numbered now,
        like :meth:`emit`): for the hot path's decisions, which nobody may read. ``make``
        may read only what no longer changes once the step ends (see
        :meth:`RuntimeEvent.deferred <cosleec.records.RuntimeEvent.deferred>`)."""
        c = self._counters
        n = c["record"]
        c["record"] = n + 1
        self.events.append(RuntimeEvent.deferred(kind, self.now, make, n))

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
    """``with steps.step() as step``: the lock, then the commit, then delivery to observers."""

    __slots__ = ("step", "steps")

    def __init__(self, steps: Steps) -> None:
        self.steps = steps

    def __enter__(self) -> Step:
        s = self.steps
        if s.broken is not None or s.closed:
            raise s.refusal()
        s.lock.acquire()
        if s.broken is not None or s.closed:  # the step it waited behind failed, or closed
            s.lock.release()
            raise s.refusal()
        self.step = Step(s.clock.now(), s.counters)  # read under the lock: steps' times follow their order
        return self.step

    def __exit__(self, *exc: object) -> None:
        s, step = self.steps, self.step
        try:
            # every change made, even by a step that raised, with its records (a step that
            # made neither, with nothing to add, has nothing to commit)
            if step.events or step._change is not None or s.before_commit is not None:
                s.commit(step)
        finally:
            s.lock.release()
            if s._delivery:
                s.deliver()


class Steps:
    """The lock, the counters, the commit of each step, and the observers that hear its records.

    ``meta`` gives what the journal keeps beside each commit (counters, rules, run); ``rules``
    the digest each audit record names; ``before_commit`` may add to a step as it commits
    (published decisions leaving the outbox). The counters (``decision``, ``seq``,
    ``record``) number decisions, occurrences and records; a journal's restore sets them.
    """

    def __init__(
        self,
        clock: Clock,
        *,
        run_id: str,
        audit: AuditLog | None = None,
        journal: Journal | None = None,
        meta: Callable[[], dict[str, Any]] = dict,
        rules: Callable[[], str] = str,
        before_commit: Callable[[Step], None] | None = None,
    ) -> None:
        self.clock = clock
        self.run_id = run_id
        self.audit = audit
        self.journal = journal
        self.meta = meta
        self.rules = rules
        self.before_commit = before_commit
        self.lineage = (
            run_id  # which history this continues: its journal's (kept across restarts), else this run's
        )
        self.lock = threading.RLock()
        # the next decision id, causal sequence number (occurrences and obligations) and record number
        self.counters = {"decision": 1, "seq": 1, "record": 1}
        if audit is not None:  # sequence numbers go on from where the log ends
            self.counters["record"] = audit.last_seq + 1
        self.broken: JournalError | None = None
        self.closed = False
        self.observers: list[Observer] = []
        self._delivery: deque[RuntimeEvent] = deque()
        self._delivering = threading.Lock()

    def keep(self, audit: AuditLog | None) -> None:
        """Write records to ``audit`` from now on; their numbers go on from where it ends."""
        self.audit = audit
        if audit is not None:
            self.counters["record"] = audit.last_seq + 1

    def step(self) -> _Scope:
        """One locked step: what it changes is committed with its records when it ends, even
        when it ends by an exception (every change made so far has its record); observers
        hear the records after the lock is released, in order."""
        return _Scope(self)

    def count(self, name: str) -> int:
        """The next number of counter ``name`` (decision, seq, record), used up."""
        n = self.counters[name]
        self.counters[name] = n + 1
        return n

    @property
    def last_record(self) -> int:
        """The ``seq`` of the last record made (0: none yet)."""
        return self.counters["record"] - 1

    @property
    def recording(self) -> bool:
        """Does anyone read records (observers, audit log, journal)? If not, no payload is built."""
        return bool(self.observers) or self.audit is not None or self.journal is not None

    def refusal(self) -> CosleecError:
        """Why no more steps are taken (a failed journal or audit log, or closed)."""
        if self.broken is not None:
            return JournalError(self.broken.message, where=self.broken.where, hint=self.broken.hint)
        return ConfigurationError("this Manager is closed", hint="make a new Manager (with its journal)")

    def subscribe(self, fn: Observer) -> Callable[[], None]:
        """Deliver every record from now on to ``fn``; returns the function that unsubscribes
        (harmless once ``fn`` is gone)."""
        self.observers.append(fn)

        def unsubscribe() -> None:
            if fn in self.observers:
                self.observers.remove(fn)

        return unsubscribe

    # ------------------------------------------------------------------ commit
    def commit(self, step: Step) -> None:
        """(Under the lock.) Write the step's records to the audit log, then commit its change
        with the log's new length to the journal; on failure, break (JournalError)."""
        if self.before_commit is not None:
            self.before_commit(step)
        if not step.events and not step.changed():
            return
        end = self._write(step.events) if self.audit is not None else None
        if self.journal is not None:
            self._keep(step, end)
        if self.observers:
            self._delivery.extend(step.events)

    def _write(self, events: list[RuntimeEvent]) -> int | None:
        assert self.audit is not None
        try:
            return self.audit.write_events(events, run=self.run_id, rules=self.rules())
        except (OSError, ValueError) as e:  # a full disk, a closed log: the state can no longer be kept
            self.broken = JournalError(
                f"cannot write the audit log: {getattr(e, 'strerror', None) or e}",
                where=str(self.audit.path),
                hint="free space or give a writable path, then restart: the journal has the state",
            )
            log.error("audit log failed, the Manager stops deciding: %s", e)
            raise self.broken from None

    def _keep(self, step: Step, end: int | None) -> None:
        assert self.journal is not None
        meta = self.meta()
        if end is not None:
            meta["audit"] = end  # the records just written belong to this commit
        try:
            self.journal.commit(step.change, meta, self.clock.now())
        except JournalError as e:
            self.broken = e
            log.error("journal failed, the Manager stops deciding: %s", e)
            raise
        except BaseException as e:  # interrupted mid-commit: whether it landed is unknown
            self.broken = JournalError(
                f"a journal commit was interrupted ({type(e).__name__})",
                where=str(self.journal.path),
                hint="restart the Manager: the journal has the last committed state",
            )
            raise

    # ------------------------------------------------------------------ delivery
    def deliver(self) -> None:
        """Hand queued records to observers in order; whoever holds the delivery lock delivers for all."""
        failed: list[tuple[Observer, Exception]] = []
        while self._delivery:
            if not self._delivering.acquire(blocking=False):
                return  # another thread is delivering: it delivers ours too, in order
            try:
                while self._delivery:
                    ev = self._delivery.popleft()
                    for fn in list(self.observers):
                        try:
                            fn(ev)
                        except Exception as e:  # an observer must never break the runtime
                            log.exception("observer %r failed: it is removed", fn)
                            if fn in self.observers:
                                self.observers.remove(fn)
                                failed.append((fn, e))
            finally:
                self._delivering.release()
        if failed:
            self._removed(failed)

    def _removed(self, failed: list[tuple[Observer, Exception]]) -> None:
        """Record the observers removed for raising (a step of its own; nothing if none can be taken)."""
        if self.broken is not None or self.closed:
            return
        try:
            with self.step() as step:
                for fn, e in failed:
                    step.emit(
                        Kind.OBSERVER_REMOVED,
                        {
                            "observer": clip(getattr(fn, "__qualname__", None) or repr(fn), 120),
                            "reason": clip(f"{type(e).__name__}: {e}", 300),
                        },
                    )
        except CosleecError:  # closed or broken meanwhile: the log above says it
            pass
