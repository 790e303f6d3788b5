"""One outcome, whatever the transport: the normalised record stream of a run, and its comparison.

The embedded demo and the same scenario over ROS 2 or ROS 1 must decide, oblige, fulfil
and violate exactly alike, on the scenario's virtual clock. Their raw records cannot be
compared as they are: the embedded Manager runs a task's reports depth-first, inside the
dispatch that caused them, while a task node queues decisions and reports them in turn;
and on ROS 1 the Manager handles messages of different publishers on different threads,
so records of one instant can be written in another order. :func:`outcomes` keeps what
a run *decided and what came of it*, and puts the records of each instant into one
canonical order, so that two runs compare record by record and any difference is real.

Records are the Manager's runtime events in audit form (``{"kind", "time", **data}``, kinds
and fields as :mod:`cosleec.records` defines them): the records of a Manager's ``--audit``
file as the one reader reads them (:func:`cosleec.runtime.read_audit`), or
:meth:`cosleec.demo.Run.records`.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from cosleec.demo.player import Step
from cosleec.demo.runner import run
from cosleec.records import HEADER, Kind

#: record kinds that end an instant: the driver changed the context (and so the layers)
BARRIERS = (Kind.CONTEXT, Kind.LAYERS)
#: record kinds only the embedded Manager makes: it runs the tasks, a Manager node does not
#: (task nodes count what they ran in their status); what a task failed to do shows up as
#: a violation anyway
EMBEDDED_ONLY = (Kind.TASK_DONE, Kind.TASK_FAILED)
#: record kinds that describe the run rather than its outcomes (the options it ran with)
SETTINGS = (Kind.OPTIONS,)
#: fields of a record of another kind that are not compared: the Manager's numbering of
#: its inputs (the order in which reports arrived), the process it ran in, and the audit
#: log's header (seq, wall and monotonic time, run id, rule digest)
VOLATILE = ("causal", "session", *(k for k in HEADER if k not in ("kind", "time")))


@dataclass(frozen=True)
class Outcome:
    """One normalised record: what was decided or what became of an obligation, and when.

    ``time`` is the Manager's clock when the record was made (the virtual clock of the
    scenario). ``id`` is the decision's or obligation's id, the context or layer version
    for those kinds; ``decision`` is an obligation's decision (for a decision, the
    obligation whose violation started its ``otherwise``). ``detail`` is canonical JSON of
    the remaining fields that must match (required obligations, values, windows, ...).
    Left out because they legitimately differ between transports: wall-clock times, the
    Manager's input sequence numbers (``seq``, the order in which reports arrived), the
    configuration echoed in each decision and the explanation text built from the other
    fields.
    """

    kind: str
    time: float
    id: int | None = None
    rule: str | None = None
    event: str | None = None  # a decision's trigger ("otherwise" for a fallback); an obligation's event
    clause: int | None = None
    layer: str | None = None
    decision: int | None = None
    status: str | None = None  # an obligation's: pending, fulfilled, violated, respected
    at: float | None = None  # when an obligation was fulfilled, violated or respected
    late: tuple[float, ...] = ()  # when the event came after the violation
    detail: str = ""

    def __str__(self) -> str:
        """One line for reports, without ``detail``: ``t=150 obligation #7 R3 RetryAgreed violated at 120``."""
        parts = [f"t={self.time:g}", self.kind]
        if self.id is not None:
            parts.append(f"#{self.id}")
        parts += [v for v in (self.rule, self.event) if v is not None]
        if self.kind == Kind.DECISION:
            parts.append(f"clause={self.clause} layer={self.layer}")
        if self.status is not None:
            parts.append(self.status + (f" at {self.at:g}" if self.at is not None else ""))
        if self.late:
            parts.append("late at " + ", ".join(f"{t:g}" for t in self.late))
        return " ".join(parts)

    def fields(self) -> dict[str, Any]:
        """Every compared field by name, ``detail`` spread out: what :func:`first_difference` names."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "detail"}
        if self.detail:
            out.update(json.loads(self.detail))
        return out

    @property
    def violation(self) -> bool:
        """A first violation of an obligation, as the Manager counts it (not a later ``late`` report)."""
        return self.kind == Kind.OBLIGATION and self.status == "violated" and not self.late


def _canon(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)


def _opt_int(v: Any) -> int | None:
    return None if v is None else int(v)


def _opt_float(v: Any) -> float | None:
    return None if v is None else float(v)


def normalise(record: Mapping[str, Any]) -> Outcome | None:
    """The :class:`Outcome` of one audit-form record; None for a kind in ``EMBEDDED_ONLY`` or ``SETTINGS``.

    A record of a kind not known here is compared whole, but for ``VOLATILE`` fields: a
    new kind of record is checked, not dropped. KeyError for a record that lacks a field
    of its kind.
    """
    kind = str(record["kind"])
    t = float(record["time"])
    if kind in EMBEDDED_ONLY or kind in SETTINGS:
        return None
    if kind == Kind.DECISION:
        return Outcome(
            kind,
            t,
            id=int(record["id"]),
            rule=record["rule"],
            event=record["event"],
            clause=record["clause"],
            layer=record["layer"],
            decision=_opt_int(record.get("violated")),
            detail=_canon(
                {
                    "time": record["time"],
                    "obligations": record["obligations"],
                    "values": record["values"],
                    "conditions": record["conditions"],
                    "missing": record["missing"],
                    "context_version": record["context_version"],
                }
            ),
        )
    if kind == Kind.OBLIGATION:
        return Outcome(
            kind,
            t,
            id=int(record["id"]),
            rule=record["rule"],
            event=record["event"],
            clause=record["clause"],
            decision=int(record["decision"]),
            status=record["status"],
            at=_opt_float(record["at"]),
            late=tuple(float(x) for x in record["late"]),
            detail=_canon(
                {
                    "negated": record["negated"],
                    "start": record["start"],
                    "window": record["window"],
                    "by": record["by"],
                    "refused": record["refused"],
                    "depth": record["depth"],
                    "obligation": record["obligation"],
                }
            ),
        )
    if kind == Kind.CONTEXT:
        return Outcome(
            kind,
            t,
            id=_opt_int(record.get("version")),
            detail=_canon({"values": record["values"], "stale": record.get("stale", [])}),
        )
    if kind == Kind.LAYERS:
        return Outcome(
            kind,
            t,
            id=int(record["version"]),
            detail=_canon({"active": record["active"], "switches": record["switches"]}),
        )
    if kind == Kind.REFUSED:
        return Outcome(
            kind,
            t,
            event=record["event"],
            detail=_canon({"by": record["by"], "obligations": record["obligations"]}),
        )
    if kind == Kind.OCCURRENCE:  # an occurrence the Manager was told of
        return Outcome(kind, t, event=record["event"])
    rest = {k: v for k, v in record.items() if k not in ("kind", "time", *VOLATILE)}
    return Outcome(kind, t, detail=_canon(rest))


def _order(o: Outcome) -> tuple[float, int, int, int, str]:
    """The canonical place of ``o`` among the records of its instant.

    A decision, then its obligations in order of creation, each through its life
    (pending, its outcome, each late report); then every other record by its content
    (occurrences by name, refusals, rejections).
    """
    if o.kind == Kind.DECISION:
        return (float(o.id or 0), 0, 0, 0, "")
    if o.kind == Kind.OBLIGATION:
        stage = 0 if o.status == "pending" else 1 + len(o.late)
        return (float(o.decision or 0), 1, o.id or 0, stage, "")
    return (math.inf, 2, 0, 0, f"{o.kind} {o.event} {o.detail}")


def outcomes(records: Iterable[Mapping[str, Any]]) -> list[Outcome]:
    """The normalised stream of a run: every compared record, instants in canonical order.

    An *instant* is what one input from the driver caused: it ends where the context
    changes (a ``context`` or ``layers`` record, which the driver sends only when the
    system is quiet) or the clock moves. Instants keep their order; the records inside
    one are sorted by :func:`_order`, which does not depend on which task report reached
    the Manager first. Decisions keep their context through ``context_version`` and
    ``values``.
    """
    out: list[Outcome] = []
    instant: list[Outcome] = []

    def close() -> None:
        out.extend(sorted(instant, key=_order))
        instant.clear()

    for r in records:
        o = normalise(r)
        if o is None:
            continue
        if instant and o.time != instant[0].time:
            close()
        if o.kind in BARRIERS:
            close()
            out.append(o)
        else:
            instant.append(o)
    close()
    return out


def first_difference(expected: list[Outcome], actual: list[Outcome]) -> str | None:
    """None when the two streams are equal record by record; otherwise the first difference, in words.

    Names the position, the record before it (which places it in the scenario), both
    records (or the one missing or extra) and, for two records of one kind, each field
    that differs.
    """
    for i, (e, a) in enumerate(zip(expected, actual)):
        if e != a:
            lines = [f"record {i} differs"]
            if i:
                lines.append(f"  after:    {expected[i - 1]}")
            lines += [f"  expected: {e}", f"  actual:   {a}"]
            if e.kind == a.kind:  # the same kind of record: say which fields differ
                want, got = e.fields(), a.fields()
                for k in sorted(want.keys() | got.keys()):
                    if want.get(k) != got.get(k):
                        lines.append(f"  {k}: expected {want.get(k)!r}, actual {got.get(k)!r}")
            return "\n".join(lines)
    if len(expected) != len(actual):
        i = min(len(expected), len(actual))
        if len(actual) < len(expected):
            return f"record {i} is missing ({len(expected) - i} fewer records than expected): {expected[i]}"
        return f"record {i} is extra ({len(actual) - i} more records than expected): {actual[i]}"
    return None


def expected(steps: list[Step] | None = None) -> list[Outcome]:
    """The normalised stream of the embedded run of ``steps`` (the scripted day by default).

    The reference a run over ROS must equal: the embedded Manager on a virtual clock, in
    this process (a fraction of a second).
    """
    return outcomes(run(steps).records())


def summary(stream: Iterable[Outcome]) -> dict[str, int]:
    """Counts of a normalised stream: decisions, violations (as the Manager counts them), late events, refusals."""
    s = {"decisions": 0, "violations": 0, "late": 0, "refused": 0}
    for o in stream:
        if o.kind == Kind.DECISION:
            s["decisions"] += 1
        elif o.violation:
            s["violations"] += 1
        elif o.kind == Kind.OBLIGATION and o.late:
            s["late"] += 1
        elif o.kind == Kind.REFUSED:
            s["refused"] += 1
    return s


__all__ = ["Outcome", "expected", "first_difference", "normalise", "outcomes", "summary"]
