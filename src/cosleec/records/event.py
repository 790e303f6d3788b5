"""The record observers hear: :class:`RuntimeEvent`, one per state change, in order."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from cosleec.records.kinds import Kind


@dataclass(frozen=True)
class RuntimeEvent:
    """What observers (terminal display, ROS publishers, the audit log, tests) are told, in order.

    ``kind`` says what happened (:class:`Kind`; it equals its string, ``ev.kind ==
    "decision"``); ``data`` carries the fields of that kind (:data:`cosleec.records.FIELDS`;
    a decision's ``time`` is its own, which the audit log makes the record's time).
    ``seq`` numbers the records of one Manager (continued across restarts with a journal,
    or from the audit log it appends to); 0 when nothing records.
    """

    kind: Kind
    time: float
    data: dict[str, Any] = field(default_factory=dict)
    seq: int = 0

    @classmethod
    def made(cls, kind: Kind, time: float, data: dict[str, Any], seq: int) -> RuntimeEvent:
        """The same as the constructor with every field given, for the Manager's hot path
        (a frozen dataclass sets each field through ``object.__setattr__``; a decision with
        observers makes several records). ``kind`` is taken as given: no conversion."""
        ev = object.__new__(cls)
        ev.__dict__.update(kind=kind, time=time, data=data, seq=seq)
        return ev
