"""The marks of a run's timeline: what :class:`~cosleec.views.timeline.Timeline` holds and both renderers draw.

A measure's :class:`Series`, a rule's layer :class:`Band`, a :class:`Marker` for something
that happened at one time, an obligation's :class:`Bar` with its :class:`Outcome`, and the
:class:`Link` of an ``otherwise`` chain. Plain records, built by
:mod:`cosleec.views.timeline` from the runtime's records.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import StrEnum

Value = bool | int | float | str
"""A measure's value as records carry it (a scale measure's is its literal's name)."""

UNDETERMINED = "?"
"""The layer name of a rule whose clause could not be chosen (a measure had no value)."""


class Outcome(StrEnum):
    """What became of an obligation, as its bar is coloured."""

    PENDING = "pending"  # still owed when the run ended
    FULFILLED = "fulfilled"
    RESPECTED = "respected"  # a prohibition whose window passed without the event
    VIOLATED = "violated"
    LATE = "late"  # violated, and the event came after the deadline
    BLOCKED = "blocked"  # a prohibition forbade its whole window (a conflict the prohibition won)
    REFUSED = "blocked"  # the old name of BLOCKED (an alias)
    CONFLICT = "conflict"  # in a conflict that did not end it blocked, violated or late
    CANCELLED = "cancelled"  # a higher rule's priority
    WITHDRAWN = "withdrawn"  # a reload removed its rule
    OTHER = "other"  # a status this version does not know (the bar's label says which)


class MarkerKind(StrEnum):
    """What a :class:`Marker` marks."""

    TRIGGER = "trigger"  # an event occurred
    DECISION = "decision"  # a rule decided, at its default or a layer
    UNDETERMINED = "undetermined"  # a rule decided without a clause (a measure had no value)
    OTHERWISE = "otherwise"  # the fallback of a missed obligation
    REFUSED = "refused"  # a request for an event a prohibition forbids
    REJECTED = "rejected"  # an update or event the Manager did not take
    CONFLICT = "conflict"  # an obligation met a prohibition
    CANCELLED = "cancelled"  # a rule's activation cancelled by a priority
    HELD = "held"  # a decision waits until its events are allowed
    WITHHELD = "withheld"  # a decision that never ran: nothing it required was still owed
    TASK_FAILED = "task-failed"
    TASK_INTERRUPTED = "task-interrupted"  # decided before a crash, perhaps never run
    NOTE = "note"  # about the whole run: a semantics switch, a reload, a restart...


@dataclass(frozen=True, kw_only=True, slots=True)
class Series:
    """A measure's values over time: ``points`` ``(time, value)``, each in force until the next.

    Only changes are kept; ``None`` is unknown (before its first value, or stale).
    """

    name: str
    points: tuple[tuple[float, Value | None], ...]

    @property
    def changes(self) -> int:
        """How many times the value was set to a new one."""
        return len(self.points)


@dataclass(frozen=True, kw_only=True, slots=True)
class Band:
    """Rule ``rule``'s layer ``layer`` (``R1.1``, or ``?`` undetermined) active over ``[start, end)``."""

    rule: str
    layer: str
    start: float
    end: float

    @property
    def clause(self) -> int | None:
        """The clause the layer stands for (``R1.2`` -> 2); None when undetermined."""
        tail = self.layer.rsplit(".", 1)[-1]
        return int(tail) if tail.isdigit() else None


@dataclass(frozen=True, kw_only=True, slots=True)
class Marker:
    """Something that happened at ``time``: on rule ``rule``'s lane, or the run's (``rule`` None).

    ``label`` is short (drawn next to it); ``detail`` says all (a tooltip).
    """

    kind: MarkerKind
    time: float
    rule: str | None
    label: str
    detail: str


@dataclass(frozen=True, kw_only=True, slots=True)
class Bar:
    """One obligation (or prohibition, ``negated``) from its trigger ``start`` to ``end``.

    ``end`` is its deadline; with none (an untimed response) the time it was settled, else
    the end of the run (``open``). ``at``: when it was settled (None: pending); ``late``:
    the event that came after a missed deadline. ``key`` is ``(run, id)``: a log of runs
    that do not continue one another numbers each run's obligations anew.
    """

    key: tuple[int, int]
    rule: str
    event: str
    negated: bool
    start: float
    end: float
    deadline: float | None
    outcome: Outcome
    status: str
    at: float | None
    late: float | None
    decision: int
    clause: int | None
    depth: int  # 0: from a decision; n: the n-th otherwise down a chain
    open: bool = False

    @property
    def id(self) -> int:
        """The obligation's id, as the runtime numbered it."""
        return self.key[1]

    @property
    def label(self) -> str:
        """``not E`` or ``E``, with the obligation's id: what the bar is about."""
        return f"{'not ' if self.negated else ''}{self.event} #{self.id}"


@dataclass(frozen=True, kw_only=True, slots=True)
class Link:
    """An ``otherwise`` chain: obligation ``parent`` was missed at ``time``; its fallback put ``child`` in force."""

    parent: tuple[int, int]
    child: tuple[int, int]
    time: float


def natural(name: str) -> tuple[tuple[int, int | str], ...]:
    """The sort key that puts ``R2`` before ``R10``: digits compare as numbers."""
    return tuple((0, int(part)) if part.isdigit() else (1, part) for part in re.split(r"(\d+)", name) if part)
