"""The records of a run: what observers hear and the audit log keeps, one per state change.

Defined here, below both :mod:`cosleec.runtime` (which writes them) and
:mod:`cosleec.semantics` (which reads an audit log back to judge it), so that both name the
same thing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class RuntimeEvent:
    """What observers (terminal display, ROS publishers, the audit log, tests) are told, in order.

    ``kind`` is one of options, event, context, layers, semantics, decision, obligation,
    refused, rejected, conflict, cancelled, held, dispatch, withheld, task-done, task-failed,
    task-interrupted, restored, reloaded, reload-attempt, dropped, uncommitted, audit-mismatch,
    journal-reset. ``seq`` numbers the records of one Manager (continued across restarts with a journal, or from
    the audit log it appends to); 0 when nothing records.
    """

    kind: str
    time: float
    data: dict[str, Any] = field(default_factory=dict)
    seq: int = 0

    @classmethod
    def made(cls, kind: str, time: float, data: dict[str, Any], seq: int) -> RuntimeEvent:
        """The same as the constructor with every field given, for the Manager's hot path
        (a frozen dataclass sets each field through ``object.__setattr__``; a decision with
        observers makes several records)."""
        ev = object.__new__(cls)
        ev.__dict__.update(kind=kind, time=time, data=data, seq=seq)
        return ev
