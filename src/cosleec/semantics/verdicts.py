"""What the reference semantics says about a trace: firings, verdicts and conflicts.

These records are the vocabulary ``cosleec conforms`` prints and the differential test
compares with the runtime's own records. Statuses:

- an obligation (``E within T``) ends ``fulfilled`` (at the occurrence), ``violated`` (at
  its deadline), ``blocked`` (its whole window is forbidden by another rule's prohibition
  and no priority settles the conflict: violated by conflict, at the moment the conflict
  arises, and its ``otherwise`` starts then) or ``cancelled`` (by a higher rule's
  priority), or stays ``pending`` (it can still be met);
- a prohibition (``not E within T``) ends ``respected`` (when its window closes),
  ``violated`` (at the forbidden occurrence) or ``cancelled``, or stays ``pending``.

One meaning per word, the same in ``Manager.stats``, the audit log and ``cosleec
conforms``: a *violation* is a verdict that makes the run not conform -- ``violated`` or
``blocked`` (:data:`BREACHES`; ``stats["violations"]`` counts both); *refused* is only ever
an attempt (``Manager.request``, a dispatch) a prohibition did not permit -- a ``refused``
record, ``stats["refused"]`` -- never a verdict. Before issue 33 ``blocked`` was called
``refused``: :func:`status` reads the old name (an old audit log, a saved ``--json``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

PENDING = "pending"
FULFILLED = "fulfilled"
RESPECTED = "respected"
VIOLATED = "violated"
BLOCKED = "blocked"
CANCELLED = "cancelled"
REFUSED = BLOCKED
"""The old name of :data:`BLOCKED` (its value is ``"blocked"`` now): kept for importers."""

BREACHES = frozenset({VIOLATED, BLOCKED})  # the violations: the outcomes that make a trace not conform
OLD_NAMES = {"refused": BLOCKED}  # statuses renamed: what an old record's status means now


def status(word: str) -> str:
    """A verdict status as it is named now: ``refused`` (an obligation's status before issue
    33) is ``blocked``; any other word is itself."""
    return OLD_NAMES.get(word, word)


@dataclass(frozen=True, slots=True)
class Firing:
    """One occurrence of a rule's trigger and what the rule made of it.

    ``fired`` is the trigger condition's value (None: a measure it reads has no value);
    ``clause`` the clause that applies (0: the default response, i: ``unless`` clause i,
    None: the rule did not fire or could not be decided, see ``missing``). ``step`` is the
    trace step (0-based) of the occurrence; ``instance`` numbers the rule's activation (its
    obligations carry it).
    """

    step: int
    time: float
    rule: str
    event: str
    fired: bool | None
    clause: int | None
    instance: int | None
    missing: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """A plain dict for ``--json``."""
        return {
            "step": self.step,
            "time": self.time,
            "rule": self.rule,
            "event": self.event,
            "fired": self.fired,
            "clause": self.clause,
            "instance": self.instance,
            "missing": list(self.missing),
        }


@dataclass(slots=True)
class Verdict:
    """One obligation or prohibition an activation imposed, and what became of it.

    ``key`` names the response item it comes from (``Rule1:0``; ``Rule1.2:0/o:0`` is the
    first item of the ``otherwise`` of clause 2's first item); ``window`` is absolute
    ``(lo, hi)`` in trace seconds, ``hi`` None for no deadline. ``by`` says what settled it:
    the occurring event, or for ``blocked``/``cancelled`` the rule whose prohibition or
    priority did. ``depth`` counts ``otherwise`` steps down a chain (0: from the trigger).
    """

    id: int
    instance: int
    rule: str
    clause: int
    key: str
    event: str
    negated: bool
    start: float
    window: tuple[float, float | None]
    depth: int = 0
    status: str = PENDING
    at: float | None = None
    by: str | None = None
    alternatives: tuple[tuple[tuple[str, float, float | None], ...], ...] = ()
    note: str = ""

    @property
    def breach(self) -> bool:
        """True when this verdict is a violation: it makes the trace not conform (violated or blocked)."""
        return self.status in BREACHES

    def describe(self) -> str:
        """``not CallSupport in [0, 600]`` -- the item with its absolute window."""
        lo, hi = self.window
        w = f"[{_n(lo)}, {_n(hi)}]" if hi is not None else f"from {_n(lo)} on"
        return f"{'not ' if self.negated else ''}{self.event} in {w}"

    def to_json(self) -> dict[str, Any]:
        """A plain dict for ``--json`` (and the differential test)."""
        return {
            "id": self.id,
            "instance": self.instance,
            "rule": self.rule,
            "clause": self.clause,
            "key": self.key,
            "event": self.event,
            "negated": self.negated,
            "start": self.start,
            "window": list(self.window),
            "depth": self.depth,
            "status": self.status,
            "at": self.at,
            "by": self.by,
            "note": self.note,
        }


@dataclass(frozen=True, slots=True)
class Conflict:
    """The moment the rules owed ``event`` and forbade it in overlapping windows.

    ``obligation`` and ``prohibition`` are verdict ids; ``resolution`` says how it was
    settled: ``prohibition-wins`` (no priority: the obligation is blocked), ``deferred``
    (the obligation's window outlasts the prohibition: the robot waits), ``cancel`` or
    ``conflict-aware`` (a declared priority).
    """

    time: float
    event: str
    obligation: int
    prohibition: int
    rules: tuple[str, str]  # (the obligation's rule, the prohibition's rule)
    clauses: tuple[int, int]
    resolution: str
    winner: str | None = None  # the rule that prevails, when one does

    def to_json(self) -> dict[str, Any]:
        """A plain dict for ``--json``."""
        return {
            "time": self.time,
            "event": self.event,
            "obligation": self.obligation,
            "prohibition": self.prohibition,
            "rules": list(self.rules),
            "clauses": list(self.clauses),
            "resolution": self.resolution,
            "winner": self.winner,
        }


@dataclass
class Judgement:
    """The reference verdicts on a trace, up to its last time ``end``."""

    end: float
    firings: list[Firing] = field(default_factory=list)
    verdicts: list[Verdict] = field(default_factory=list)
    conflicts: list[Conflict] = field(default_factory=list)
    undetermined: list[str] = field(default_factory=list)  # otherwise fallbacks that could not start

    @property
    def breaches(self) -> list[Verdict]:
        """The violations (violated and blocked obligations and prohibitions), in time order."""
        return sorted((v for v in self.verdicts if v.breach), key=lambda v: (v.at or 0.0, v.id))

    @property
    def pending(self) -> list[Verdict]:
        """What the trace leaves open: obligations and prohibitions still in force at ``end``."""
        return [v for v in self.verdicts if v.status == PENDING]

    @property
    def conforms(self) -> bool:
        """True when nothing is violated or blocked up to ``end`` (pending items are fine)."""
        return not any(v.breach for v in self.verdicts)

    def to_json(self) -> dict[str, Any]:
        """The whole judgement as one JSON document."""
        return {
            "conforms": self.conforms,
            "violations": len(self.breaches),  # as Manager.stats["violations"] counts them
            "end": self.end,
            "firings": [f.to_json() for f in self.firings],
            "verdicts": [v.to_json() for v in self.verdicts],
            "conflicts": [c.to_json() for c in self.conflicts],
            "undetermined": list(self.undetermined),
        }


def _n(x: float) -> str:
    return f"{x:g}"
