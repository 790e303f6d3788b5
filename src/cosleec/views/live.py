"""What the live web view shows, kept up to date from the Manager's records.

A :class:`Live` is a Manager observer. It starts from the Manager's public state (values,
each rule's layer, what is in force) and then follows the records: ``context`` (values and
the time each last changed: its *age*), ``layers``, ``decision``, ``obligation`` (pending
ones are in force; ``violated`` ones are violations), ``conflict`` and ``refused``. A
reload, a change of semantics or a restore makes it read the Manager's state again.

It runs on the runtime's threads, so it only updates a few dictionaries under its own lock
and then calls ``wake`` (the server's way to tell its browsers, without waiting for them);
the history it keeps is bounded (:data:`HISTORY` of each kind), whatever the rate of
records. :meth:`Live.snapshot` is the page's whole state as JSON-ready data, the same for
``GET /state`` and every server-sent ``state`` message.
"""

from __future__ import annotations

import threading
from collections import OrderedDict, deque
from collections.abc import Callable
from typing import Any

from cosleec.runtime import Manager, Obligation, RuntimeEvent, Tracked, VirtualClock, said_in

#: how many decisions, violations, conflicts and refusals the page lists (the newest)
HISTORY = 20

#: the records after which the Manager's state is read again rather than followed
_RESYNC = frozenset({"reloaded", "semantics", "restored"})


class Live:
    """The state of the page, kept from a Manager's records (see the module docstring).

    ``wake`` is called, on the runtime's thread, after every change that the page shows;
    it must return at once. ``controls`` is copied into the snapshot (the page shows its
    controls only then).
    """

    def __init__(self, manager: Manager, wake: Callable[[], None], *, controls: bool = False) -> None:
        self.manager = manager
        self.controls = controls
        self._wake = wake
        self._lock = threading.Lock()
        self.version = 0  # counts the changes the page shows: a browser is sent each new one
        self.values: dict[str, Any] = {}
        self.since: dict[str, float] = {}  # when each value last changed (runtime clock, seconds)
        self.before: set[str] = set()  # values that were set before the view started: aged from then
        self.layers: dict[str, str | None] = {}
        self.in_force: dict[int, dict[str, Any]] = {}  # pending obligations and prohibitions, by id
        self.decisions: deque[dict[str, Any]] = deque(maxlen=HISTORY)
        self.violations: OrderedDict[int, dict[str, Any]] = OrderedDict()
        self.conflicts: deque[dict[str, Any]] = deque(maxlen=HISTORY)
        self.refusals: deque[dict[str, Any]] = deque(maxlen=HISTORY)
        self._unsubscribe = manager.subscribe(self.observe)  # first: nothing between read and follow
        self.resync(first=True)

    def close(self) -> None:
        """Stop following the Manager (again: nothing more)."""
        unsubscribe, self._unsubscribe = self._unsubscribe, _nothing
        unsubscribe()

    # ------------------------------------------------------------------ following the records
    def resync(self, first: bool = False) -> None:
        """Read the Manager's state anew: values, each rule's layer, what is in force."""
        m = self.manager
        values, layers = m.values(), m.rule_layers()
        in_force = {t.id: _tracked(t) for t in m.outstanding(prohibitions=True)}
        now = m.clock.now()
        with self._lock:
            for name, v in values.items():  # a value that did not change keeps its age
                if v is None and name not in self.since:
                    continue  # never known yet (at the start, or a measure a reload added): no age
                if name not in self.since or self.values.get(name) != v:
                    self.since[name] = now
                    if first:
                        self.before.add(name)
            for gone in set(self.since) - set(values):  # a reload dropped the measure
                del self.since[gone]
            self.values, self.layers, self.in_force = values, layers, in_force
            self.version += 1
        self._wake()

    def observe(self, ev: RuntimeEvent) -> None:
        """The Manager's observer: follow one record (quick, never blocks on a browser)."""
        kind, d = ev.kind, ev.data
        if kind in _RESYNC:
            self.resync()
            return
        with self._lock:
            if kind == "context":
                for name, v in d["values"].items():
                    self.values[name] = v
                    self.since[name] = ev.time
                    self.before.discard(name)
            elif kind == "layers":
                for sw in d["switches"]:
                    self.layers[sw["rule"]] = sw["to"]
            elif kind == "decision":
                self.decisions.append(_decision(d))
            elif kind == "obligation":
                self._obligation(d)
            elif kind == "conflict":
                self.conflicts.append(dict(d, time=ev.time))
            elif kind == "refused":
                self.refusals.append(
                    {"time": ev.time, "event": d["event"], "by": d["by"], "reason": d["reason"]}
                )
            else:
                return
            self.version += 1
        self._wake()

    def _obligation(self, d: dict[str, Any]) -> None:
        if d["status"] == "pending":
            self.in_force[d["id"]] = _obligation(d)
            return
        self.in_force.pop(d["id"], None)
        # a violation: missed, forbidden and done, or blocked (a prohibition forbade its whole
        # window: the Manager counts it so; "refused" in a log written before issue 33); a late
        # report of it comes again: one entry, updated
        if d["status"] in ("violated", "blocked", "refused"):
            self.violations[d["id"]] = {
                **_obligation(d),
                "status": "blocked" if d["status"] == "refused" else d["status"],
                "at": d["at"],
                "by": d["by"],
                "late": d["late"],
            }
            self.violations.move_to_end(d["id"])
            while len(self.violations) > HISTORY:
                self.violations.popitem(last=False)

    # ------------------------------------------------------------------ the page's state
    def snapshot(self) -> dict[str, Any]:
        """Everything the page shows, as JSON-ready data (``version`` says which change it is)."""
        m = self.manager
        rules = m.ruleset
        with self._lock:
            values, since, before = dict(self.values), dict(self.since), set(self.before)
            layers, version = dict(self.layers), self.version
            in_force = sorted(  # the nearest deadline first, those without one last
                self.in_force.values(), key=lambda o: (o["deadline"] is None, o["deadline"] or 0.0, o["id"])
            )
            decisions = list(self.decisions)[::-1]
            violations = list(self.violations.values())[::-1]
            conflicts, refusals = list(self.conflicts)[::-1], list(self.refusals)[::-1]
        measures = rules.measures
        state: dict[str, Any] = {
            "version": version,
            "now": m.clock.now(),
            "clock": "virtual" if isinstance(m.clock, VirtualClock) else "real",
            "source": str(rules.spec.path or ""),
            "semantics": str(m.semantics),
            "stats": dict(m.stats),
            "context": [
                {
                    "name": name,
                    "type": measures[name].kind if name in measures else "",
                    "value": v,
                    "since": since.get(name),
                    "before": name in before,
                }
                for name, v in values.items()
            ],
            "rules": [
                {
                    "name": r.name,
                    "trigger": r.trigger,
                    "layer": layers.get(r.name),
                    "clauses": {c.layer: c.text for c in r.clauses},
                }
                for r in rules.rules
            ],
            "obligations": [o for o in in_force if not o["negated"]],
            "prohibitions": [o for o in in_force if o["negated"]],
            "decisions": decisions,
            "violations": violations,
            "conflicts": conflicts,
            "refusals": refusals,
            "controls": self.controls,
        }
        if self.controls:
            state["events"] = sorted(rules.events)
        return state


