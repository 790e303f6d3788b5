"""The gate: what a decision requires runs only when ``request`` would allow it.

Each action of a decision (an obligation that requires an event) is judged on its own: one
that names an event a prohibition forbids now, or whose interval has not opened (an
earlier occurrence would not count), waits -- a ``held`` record naming it, kept in the
journal's outbox -- while the decision's other actions run now, as a *part* of it (a
``dispatch`` record). A waiting action runs once allowed (another ``dispatch`` record);
one that ended while it waited never runs (``withheld``).

The check is made again where an implementation is started (:meth:`Gate.admit`), under
the lock ``request`` takes: a prohibition that took force since the decision stops the
actions it forbids (a ``refused`` record; they are held again), so ``request(E)`` and what
the runtime dispatches never disagree, whatever other threads or observers do in between.

With a journal, the outbox names what was handed on and what still runs, so a restart
runs nothing twice (:mod:`cosleec.runtime.restore`); a Manager node that publishes
decisions instead of running them tells the gate what it published (:meth:`Gate.delivered`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Iterable
from typing import Any

from cosleec.records import Kind
from cosleec.runtime.core import Core
from cosleec.runtime.decision import Decision
from cosleec.runtime.jobs import Job
from cosleec.runtime.obligations import PENDING, Tracked
from cosleec.runtime.permission import Answers
from cosleec.runtime.steps import Step


class Gate:
    """Holds what may not run yet and releases it when allowed (see the module docstring)."""

    def __init__(self, core: Core, answers: Answers) -> None:
        self.core = core
        self.answers = answers
        self.held: dict[int, Job] = {}  # decisions whose action is forbidden for now, by id
        # with a journal: the actions of a decision dispatched in parts that were handed to their
        # implementation and whose outcome is not recorded yet, by decision id (its outbox entry
        # names them: a restart records them task-interrupted, see keep_held)
        self.running: dict[int, set[int]] = {}
        # held decisions as last examined: (tracker version, when the next interval opens)
        self.seen: tuple[int, float] = (-1, 0.0)
        # decisions a journal held that were decided but perhaps never published (dispatch=False):
        # the Manager node publishes them again after a restart (task nodes run each id once)
        self.undelivered: list[dict[str, Any]] = []
        self._delivered: deque[int] = deque()  # published since the last commit: leave the outbox

    def look_again(self) -> None:
        """Examine every held decision at the next step (what forbade it may have changed)."""
        self.seen = (-1, 0.0)

    @property
    def opening(self) -> float | None:
        """When the next interval of a held action opens (None: nothing held waits for one)."""
        return self.seen[1] if self.held and self.seen[1] < math.inf else None

    # ------------------------------------------------------------------ in the step that decides
    def ready(self, jobs: list[Job], now: float, step: Step) -> list[Job]:
        """Of ``jobs`` (and those held before), the parts that may run now; the rest is held."""
        tracker = self.core.tracker
        quiet = not self.held and not tracker.bans  # nothing is forbidden: the common case
        if quiet and all(
            t.status == PENDING and (t.prohibition or t.lo <= now) for job in jobs for t in job.items
        ):
            return jobs
        out: list[Job] = []
        # a held decision can only become ready when something in force ends or an interval opens
        recheck = tracker.ended != self.seen[0] or now >= self.seen[1]
        opening = math.inf if recheck else self.seen[1]
        for job in [*(self.held.values() if recheck else ()), *jobs]:
            part, blocked = self._split(job, now, step)
            opening = min([opening, *(t.lo for t in blocked if t.lo > now)])
            if part is not None:
                out.append(part)
        self.seen = (tracker.ended, opening)
        return out

    def _split(self, job: Job, now: float, step: Step) -> tuple[Job | None, list[Tracked]]:
        """The part of ``job`` that may run now (None: nothing), and the actions that must wait."""
        was_held = job.decision.id in self.held
        todo = [t for t in job.items if not t.prohibition and t.id not in job.sent]
        if not todo and (was_held or job.sent):  # every action was handed on: nothing waits
            self.held.pop(job.decision.id, None)
            return None, []
        live = [t for t in todo if t.status == PENDING]
        if todo and not live:  # refused, cancelled, closed at once, or met while it waited
            self._withhold(job, was_held, step)
            return None, []
        tracker = self.core.tracker
        blocked = [t for t in live if t.lo > now or tracker.forbidding(t.event, now)]
        ready = [t for t in live if t not in blocked]
        if blocked:
            if not was_held:
                self._hold(job, blocked, now, step, annotate=True)
            if not ready:
                return None, blocked
        else:
            self.held.pop(job.decision.id, None)
        return self._part(job, ready, blocked, was_held, step), blocked

    def _withhold(self, job: Job, was_held: bool, step: Step) -> None:
        """Nothing ``job`` required is still owed: it never runs (a ``withheld`` record)."""
        self.held.pop(job.decision.id, None)
        if job.record is not None and not was_held and not job.sent:
            job.record["dispatch"] = "withheld"  # a Manager node does not hand it on either
        step.emit(
            Kind.WITHHELD,
            {
                "decision": job.decision.id,
                "rule": job.decision.rule,
                "reason": "nothing it required is still owed",
            },
        )
        if self.core.journal:
            if job.decision.id in self.running:  # a part handed on before still runs
                self.keep_held(job, step)
            else:
                step.change.outbox[job.decision.id] = None

    def _part(
        self, job: Job, ready: list[Tracked], blocked: list[Tracked], was_held: bool, step: Step
    ) -> Job:
        """The part of ``job`` that runs its ``ready`` actions (``job`` itself when that is all of it)."""
        ids = {t.id for t in ready}
        whole = not was_held and not blocked and not job.sent
        job.sent.update(ids)
        kept = [t for t in job.items if t.prohibition or t.id in ids]
        if whole and len(kept) == len(job.decision.obligations):
            return job  # as decided: the decision record says all
        part = _narrowed(job, kept)
        if job.record is not None and whole:
            job.record["dispatch"] = "changed"
        if self.core.journal and (blocked or was_held):
            self.handed_on(
                job.decision.id, ids
            )  # in flight until its outcome is recorded (or it is published)
            self.keep_held(job, step)  # what was handed on is not run (or published) again after a restart
        step.emit(Kind.DISPATCH, {"decision": part.decision.to_json()})
        return part

    def _hold(self, job: Job, blocked: list[Tracked], now: float, step: Step, *, annotate: bool) -> None:
        """Hold ``job`` until its ``blocked`` actions are allowed, with a ``held`` record.

        ``annotate``: the decision's record is still being written (the step that made it):
        it says ``dispatch: held``, so a Manager node hands on each part by its ``dispatch`` record.
        """
        self.held[job.decision.id] = job
        if annotate and job.record is not None and "dispatch" not in job.record:
            job.record["dispatch"] = "held"
        opens = [t.lo for t in blocked if t.lo > now]
        forbidding = self.core.tracker.forbidding
        step.emit(
            Kind.HELD,
            {
                "decision": job.decision.id,
                "rule": job.decision.rule,
                "events": sorted({t.event for t in blocked}),
                "by": sorted({p.rule for t in blocked for p in forbidding(t.event, now)}),
                "opens": max(opens) if opens else None,
            },
        )
        if self.core.journal:  # a restart holds it again (and runs it once allowed)
            self.keep_held(job, step)

    # ------------------------------------------------------------------ the outbox
    def keep_held(self, job: Job, step: Step) -> None:
        """The journal's outbox entry of a decision dispatched in parts: whether actions of it
        are still held, those already handed on (``sent``: never run again) and those of them
        whose outcome is not recorded yet (``running``: a restart records the decision
        ``task-interrupted``)."""
        d = job.decision
        step.change.outbox[d.id] = {
            "decision": d.id,
            "rule": d.rule,
            "event": d.event,
            "held": d.id in self.held,
            "running": sorted(self.running.get(d.id, ())),
            "trigger": job.composition is not None,
            "record": d.to_json(),
            "sent": sorted(job.sent),
        }

    def handed_on(self, decision: int, actions: Iterable[int]) -> None:
        """(In a step.) ``actions`` of a decision dispatched in parts are handed to their
        implementation: in flight until :meth:`landed`, named by its outbox entry meanwhile."""
        ids = set(actions)
        if ids and self.core.journal:  # (a Manager node: handed on until it is published)
            self.running.setdefault(decision, set()).update(ids)

    def landed(self, decision: int, actions: Iterable[int], step: Step) -> None:
        """(In a step, with a journal.) ``actions`` of ``decision`` are no longer in flight
        (their outcome is recorded, they will not start, or -- a Manager node -- they were
        published): its outbox entry keeps what still waits or runs, and leaves when nothing does."""
        running = self.running.get(decision)
        if running is not None:
            running.difference_update(actions)
            if not running:
                del self.running[decision]
        held = self.held.get(decision)
        if held is not None:
            self.keep_held(held, step)
        elif decision not in self.running:
            step.change.outbox[decision] = None

    def delivered(self, decision: int) -> None:
        """A decision made with ``dispatch=False`` was handed on (published): with a journal,
        it leaves the outbox with the next step. Safe from any thread."""
        if self.core.journal:
            self._delivered.append(decision)

    @property
    def pending_delivery(self) -> bool:
        """Were decisions published since the last commit (their outbox entries still to clear)?"""
        return bool(self._delivered)

    def before_commit(self, step: Step) -> None:
        """(As a step commits.) Published decisions leave the journal's outbox with it."""
        while self._delivered:
            done = self._delivered.popleft()
            if done in self.held or done in self.running:  # dispatched in parts: keep what still waits
                self.landed(done, list(self.running.get(done, ())), step)
            else:
                step.change.outbox[done] = None

    # ------------------------------------------------------------------ where it starts
    def admit(self, job: Job) -> tuple[Job, int] | None:
        """``job`` as it may start now, with the ``seq`` of the last record before the check;
        None when nothing of it may.

        The check and what it reads happen under the lock ``request`` takes, so a dispatch
        and ``request`` never disagree: an action a prohibition forbids now is refused (a
        ``refused`` record, ``source`` the dispatch) and held again until allowed; one that
        ended since the decision (met, cancelled) is left out. A runtime that can no longer
        keep its state, or is closed, starts nothing.
        """
        core = self.core
        steps = core.steps
        with steps.lock:
            if steps.broken is not None or steps.closed:
                return None
            if not core.tracker.bans and all(t.status == PENDING for t in job.items):
                return job, steps.last_record  # nothing can forbid it: the common case
            with steps.step() as step:
                part = self._recheck(job, step)
                if part is job:  # as it was: the check is the last thing before it starts
                    return job, steps.last_record
            return None if part is None else (part, steps.last_record)

    def _recheck(self, job: Job, step: Step) -> Job | None:
        """(In ``step``.) What of ``job`` may start now; refuse and hold what is forbidden."""
        now = step.now
        tracker = self.core.tracker
        actions = [t for t in job.items if not t.prohibition]
        gone = [t for t in actions if t.status != PENDING]
        stopped = [t for t in actions if t.status == PENDING and tracker.forbidding(t.event, now)]
        if stopped:
            self._stop_at_start(job, stopped, now, step)
        if not gone and not stopped:
            return job
        left = {t.id for t in gone + stopped}
        kept = [t for t in job.items if t.id not in left]
        if gone and not stopped and all(t.id in left for t in actions):
            step.emit(
                Kind.WITHHELD,
                {
                    "decision": job.decision.id,
                    "rule": job.decision.rule,
                    "reason": "nothing it required is still owed",
                },
            )
        if actions and all(t.id in left for t in actions):
            if self.core.journal:
                self.landed(job.decision.id, [t.id for t in actions], step)
            return None  # every action it had waits, or is over
        part = _narrowed(job, kept)
        step.emit(Kind.DISPATCH, {"decision": part.decision.to_json()})
        return part

    def _stop_at_start(self, job: Job, stopped: list[Tracked], now: float, step: Step) -> None:
        """Refuse the ``stopped`` actions of ``job`` (a prohibition took force since it was
        decided) and hold them until allowed, as :meth:`ready` holds an action."""
        core = self.core
        for t in stopped:
            t.refused += 1
            job.sent.discard(t.id)
            if core.journal:
                step.change.obligations[t.id] = t.to_json()
        for event in sorted({t.event for t in stopped}):
            forbidding = core.tracker.forbidding(event, now)
            core.stats.refused += 1
            step.emit(
                Kind.REFUSED,
                {
                    "event": event,
                    "by": [p.rule for p in forbidding],
                    "obligations": [p.id for p in forbidding],
                    "reason": self.answers.given(event, forbidding).reason,
                    "source": f"dispatch of decision {job.decision.id} ({job.decision.rule})",
                },
            )
        held = self.held.get(job.decision.id)
        if held is None:  # the part waits as the decision's job: the rest of it has been handed on
            others = [t for t in job.items if not t.prohibition and t not in stopped]
            job.sent.update(t.id for t in others)
            self.handed_on(job.decision.id, (t.id for t in others if t.status == PENDING))
            self._hold(job, stopped, now, step, annotate=False)
        elif core.journal:
            self.keep_held(held, step)
        self.look_again()

    # ------------------------------------------------------------------ after a restart
    def rehold(self, rec: dict[str, Any]) -> bool:
        """Hold again a decision the journal kept as held; False when it cannot be (its rule is gone)."""
        core = self.core
        try:
            rule = core.ruleset.rule(str(rec["rule"]))
            d = Decision.from_json(rec["record"])
        except (KeyError, TypeError, ValueError):
            return False
        composition = (
            rule.compositions[d.clause]
            if rec.get("trigger") and d.clause is not None and 0 <= d.clause < len(rule.compositions)
            else None
        )
        items = [t for t in core.tracker.active if t.decision_id == d.id]
        sent = {int(i) for i in rec.get("sent", ()) if isinstance(i, int)}
        self.held[d.id] = Job(rule, d, composition, items, None, core.implementations, sent)
        return True

    def republish(self, rec: dict[str, Any], held: bool, step: Step) -> None:
        """(Restore, a Manager node.) The part of a decision dispatched in parts that was
        handed on but not known to be published goes into :attr:`undelivered` again -- only
        its actions still owed, so held ones are not published before they are allowed (task
        nodes run each action of a decision once); it stays in the outbox until published.
        No ``dispatch`` record is made again: the one before the restart says it."""
        decision = int(rec["decision"])
        ids = {int(i) for i in rec.get("running", ()) if isinstance(i, int)}
        items = (
            self.held[decision].items
            if held
            else [t for t in self.core.tracker.active if t.decision_id == decision]
        )
        owed = [t for t in items if t.id in ids and t.status == PENDING and not t.prohibition]
        if owed:
            events = {t.event for t in owed}
            record = dict(rec["record"])
            record["obligations"] = [
                o for o in record.get("obligations", ()) if o.get("negated") or o.get("event") in events
            ]
            self.undelivered.append(record)
            self.running[decision] = {t.id for t in owed}
        if held:
            self.keep_held(self.held[decision], step)
        elif owed:
            step.change.outbox[decision] = {**rec, "running": sorted(self.running[decision])}
        else:
            step.change.outbox[decision] = None


def _narrowed(job: Job, kept: list[Tracked]) -> Job:
    """A part of ``job``: its decision with only the obligations of ``kept``."""
    return dataclasses.replace(
        job,
        decision=dataclasses.replace(job.decision, obligations=tuple(t.obligation for t in kept)),
        items=kept,
    )
