"""A run over time, as the runtime recorded it: the model ``cosleec timeline`` draws.

A :class:`Timeline` is built from the records a Manager writes -- its audit log
(``cosleec demo --audit FILE``, ``Manager(audit=...)``), a Manager node's MCAP recording
(``--record FILE.mcap``, channels ``/cosleec/<kind>``) or the records of a run in memory
(:meth:`Timeline.from_records`) -- and holds what a reviewer looks at:

- measure values as step series (:class:`Series`; ``None`` while a value is unknown or stale);
- the active layer of each rule as bands (:class:`Band`), from the ``layers`` records'
  switches (and a ``semantics`` switch's active layers): a rule at its default has no band,
  an undetermined rule a band named ``?``. A band covers ``[start, end)``; a layer that was
  active for no time at all (switched in and out at one instant, as an update of several
  measures does) has none;
- markers (:class:`Marker`): each trigger (an ``event`` record), each decision with its rule
  and clause (the default, a layer ``R1.1``, undetermined, or an ``otherwise`` fallback),
  refusals, rejections, conflicts, cancellations, held and withheld decisions, failed and
  interrupted tasks, and run-wide notes (a semantics switch, a reload, a restart from a
  journal, records set aside);
- each obligation as a :class:`Bar` from its trigger to its deadline with its outcome
  (:class:`Outcome`), the time it was settled and a late event;
- ``otherwise`` chains as :class:`Link` s: the fallback decision of a missed obligation
  names it (``violated``), and that decision's obligations are its children.

Every record kind the runtime writes (:class:`cosleec.records.Kind`) is read; ``options``
gives the title, ``task-done`` and ``dispatch`` are counted but not drawn (an obligation's
outcome shows the first, the decision the second). A kind this version does not know is
ignored and counted in :attr:`Timeline.ignored`. Times are the runtime clock's, in seconds.

The marks themselves are in :mod:`cosleec.views.timeline_marks`, the files they are read
from in :mod:`cosleec.views.timeline_files` (:meth:`Timeline.read`). Drawing is elsewhere
(:mod:`cosleec.views.timeline_layout` and the renderers), so the model can be tested on
its own.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from cosleec.errors import UserError, clip, show
from cosleec.records import HEADER, Kind
from cosleec.runtime import said_in
from cosleec.views.timeline_files import read_records
from cosleec.views.timeline_marks import (
    UNDETERMINED,
    Band,
    Bar,
    Link,
    Marker,
    MarkerKind,
    Outcome,
    Series,
    Value,
    natural,
)


@dataclass(frozen=True, kw_only=True)
class Timeline:
    """A recorded run as the timeline draws it; build it with :meth:`from_records` or :meth:`read`.

    ``start`` and ``end`` are the first and last times the records name; ``rules`` every
    rule the run involved, in natural order (``R2`` before ``R10``); ``options`` the run's
    last ``options`` record (semantics, priorities); ``counts`` the records of each kind;
    ``ignored`` those of kinds this version does not know; ``runs`` how many runs the
    records hold.
    """

    source: str
    start: float
    end: float
    series: tuple[Series, ...]
    bands: tuple[Band, ...]
    markers: tuple[Marker, ...]
    bars: tuple[Bar, ...]
    links: tuple[Link, ...]
    rules: tuple[str, ...]
    options: Mapping[str, Any] = field(default_factory=dict)
    counts: Mapping[str, int] = field(default_factory=dict)
    ignored: Mapping[str, int] = field(default_factory=dict)
    runs: int = 1

    @classmethod
    def from_records(cls, records: Iterable[Mapping[str, Any]], source: str = "") -> Timeline:
        """The timeline of runtime records ``{"kind": ..., "time": ..., **data}`` in the order written.

        Audit-log lines, MCAP messages and :meth:`cosleec.demo.Run.records` all have this
        form. A record that lacks what its kind needs raises :class:`UserError` naming it
        (``source``, its ``seq`` or position, and the field).
        """
        return _Builder(source).build(list(records))

    @classmethod
    def read(cls, path: str | Path) -> Timeline:
        """The timeline of an audit log (``.jsonl``, ``.ndjson``) or a Manager node's recording (``.mcap``).

        Raises :class:`UserError` for a file that is missing, empty, not what its name says,
        holds a line that is not JSON (``file:line:col``) or a record that lacks what its kind
        needs, or whose name ends otherwise (:func:`cosleec.views.timeline_files.read_records`).
        """
        return cls.from_records(read_records(path), str(path))

    def bar(self, key: tuple[int, int]) -> Bar:
        """The bar of obligation ``key`` (``(run, id)``); KeyError if none."""
        return self._by_key[key]

    @cached_property
    def _by_key(self) -> dict[tuple[int, int], Bar]:
        return {b.key: b for b in self.bars}


# ------------------------------------------------------------------------------------------ building


def _describe(obligation: Mapping[str, Any]) -> str:
    """An obligation of a decision record as words: ``not RecordVideo within 600 s``."""
    within = obligation.get("within_s")
    text = f"{'not ' if obligation.get('negated') else ''}{obligation.get('event')}"
    return text + (f" within {within:g} s" if isinstance(within, int | float) else "")


class _Bad(Exception):
    """A record lacks what its kind needs (the builder names where)."""


def _num(rec: Mapping[str, Any], key: str, *, none: bool = False) -> float | None:
    x = rec.get(key)
    if x is None and none:
        return None
    if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
        raise _Bad(f"its {key} is not a finite number: {show(x)}")
    return float(x)


def _int(rec: Mapping[str, Any], key: str) -> int:
    x = rec.get(key)
    if isinstance(x, bool) or not isinstance(x, int):
        raise _Bad(f"its {key} is not a whole number: {show(x)}")
    return x


def _str(rec: Mapping[str, Any], key: str) -> str:
    x = rec.get(key)
    if not isinstance(x, str):
        raise _Bad(f"its {key} is not a name: {show(x)}")
    return x


_KNOWN_STATUS = {o.value for o in Outcome} - {Outcome.LATE, Outcome.CONFLICT, Outcome.OTHER}


class _Builder:
    """Reads records in order into a :class:`Timeline` (one pass, then the bars and links)."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.counts: Counter[str] = Counter()
        self.ignored: Counter[str] = Counter()
        self.options: dict[str, Any] = {}
        self.values: dict[str, list[tuple[float, Value | None]]] = {}
        self.layer: dict[str, tuple[str, float]] = {}  # rule -> (layer, since): open bands
        self.bands: list[Band] = []
        self.markers: list[Marker] = []
        self.obligations: dict[tuple[int, int], tuple[Mapping[str, Any], float | None]] = {}
        self.in_conflict: set[tuple[int, int]] = set()
        self.fallbacks: dict[tuple[int, int], tuple[int, int]] = {}  # fallback decision -> missed obligation
        self.rules: set[str] = set()
        self.space = 0  # the run whose ids the records use
        self.times: list[float] = []

    def build(self, records: Sequence[Mapping[str, Any]]) -> Timeline:
        spaces = _spaces(records)
        for i, rec in enumerate(records):
            if not isinstance(rec, Mapping):
                raise UserError(f"record {i + 1} is not an object: {show(rec)}", where=self.source)
            kind = rec.get("kind")
            try:
                if not isinstance(kind, str):
                    raise _Bad(f"it names no kind: {show(kind)}")
                t = _num(rec, "time")
                assert t is not None
                if spaces[i] != self.space:
                    self._new_run(t, rec)
                    self.space = spaces[i]
                self.times.append(t)
                self.counts[kind] += 1
                handler = _HANDLERS.get(kind)
                if handler is None:
                    self.ignored[kind] += 1
                else:
                    handler(self, t, rec)
            except (_Bad, KeyError, TypeError, ValueError, AttributeError) as e:
                what = f"{e}" if isinstance(e, _Bad) else f"{type(e).__name__}: {clip(str(e), 100)}"
                seq = rec.get("seq") if isinstance(rec, Mapping) else None
                at = f"seq {seq}" if isinstance(seq, int) else f"{i + 1}"
                raise UserError(
                    f"record {at} ({clip(str(kind), 40)}) cannot be drawn: {what}",
                    where=self.source,
                    hint="give the log as the runtime wrote it",
                ) from None
        return self._finish()

    # ------------------------------------------------------------------ records
    def _new_run(self, t: float, rec: Mapping[str, Any]) -> None:
        """A run that does not continue the last: it starts with every rule at its default and
        every measure unknown."""
        for rule in list(self.layer):
            self._switch(rule, None, t)
        for points in self.values.values():
            if points[-1][1] is not None:
                points.append((t, None))
        self._note(t, "new run", f"run {rec.get('run')} starts (its ids are its own)")

    def _context(self, t: float, rec: Mapping[str, Any]) -> None:
        values = rec["values"]
        if not isinstance(values, Mapping):
            raise _Bad(f"its values are not an object: {show(values)}")
        for name, v in values.items():
            if v is not None and not isinstance(v, bool | int | float | str):
                raise _Bad(f"measure {clip(str(name), 80)} has a value that is none: {show(v)}")
            points = self.values.setdefault(str(name), [])
            if not points or points[-1][1] != v or type(points[-1][1]) is not type(v):
                points.append((t, v))

    def _layers(self, t: float, rec: Mapping[str, Any]) -> None:
        for sw in rec["switches"]:
            self._switch(_str(sw, "rule"), sw.get("to"), t)

    def _semantics(self, t: float, rec: Mapping[str, Any]) -> None:
        active = {str(layer).rsplit(".", 1)[0]: str(layer) for layer in rec.get("active", ())}
        for rule in sorted(self.layer.keys() | active.keys()):
            self._switch(rule, active.get(rule), t)
        self._note(
            t,
            f"semantics {rec.get('semantics')}",
            "clause semantics switched; active layers: " + (", ".join(active.values()) or "none"),
        )

    def _switch(self, rule: str, to: object, t: float) -> None:
        if to is not None and not isinstance(to, str):
            raise _Bad(f"rule {clip(rule, 80)} switches to a layer that is no name: {show(to)}")
        was = self.layer.pop(rule, None)
        if was is not None and was[1] < t:
            self.bands.append(Band(rule=rule, layer=was[0], start=was[1], end=t))
        if to is not None:
            self.layer[rule] = (to, t)
            self.rules.add(rule)

    def _event(self, t: float, rec: Mapping[str, Any]) -> None:
        name = _str(rec, "event")
        self.markers.append(
            Marker(kind=MarkerKind.TRIGGER, time=t, rule=None, label=name, detail=f"event {name}")
        )

    def _decision(self, t: float, rec: Mapping[str, Any]) -> None:
        rule, event, clause = _str(rec, "rule"), _str(rec, "event"), rec.get("clause")
        self.rules.add(rule)
        wants = " and ".join(_describe(o) for o in rec.get("obligations", ())) or "nothing required"
        violated = rec.get("violated")
        if violated is not None:
            kind, label = MarkerKind.OTHERWISE, f"otherwise #{violated}"
            self.fallbacks[(self.space, _int(rec, "id"))] = (self.space, _int(rec, "violated"))
            head = f"{rule} otherwise (obligation #{violated} missed)"
        elif clause is None:
            kind, label = MarkerKind.UNDETERMINED, UNDETERMINED
            head = (
                f"{event} → {rule} undetermined (no value for {', '.join(map(str, rec.get('missing', ())))})"
            )
        else:
            where = "default" if clause == 0 else str(rec.get("layer") or f"{rule}.{clause}")
            kind, label = MarkerKind.DECISION, where
            head = f"{event} → {rule} [{where}]"
        why = rec.get("explanation") or rec.get("reason") or ""
        said = said_in(rec)  # what the robot says to people
        detail = (
            f"decision #{rec.get('id')}: {head} → {wants}"
            + (f"\n{clip(str(why), 300)}" if why else "")
            + (f"\nsays: {clip(str(said), 300)}" if said else "")
        )
        self.markers.append(Marker(kind=kind, time=t, rule=rule, label=label, detail=detail))

    def _obligation(self, t: float, rec: Mapping[str, Any]) -> None:
        key = (self.space, _int(rec, "id"))
        for k in ("rule", "event", "status"):
            _str(rec, k)
        _num(rec, "start")
        _num(rec, "deadline", none=True)
        _num(rec, "at", none=True)
        _int(rec, "decision")
        self.rules.add(rec["rule"])
        self.obligations[key] = (rec, t)  # the last record of an obligation is its state

    def _refused(self, t: float, rec: Mapping[str, Any]) -> None:
        event = _str(rec, "event")
        detail = f"request for {event} refused: {clip(str(rec.get('reason', '')), 300)}"
        for rule in rec.get("by", ()):
            self.rules.add(str(rule))
            self._mark(MarkerKind.REFUSED, t, str(rule), f"refused {event}", detail)

    def _rejected(self, t: float, rec: Mapping[str, Any]) -> None:
        reason = clip(str(rec.get("reason", "")), 300)
        hint = rec.get("hint")
        self._mark(MarkerKind.REJECTED, t, None, "rejected", reason + (f" ({hint})" if hint else ""))

    def _conflict(self, t: float, rec: Mapping[str, Any]) -> None:
        self.in_conflict.update(
            {(self.space, _int(rec, "obligation")), (self.space, _int(rec, "prohibition"))}
        )
        between = [str(r) for r in rec.get("between", ())]
        detail = (
            f"conflict over {rec.get('event')} ({rec.get('resolution')}, {rec.get('winner')} wins): "
            + clip(str(rec.get("explanation", "")), 300)
        )
        at = _num(rec, "at", none=True)
        for rule in dict.fromkeys(between):
            self.rules.add(rule)
            self._mark(
                MarkerKind.CONFLICT, t if at is None else at, rule, f"conflict {rec.get('event')}", detail
            )

    def _cancelled(self, t: float, rec: Mapping[str, Any]) -> None:
        rule = _str(rec, "rule")
        self.rules.add(rule)
        at = _num(rec, "at", none=True)
        detail = f"{rule}'s activation #{rec.get('instance')} cancelled: {rec.get('by')} has priority ({rec.get('priority')})"
        self._mark(
            MarkerKind.CANCELLED, t if at is None else at, rule, f"cancelled by {rec.get('by')}", detail
        )

    def _held(self, t: float, rec: Mapping[str, Any]) -> None:
        rule = _str(rec, "rule")
        events, by = ", ".join(map(str, rec.get("events", ()))), ", ".join(map(str, rec.get("by", ())))
        detail = f"decision #{rec.get('decision')} held: {events} not allowed yet" + (
            f" (forbidden by {by})" if by else ""
        )
        self._mark(MarkerKind.HELD, t, rule, "held", detail)

    def _withheld(self, t: float, rec: Mapping[str, Any]) -> None:
        rule = _str(rec, "rule")
        self._mark(
            MarkerKind.WITHHELD,
            t,
            rule,
            "withheld",
            f"decision #{rec.get('decision')} withheld: {rec.get('reason')}",
        )

    def _task_failed(self, t: float, rec: Mapping[str, Any]) -> None:
        rule = _str(rec, "rule")
        what = rec.get("event") or rec.get("what") or "task"
        self._mark(
            MarkerKind.TASK_FAILED,
            t,
            rule,
            f"{what} failed",
            f"decision #{rec.get('decision')}: {what} failed: " + clip(str(rec.get("error")), 300),
        )

    def _task_interrupted(self, t: float, rec: Mapping[str, Any]) -> None:
        rule = rec.get("rule")
        detail = f"decision #{rec.get('decision')}: {rec.get('reason')}"
        self._mark(
            MarkerKind.TASK_INTERRUPTED, t, str(rule) if rule is not None else None, "interrupted", detail
        )

    def _options(self, t: float, rec: Mapping[str, Any]) -> None:
        self.options = {
            k: rec[k]
            for k in ("semantics", "unknown", "untimed", "priorities", "priority_semantics")
            if k in rec
        }

    def _run_note(self, t: float, rec: Mapping[str, Any]) -> None:
        kind = str(rec["kind"])
        shown = {k: v for k, v in rec.items() if k not in HEADER}
        self._note(t, kind, f"{kind}: {clip(str(shown), 300)}")

    def _counted(self, t: float, rec: Mapping[str, Any]) -> None:
        """A kind the picture shows through others (task-done, dispatch): counted only."""

    def _note(self, t: float, label: str, detail: str) -> None:
        self._mark(MarkerKind.NOTE, t, None, label, detail)

    def _mark(self, kind: MarkerKind, t: float, rule: str | None, label: str, detail: str) -> None:
        self.markers.append(Marker(kind=kind, time=t, rule=rule, label=clip(label, 60), detail=detail))

    # ------------------------------------------------------------------ the end
    def _finish(self) -> Timeline:
        start = min(self.times, default=0.0)
        end = max(self.times, default=0.0)
        for rec, _ in self.obligations.values():  # a deadline judged late is settled at the deadline
            for x in (rec.get("at"), *(rec.get("late") or ())):
                if isinstance(x, int | float) and math.isfinite(x):
                    end = max(end, float(x))
        for rule, (layer, since) in sorted(self.layer.items()):
            if since < end:
                self.bands.append(Band(rule=rule, layer=layer, start=since, end=end))
        bars = tuple(self._bar(key, rec, end) for key, (rec, _) in sorted(self.obligations.items()))
        keys = {b.key for b in bars}
        links = tuple(
            Link(parent=self.fallbacks[(b.key[0], b.decision)], child=b.key, time=b.start)
            for b in bars
            if (b.key[0], b.decision) in self.fallbacks and self.fallbacks[(b.key[0], b.decision)] in keys
        )
        return Timeline(
            source=self.source,
            start=start,
            end=end,
            series=tuple(
                Series(name=n, points=tuple(p))
                for n, p in sorted(self.values.items(), key=lambda x: natural(x[0]))
            ),
            bands=tuple(sorted(self.bands, key=lambda b: (natural(b.rule), b.start))),
            markers=tuple(self.markers),
            bars=bars,
            links=links,
            rules=tuple(sorted(self.rules, key=natural)),
            options=self.options,
            counts=dict(self.counts),
            ignored=dict(self.ignored),
            runs=1 + self.space,
        )

    def _bar(self, key: tuple[int, int], rec: Mapping[str, Any], end: float) -> Bar:
        status = str(rec["status"])
        late = [float(x) for x in rec.get("late") or ()]
        if status == "violated" and late:
            outcome = Outcome.LATE
        elif status in ("violated", "blocked", "refused"):  # refused: blocked, in a log before issue 33
            outcome = Outcome.VIOLATED if status == "violated" else Outcome.BLOCKED
        elif key in self.in_conflict:
            outcome = Outcome.CONFLICT
        else:
            outcome = Outcome(status) if status in _KNOWN_STATUS else Outcome.OTHER
        start = float(rec["start"])
        deadline = None if rec.get("deadline") is None else float(rec["deadline"])
        at = None if rec.get("at") is None else float(rec["at"])
        stop = deadline if deadline is not None else at if at is not None else end
        clause = rec.get("clause")
        return Bar(
            key=key,
            rule=str(rec["rule"]),
            event=str(rec["event"]),
            negated=bool(rec.get("negated")),
            start=start,
            end=max(start, stop),
            deadline=deadline,
            outcome=outcome,
            status=status,
            at=at,
            late=late[0] if late else None,
            decision=int(rec["decision"]),
            clause=clause if isinstance(clause, int) and not isinstance(clause, bool) else None,
            depth=int(rec.get("depth") or 0),
            open=deadline is None and at is None,
        )