def _nothing() -> None:
    """What :meth:`Live.close` leaves to call once it has unsubscribed."""


def _decision(d: dict[str, Any]) -> dict[str, Any]:
    """What the page shows of a decision record."""
    return {
        "id": d["id"],
        "time": d["time"],
        "event": d["event"],
        "rule": d["rule"],
        "clause": d["clause"],
        "layer": d["layer"],
        "obligations": [Obligation.from_json(o).describe() for o in d["obligations"]],
        "explanation": d["explanation"],
        "for_people": said_in(d),  # what the robot says to people
    }


def _obligation(d: dict[str, Any]) -> dict[str, Any]:
    """What the page shows of an obligation record (its countdown runs from start to deadline)."""
    return {
        "id": d["id"],
        "rule": d["rule"],
        "event": d["event"],
        "negated": d["negated"],
        "decision": d["decision"],
        "start": d["start"],
        "deadline": d["deadline"],
        "what": Obligation.from_json(d["obligation"]).describe(),
    }


def _tracked(t: Tracked) -> dict[str, Any]:
    """An obligation in force, read from the Manager, as :func:`_obligation` shows a record."""
    return {
        "id": t.id,
        "rule": t.rule,
        "event": t.event,
        "negated": t.prohibition,
        "decision": t.decision_id,
        "start": t.start,
        "deadline": t.hi,
        "what": t.obligation.describe(),
    }
