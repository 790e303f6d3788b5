"""The lifecycle of obligations: pending -> fulfilled | violated, as SLEEC defines it.

The Manager owns one :class:`Tracker` and drives it under its lock: it starts an
obligation for every item of a decision's response, and reports occurrences and the
passing of time to it. The rules it applies:

- ``E within T`` is fulfilled by an occurrence of E reported in [t, t+T] (inclusive) and
  violated as soon as the clock passes t+T without one; ``within [a, b]`` ignores earlier
  occurrences. An untimed ``E`` has no deadline (pending, reported as outstanding) unless
  the runtime is configured otherwise (``Manager(untimed=...)``); an untimed ``not E``
  holds only at the trigger instant.
- ``otherwise`` starts only on a real miss, at the deadline; the first E that arrives
  after the deadline is recorded, once, as *late* and does not cancel the fallback.
- ``not E within T`` holds while E is not reported in its window: a request for E is
  refused and recorded; an E reported anyway violates it (and starts its ``otherwise`` at
  that moment).
- ``P else Q``: Q's items, each in its own window, fulfil it too; it is violated when
  the last of the windows closes.
- A window that ends before it starts (a negative deadline from measures) is closed at
  once (:meth:`Tracker.expire`).
- An obligation can also end ``blocked`` (a prohibition forbids its whole window: a
  conflict, see the Manager; a violation, counted in ``stats["violations"]``) or ``cancelled`` (a higher rule's priority); both are set
  by the Manager through :meth:`Tracker.finish`. It ends ``withdrawn`` when a reload
  removes the rule (or the response item) it came from (:meth:`Tracker.withdraw`): it
  can no longer be violated and its ``otherwise`` never starts.

Causal order: an occurrence counts only for obligations created before it was handled.
"""

from __future__ import annotations

import functools
import heapq
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from cosleec.bulk import positional_init
from cosleec.lang import Untimed
from cosleec.runtime.model import Obligation

PENDING, FULFILLED, VIOLATED, RESPECTED = "pending", "fulfilled", "violated", "respected"
BLOCKED, CANCELLED, WITHDRAWN = "blocked", "cancelled", "withdrawn"
REFUSED = BLOCKED  # the old name of BLOCKED; "refused" is an attempt a prohibition did not permit
MISSES_KEPT = 64  # per event: missed obligations a late occurrence is still reported for


