"""Stats: what a Manager has counted since it started (:attr:`Manager.stats <cosleec.runtime.Manager.stats>`).

A typed record, so a view, the Manager node's status and the demo's summary read the same
fields; it also reads as a mapping (``stats["refused"]``, ``dict(stats)``), the way it
was read before it had a type.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, fields


@dataclass(slots=True)
class Stats:
    """Counts since the Manager started (not kept across restarts).

    ``updates``: context updates applied; ``rejected``: inputs refused (an update, an
    unknown event, what a front end noted); ``events``: occurrences; ``decisions``:
    decisions made (``otherwise`` ones included); ``refused``: real attempts a prohibition
    did not permit -- ``request`` calls and dispatches, one per ``refused`` audit record
    (:meth:`~cosleec.runtime.Manager.permission`, a question, counts nothing);
    ``violations``: obligations and prohibitions that ended ``violated`` or ``blocked``
    (violated by conflict), counted as ``cosleec conforms`` counts its violations;
    ``undetermined``: decisions an unknown value left undetermined; ``task_failures``:
    implementations that failed; ``conflicts``: conflicts met; ``cancelled``: activations
    a priority cancelled.
    """

    updates: int = 0
    rejected: int = 0
    events: int = 0
    decisions: int = 0
    refused: int = 0
    violations: int = 0
    undetermined: int = 0
    task_failures: int = 0
    conflicts: int = 0
    cancelled: int = 0

    def __getitem__(self, name: str) -> int:
        if name not in _NAMES:
            raise KeyError(name)
        value: int = getattr(self, name)
        return value

    def keys(self) -> tuple[str, ...]:
        """The counters' names, in order (so that ``dict(stats)`` works)."""
        return _NAMES

    def __iter__(self) -> Iterator[str]:
        return iter(_NAMES)

    def to_json(self) -> dict[str, int]:
        """Every counter by name (a status message, a view)."""
        return {n: getattr(self, n) for n in _NAMES}


_NAMES = tuple(f.name for f in fields(Stats))