def _spaces(records: Sequence[Mapping[str, Any]]) -> list[int]:
    """The id space of each record: a new one where the ``run`` changes, unless the new run
    continues the last from its journal (its ids go on)."""
    out: list[int] = []
    space, run = 0, None
    for i, rec in enumerate(records):
        r = rec.get("run") if isinstance(rec, Mapping) else None
        if r is not None and run is not None and r != run and not _continues(records, i, r):
            space += 1
        if r is not None:
            run = r
        out.append(space)
    return out


def _continues(records: Sequence[Mapping[str, Any]], i: int, run: object) -> bool:
    """Does run ``run``, starting at record ``i``, restore a journal (a ``restored`` record
    before its first decision or obligation)?"""
    for rec in records[i:]:
        if not isinstance(rec, Mapping) or rec.get("run") != run:
            return False
        if rec.get("kind") == Kind.RESTORED:
            return rec.get("from") is not None  # a new journal, or one reset on purpose, starts afresh
        if rec.get("kind") in (Kind.DECISION, Kind.OBLIGATION):
            return False
    return False


_HANDLERS: dict[str, Callable[[_Builder, float, Mapping[str, Any]], None]] = {
    Kind.OPTIONS: _Builder._options,
    Kind.CONTEXT: _Builder._context,
    Kind.LAYERS: _Builder._layers,
    Kind.SEMANTICS: _Builder._semantics,
    Kind.OCCURRENCE: _Builder._event,
    Kind.DECISION: _Builder._decision,
    Kind.OBLIGATION: _Builder._obligation,
    Kind.REFUSED: _Builder._refused,
    Kind.REJECTED: _Builder._rejected,
    Kind.CONFLICT: _Builder._conflict,
    Kind.CANCELLED: _Builder._cancelled,
    Kind.HELD: _Builder._held,
    Kind.WITHHELD: _Builder._withheld,
    Kind.TASK_FAILED: _Builder._task_failed,
    Kind.TASK_INTERRUPTED: _Builder._task_interrupted,
    Kind.TASK_DONE: _Builder._counted,
    Kind.DISPATCH: _Builder._counted,
    Kind.RELOADED: _Builder._run_note,
    Kind.RESTORED: _Builder._run_note,
    Kind.DROPPED: _Builder._run_note,
    Kind.UNCOMMITTED: _Builder._run_note,
    Kind.AUDIT_MISMATCH: _Builder._run_note,
}
"""What each record kind the runtime writes contributes (by the ``kind`` string a record holds)."""