@dataclass(kw_only=True, slots=True)
class Tracked:
    """One obligation in force, with its absolute window and outcome."""

    id: int
    decision_id: int
    clause: int | None  # the clause of the decision that created it (kept by its fallbacks)
    rule: str
    obligation: Obligation
    start: float
    lo: float
    hi: float | None  # None: no deadline
    seq: int  # causal position: occurrences with a larger seq may count
    depth: int = 0  # 0: from a decision; n: the n-th otherwise down a chain
    instance: int = 0  # the decision that started the chain (a rule's activation, for priorities)
    own_hi: float | None = (
        None  # the end of the event's own window (``hi`` is the last of all, `else` included)
    )
    branches: tuple[tuple[tuple[str, float, float | None], ...], ...] = ()  # `else`, absolute windows
    met: tuple[list[int], ...] = ()  # per branch: the items already seen
    status: str = PENDING
    outcome_at: float | None = None
    by: str | None = None  # the event that fulfilled (or violated) it
    late: list[float] = field(default_factory=list)  # the first E after a missed deadline (at most one)
    refused: int = 0  # requests refused by this prohibition

    @property
    def event(self) -> str:
        """The event the obligation names (for a prohibition, the forbidden one)."""
        return self.obligation.event

    @property
    def prohibition(self) -> bool:
        """True for ``not E``: the obligation forbids E in its window instead of requiring it."""
        return self.obligation.negated

    def to_json(self) -> dict[str, Any]:
        """The ``obligation`` record of observers, the audit log and the ``violations`` topic.

        A snapshot: later changes to this obligation (a late event) do not alter it.
        :meth:`from_json` reads it back (the ``otherwise`` fallback stays in the process).
        """
        return _record(self, self._now())

    def record_of(self) -> Callable[[], dict[str, Any]]:
        """:meth:`to_json` now, as a function that makes it when called (``Step.emit_later``:
        the hot path's record, which nobody may read): it keeps, as they are now, the fields
        that change while the obligation is in force (its outcome, late events, refusals,
        the `else` items met; its window and ``otherwise`` on a restore or reload), and
        the obligation for the others, which never change once it is tracked."""
        return functools.partial(_record, self, self._now())

    def shift(self, by: float) -> None:
        """Move every time this obligation keeps by ``by`` seconds (a restore after a reboot:
        into the new boot's clock): its start, window and deadline, its own event's window
        and each `else` branch's window."""
        self.start += by
        self.lo += by
        self.hi = None if self.hi is None else self.hi + by
        self.own_hi = None if self.own_hi is None else self.own_hi + by
        self.branches = tuple(
            tuple((e, lo + by, None if hi is None else hi + by) for e, lo, hi in br) for br in self.branches
        )

    def _now(self) -> _Now:
        """What of this obligation may still change, as it is now (copies of its lists)."""
        return (
            self.obligation,
            self.start,
            self.lo,
            self.hi,
            self.own_hi,
            self.branches,
            self.status,
            self.outcome_at,
            self.by,
            tuple(self.late),
            self.refused,
            tuple(map(tuple, self.met)),
        )

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Tracked:
        """An obligation record read back from :meth:`to_json`."""
        lo, own = d["window"]
        hi = d.get("deadline", own)
        at, clause = d.get("at"), d.get("clause")
        return cls(
            id=int(d["id"]),
            decision_id=int(d["decision"]),
            clause=None if clause is None else int(clause),
            rule=str(d["rule"]),
            obligation=Obligation.from_json(d["obligation"]),
            start=float(d["start"]),
            lo=float(lo),
            hi=None if hi is None else float(hi),
            seq=int(d["causal"] if "causal" in d else d["seq"]),
            depth=int(d.get("depth", 0)),
            instance=int(d.get("instance", d["decision"])),
            own_hi=None if own is None else float(own),
            branches=tuple(
                tuple((str(e), float(a), None if b is None else float(b)) for e, a, b in br)
                for br in d.get("branches", ())
            ),
            met=tuple([int(i) for i in m] for m in d.get("met", ())),
            status=BLOCKED if d["status"] == "refused" else str(d["status"]),  # its name before issue 33
            outcome_at=None if at is None else float(at),
            by=d.get("by"),
            late=[float(x) for x in d.get("late", ())],
            refused=int(d.get("refused", 0)),
        )


@dataclass
class Outcome:
    """What an occurrence or the passing of time changed."""

    changed: list[Tracked] = field(default_factory=list)
    fallbacks: list[tuple[Tracked, float]] = field(default_factory=list)  # (violated, start of fallback)
    # pending obligations that met an `else` item and are not settled yet: a new state too
    # (what the branch met), recorded and journaled so that a restart does not forget it
    progressed: list[Tracked] = field(default_factory=list)


class Tracker:
    """Obligations in force, indexed by event and by deadline.

    The cost of an occurrence depends on the obligations waiting for that event, and the
    cost of advancing time on the windows that actually close: never on everything pending.

    ``untimed`` is the deadline of an untimed response: ``"none"``, ``"immediate"``
    (``immediate_tolerance`` seconds) or a number of seconds. Times are clock times in
    seconds. Not thread-safe: its owner (the Manager) serialises access.
    """

    def __init__(
        self, untimed: Untimed | str | float = Untimed.NONE, immediate_tolerance: float = 1.0
    ) -> None:
        self.untimed: Untimed | float = Untimed(untimed) if isinstance(untimed, str) else untimed
        self.tolerance = immediate_tolerance
        self._active: dict[int, Tracked] = {}
        self._by_event: dict[str, dict[int, Tracked]] = {}
        self._bans: dict[str, dict[int, Tracked]] = {}  # the prohibitions in force, by the event they forbid
        self.bans = 0  # how many prohibitions are in force (0: nothing is forbidden, the fast path)
        # activation -> what it has in force, rule -> its activations: kept only for priorities
        self.by_instance = False
        self._instances: dict[int, dict[int, Tracked]] = {}  # activation -> what it has in force
        self._rules: dict[str, dict[int, int]] = {}  # rule -> its decided activations in force (item counts)
        self._heap: list[tuple[float, int]] = []
        self._missed: dict[str, deque[Tracked]] = {}  # per event: recent misses a late E may still report
        self.forgotten: list[int] = []  # misses dropped from _missed since the owner last looked
        self.closed: deque[Tracked] = deque(maxlen=1000)  # the most recent outcomes, for inspection
        self._next = 1  # the next obligation id
        self.ended = 0  # changes whenever one ends (what can release an action held back)
        self.keep_started = False  # keep `started` (conflict-aware priorities read what is new)
        self.started: list[Tracked] = []  # what started since the owner last cleared it

    @property
    def active(self) -> list[Tracked]:
        """Every obligation in force, prohibitions included (a new list)."""
        return list(self._active.values())

    @property
    def next_id(self) -> int:
        """The id the next obligation will get (kept by a journal across restarts)."""
        return self._next

    def resume(self, tracked: Tracked, next_id: int) -> None:
        """Track an obligation restored from a journal, as it was; later ids start at ``next_id``."""
        self._index(tracked)
        self._next = max(next_id, tracked.id + 1, self._next)

    def resume_ids(self, next_id: int) -> None:
        """Later obligation ids start at ``next_id`` at the least (a journal's counter)."""
        self._next = max(self._next, next_id)

    def start(
        self,
        decision_id: int,
        clause: int | None,
        ob: Obligation,
        now: float,
        seq: int,
        depth: int = 0,
        instance: int | None = None,
    ) -> Tracked:
        """Start tracking ``ob``, required by decision ``decision_id`` (of ``clause``) at ``now``.

        ``instance`` is the activation it belongs to (default: the decision itself). A
        window that ends before it starts is tracked too: :meth:`expire` closes it.
        """
        hi = ob.within_s
        if hi is None and not ob.eventually:
            if ob.negated:
                hi = 0.0  # untimed `not E`: only at the trigger instant
            elif self.untimed == "immediate":
                hi = self.tolerance
            elif isinstance(self.untimed, int | float) and not isinstance(self.untimed, bool):
                hi = float(self.untimed)
        t = Tracked(
            id=self._next,
            decision_id=decision_id,
            clause=clause,
            rule=ob.rule,
            obligation=ob,
            start=now,
            lo=now + ob.from_s,
            hi=None if hi is None else now + hi,
            seq=seq,
            depth=depth,
            instance=decision_id if instance is None else instance,
        )
        t.own_hi = t.hi
        if ob.alternatives and not ob.negated:
            t.branches = tuple(
                tuple((e, now + a, None if b is None else now + b) for e, a, b in br)
                for br in ob.alternatives
            )
            t.met = tuple([] for _ in t.branches)
            ends = [t.hi, *(b for br in t.branches for _, _, b in br)]
            t.hi = None if any(e is None for e in ends) else max(e for e in ends if e is not None)
        self._next += 1
        self._index(t)
        return t

    def start_plain(
        self,
        decision_id: int,
        clause: int | None,
        rule: str,
        ob: Obligation,
        now: float,
        hi: float | None,
        seq: int,
    ) -> Tracked:
        """What :meth:`start` does for a plain obligation -- one required event (no ``not``,
        no ``else``), a window from ``now`` to ``hi`` (absolute, None: none; the caller has
        applied ``untimed``), from a decision (depth 0, its own activation) -- for the hot
        path that made ``hi`` once per rule set (:mod:`cosleec.runtime.plans`)."""
        t = _new(Tracked)
        tid = self._next
        _init_plain(t, tid, decision_id, clause, rule, ob, now, now + ob.from_s, hi, seq, decision_id, hi)
        self._next = tid + 1
        if self.keep_started or self.by_instance:
            self._index(t)
            return t
        self._active[tid] = t
        bucket = self._by_event.get(ob.event)
        if bucket is None:
            bucket = self._by_event[ob.event] = {}
        bucket[tid] = t
        if hi is not None:
            heapq.heappush(self._heap, (hi, tid))
        return t

    def quiet_for(self, event: str, now: float) -> bool:
        """Would an occurrence of ``event`` at ``now`` find nothing here to act on: nothing
        forbidden, no window due (:meth:`backlog`), nothing waiting for it (:meth:`waits_for`)?
        The three checks of the hot path, in one call."""
        heap = self._heap
        return not (
            self.bans or (heap and heap[0][0] < now) or self._by_event.get(event) or self._missed.get(event)
        )

    def waits_for(self, event: str) -> bool:
        """Would an occurrence of ``event`` change anything here: something in force names it
        (to require, forbid, or as an `else` branch), or a miss waits for its late event?"""
        return bool(self._by_event.get(event)) or bool(self._missed.get(event))

    def closed_at_start(self, t: Tracked) -> bool:
        """Does ``t``'s window end before it starts (a negative deadline computed from measures)?"""
        return t.hi is not None and t.hi < t.lo and not t.branches

    def expire(self, t: Tracked, now: float) -> Outcome:
        """Close ``t`` at once: an obligation violated (its ``otherwise`` starting ``now``), a
        prohibition respected. For a window that closed before it opened."""
        out = Outcome()
        if t.prohibition:
            t.status, t.outcome_at = RESPECTED, now
        else:
            t.status, t.outcome_at = VIOLATED, now
            if t.obligation.otherwise is not None:
                out.fallbacks.append((t, now))
        out.changed.append(t)
        self._close(t)
        return out

    def finish(self, t: Tracked, status: str, now: float, by: str) -> None:
        """End ``t`` as ``blocked`` or ``cancelled`` at ``now``, settled by rule ``by``."""
        t.status, t.outcome_at, t.by = status, now, by
        self._close(t)

    def withdraw(self, t: Tracked, now: float) -> None:
        """End ``t`` as ``withdrawn`` at ``now``: the rules it came from are gone (a reload).

        Nothing settled it, so ``by`` stays None; it is no miss, so no late event is kept for it.
        """
        t.status, t.outcome_at, t.by = WITHDRAWN, now, None
        self._close(t)

    def misses(self) -> list[Tracked]:
        """The missed obligations still waiting for their late event (oldest first per event)."""
        return [t for missed in self._missed.values() for t in missed]

    def forget(self, t: Tracked) -> None:
        """Stop waiting for the late event of missed ``t`` (its rule is gone: a reload)."""
        missed = self._missed.get(t.event)
        if missed is not None:
            for i, x in enumerate(missed):
                if x is t:
                    del missed[i]
                    break

    def reindex(self, by_instance: bool, keep_started: bool) -> None:
        """Switch the indexes priorities need on or off, for what is in force now (a reload
        that adds or removes the priorities): activations, and what started since last read."""
        self.by_instance = by_instance
        self.keep_started = keep_started
        self.started.clear()
        self._instances.clear()
        self._rules.clear()
        if by_instance:
            for t in sorted(self._active.values(), key=lambda t: t.id):
                self._index_instance(t)

    def obliging(self, event: str) -> list[Tracked]:
        """The obligations in force to produce ``event`` (not through an `else`), oldest first."""
        found = self._by_event.get(event, {}).values()
        return sorted((t for t in found if t.event == event and not t.prohibition), key=lambda t: t.id)

    def banned(self) -> list[str]:
        """The events some prohibition in force forbids (now or later)."""
        return [e for e, bans in self._bans.items() if bans]

    def banning(self, event: str) -> list[Tracked]:
        """The prohibitions of ``event`` in force (whatever their windows), oldest first."""
        bans = self._bans.get(event)
        return sorted(bans.values(), key=lambda t: t.id) if bans else []

    def _index(self, t: Tracked) -> None:
        if self.keep_started:
            self.started.append(t)
        self._active[t.id] = t
        for ev in _events(t):
            self._by_event.setdefault(ev, {})[t.id] = t
        if t.prohibition:
            self._bans.setdefault(t.event, {})[t.id] = t
            self.bans += 1
        if t.hi is not None:
            heapq.heappush(self._heap, (t.hi, t.id))
        if self.by_instance:
            self._index_instance(t)

    def _index_instance(self, t: Tracked) -> None:
        self._instances.setdefault(t.instance, {})[t.id] = t
        if t.clause is not None:  # an undetermined decision is no activation a priority acts on
            counts = self._rules.setdefault(t.rule, {})
            counts[t.instance] = counts.get(t.instance, 0) + 1

    def _close(self, t: Tracked) -> None:
        self.ended += 1
        del self._active[t.id]
        if len(self._heap) > 2 * len(self._active) + 1024:  # closed early: drop their deadlines
            self._heap[:] = [(hi, i) for hi, i in self._heap if i in self._active]  # in place: due() holds it
            heapq.heapify(self._heap)
        for ev in _events(t):
            bucket = self._by_event.get(ev)
            if bucket is not None:
                bucket.pop(t.id, None)
        if t.prohibition:
            bans = self._bans.get(t.event)
            if bans is not None and bans.pop(t.id, None) is not None:
                self.bans -= 1
        items = self._instances.get(t.instance) if self.by_instance else None
        if items is not None and items.pop(t.id, None) is not None:
            if not items:
                del self._instances[t.instance]
            counts = self._rules.get(t.rule)
            if t.clause is not None and counts is not None:
                counts[t.instance] -= 1
                if not counts[t.instance]:
                    del counts[t.instance]
        self.closed.append(t)
        if t.status == VIOLATED and not t.prohibition:
            self._miss(t)

    def _miss(self, t: Tracked) -> None:
        """Keep a missed obligation for its late event; the oldest of its event is forgotten past 64."""
        missed = self._missed.setdefault(t.event, deque(maxlen=MISSES_KEPT))
        if len(missed) == MISSES_KEPT:
            self.forgotten.append(missed[0].id)
        missed.append(t)

    def missed(self, t: Tracked) -> None:
        """Keep a missed obligation restored from a journal: its late event is still reported once."""
        self._miss(t)
        self._next = max(self._next, t.id + 1)

    def waits_late(self, t: Tracked) -> bool:
        """Is ``t`` a missed obligation whose late event is still to be reported (journal: keep it)?"""
        return t.status == VIOLATED and not t.prohibition and not t.late

    def occur(self, event: str, now: float, seq: int) -> Outcome:
        """Apply an occurrence of ``event`` at ``now``: what it fulfils, violates or arrives late for.

        Only obligations started before it (a smaller ``seq``) count. It does not look at
        deadlines: call :meth:`due` first, so that a window already closed is violated
        rather than fulfilled. A prohibition it breaks is violated, with its ``otherwise``
        starting now.
        """
        out = Outcome()
        for t in list(self._by_event.get(event, {}).values()):
            if t.seq >= seq:
                continue  # created by this very occurrence or later: it cannot count
            ob = t.obligation
            if ob.negated:
                if ob.event == event and t.lo <= now and (t.hi is None or now <= t.hi):
                    t.status, t.outcome_at, t.by = VIOLATED, now, event
                    out.changed.append(t)
                    if ob.otherwise is not None:
                        out.fallbacks.append((t, now))
                    self._close(t)
            elif ob.event == event and t.lo <= now and (t.own_hi is None or now <= t.own_hi):
                # before an interval opens it neither fulfils nor violates
                t.status, t.outcome_at, t.by = FULFILLED, now, event
                out.changed.append(t)
                self._close(t)
            elif t.branches and (complete := _branch_met(t, event, now)) is not None:
                if complete:
                    t.status, t.outcome_at, t.by = FULFILLED, now, event
                    out.changed.append(t)
                    self._close(t)
                else:  # an item met, its branch not complete: still pending
                    out.progressed.append(t)
        missed = self._missed.get(event)
        if missed:  # the first E after a missed deadline is recorded as late, once
            for t in [t for t in missed if t.hi is not None and now > t.hi and t.seq < seq]:
                t.late.append(now)
                out.changed.append(t)
                missed.remove(t)
        return out

    def due(self, now: float, limit: int | None = None) -> Outcome:
        """Close the windows that ended before ``now`` at the earliest such deadline (at most
        ``limit`` of them); the caller starts their fallbacks, then calls again for the next.

        One deadline at a time, so that an ``otherwise`` starting at a deadline is in force
        before a later deadline is judged (time order, as the reference semantics). A
        pending obligation is violated (its ``otherwise``, if any, is returned in
        ``fallbacks``, starting at the deadline); a prohibition is respected.
        """
        out = Outcome()
        heap = self._heap
        if not heap or heap[0][0] >= now:
            return out  # nothing is due: the common case
        first = self.next_deadline()
        while (
            heap and heap[0][0] < now and heap[0][0] == first and (limit is None or len(out.changed) < limit)
        ):
            hi, tid = heapq.heappop(heap)
            t = self._active.get(tid)
            if t is None or t.hi != hi:
                continue
            if t.prohibition:
                t.status, t.outcome_at = RESPECTED, t.hi
            else:
                t.status, t.outcome_at = VIOLATED, t.hi
                if t.obligation.otherwise is not None:
                    out.fallbacks.append((t, t.hi))
            out.changed.append(t)
            self._close(t)
        return out

    def forbidding(self, event: str, now: float) -> list[Tracked]:
        """The prohibitions that forbid ``event`` at ``now``; empty means it is allowed.

        Records nothing: the caller counts the refusal.
        """
        bans = self._bans.get(event)
        if not bans:
            return []
        return [t for t in bans.values() if t.lo <= now and (t.hi is None or now <= t.hi)]

    def instances_of(self, rule: str) -> list[int]:
        """The decided activations of ``rule`` with something in force."""
        return list(self._rules.get(rule, ()))

    def of_instance(self, instance: int) -> list[Tracked]:
        """What activation ``instance`` has in force, oldest first."""
        return sorted(self._instances.get(instance, {}).values(), key=lambda t: t.id)

    def backlog(self, now: float) -> int:
        """About how many windows are due at ``now`` (0 when none is); cheap, an upper bound."""
        heap = self._heap
        return len(heap) if heap and heap[0][0] < now else 0

    def next_deadline(self) -> float | None:
        """The earliest deadline still pending (clock time, seconds), or None; the timer sleeps until it."""
        heap = self._heap
        while heap and (heap[0][1] not in self._active):
            heapq.heappop(heap)
        return heap[0][0] if heap else None

    def outstanding(self) -> list[Tracked]:
        """Pending obligations that require an event (prohibitions left out): what the robot still owes."""
        return [t for t in self._active.values() if not t.prohibition]


_new = object.__new__
# Tracked's __init__ with a plain obligation's fields, positional (Tracker.start_plain)
_init_plain = positional_init(
    Tracked,
    ("id", "decision_id", "clause", "rule", "obligation", "start", "lo", "hi", "seq", "instance", "own_hi"),
)


#: what :meth:`Tracked._now` keeps: obligation, start, lo, hi, own_hi, branches, status,
#: outcome_at, by, late, refused, met
_Now = tuple[
    Obligation,
    float,
    float,
    float | None,
    float | None,
    tuple[tuple[tuple[str, float, float | None], ...], ...],
    str,
    float | None,
    str | None,
    tuple[float, ...],
    int,
    tuple[tuple[int, ...], ...],
]


def _record(t: Tracked, now: _Now) -> dict[str, Any]:
    """The ``obligation`` record of ``t`` with what may change as ``now`` holds it (:meth:`Tracked.to_json`)."""
    obligation, start, lo, hi, own_hi, branches, status, outcome_at, by, late, refused, met = now
    return {
        "type": "obligation",
        "id": t.id,
        "decision": t.decision_id,
        "clause": t.clause,
        "causal": t.seq,  # its place in the causal order of occurrences
        "obligation": obligation.to_json(),
        "rule": t.rule,
        "event": obligation.event,
        "negated": obligation.negated,
        "start": start,
        "window": [lo, own_hi],
        "deadline": hi,
        "instance": t.instance,
        "status": status,
        "at": outcome_at,
        "by": by,
        "late": list(late),  # a copy: a record must not change after it was emitted
        "refused": refused,
        "depth": t.depth,
        "branches": [[list(w) for w in b] for b in branches],
        "met": [list(m) for m in met],
    }


def _events(t: Tracked) -> tuple[str, ...]:
    """The events an occurrence of which can settle ``t``: its own and its `else` branches'."""
    if not t.branches:
        return (t.obligation.event,)
    return (t.obligation.event, *(e for br in t.branches for e, _, _ in br))


def _branch_met(t: Tracked, event: str, now: float) -> bool | None:
    """Count an occurrence for ``t``'s `else` branches: True when one is now complete, False
    when it met an item of one that is not, None when it met none."""
    counted = None
    for br, met in zip(t.branches, t.met):
        for j, (e, lo, hi) in enumerate(br):
            if e == event and lo <= now and (hi is None or now <= hi) and j not in met:
                met.append(j)
                counted = False
        if len(met) == len(br):
            return True
    return counted
