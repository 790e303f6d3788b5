"""The kinds of record a Manager makes: one :class:`Kind` for each, its value the ``kind`` an
audit line, an MCAP channel (``/cosleec/<kind>``) and an observer see.

The values are the format: a log written by any version is read by its ``kind`` strings,
so a value never changes. A :class:`~enum.StrEnum` member equals its value
(``Kind.DECISION == "decision"``), so code that compares with the strings keeps working.
"""

from __future__ import annotations

from enum import StrEnum


class Kind(StrEnum):
    """Every kind of runtime record, by what it says happened.

    The value of :attr:`OCCURRENCE` is ``"event"``: an *event* in SLEEC is the name
    (``event UserFallen``), the record is one occurrence of it that the Manager was told of.
    What each kind carries: :data:`cosleec.records.FIELDS`.
    """

    OPTIONS = "options"  # how the Manager was configured when it started (Manager.start)
    OCCURRENCE = "event"  # an event occurred: the Manager was told of it
    CONTEXT = "context"  # measure values changed (or went stale: unknown again)
    LAYERS = "layers"  # the active layers changed, and the switches that made it
    SEMANTICS = "semantics"  # the clause semantics was switched at run time
    DECISION = "decision"  # a rule was triggered: what it requires, and why
    OBLIGATION = "obligation"  # an obligation's new state (pending, fulfilled, violated...)
    REFUSED = "refused"  # a request for an event (or a dispatch) refused by a prohibition
    REJECTED = "rejected"  # an input refused before it reached the rules
    CONFLICT = "conflict"  # an obligation met a prohibition of the same event
    CANCELLED = "cancelled"  # a priority cancelled a rule's activation
    HELD = "held"  # a decision's dispatch waits until what it requires is allowed
    DISPATCH = "dispatch"  # a held (or changed) decision is handed on now
    WITHHELD = "withheld"  # a decision is not handed on: nothing it required is still owed
    TASK_DONE = "task-done"  # an implementation ran and returned
    TASK_FAILED = "task-failed"  # an implementation raised
    TASK_INTERRUPTED = "task-interrupted"  # a restart found a dispatch not known to have run
    RESTORED = "restored"  # the Manager started, from its journal or afresh
    RELOADED = "reloaded"  # new rules were put in force
    RELOAD_ATTEMPT = "reload-attempt"  # a Manager node was asked to reload (allowed or refused)
    DROPPED = "dropped"  # a restart or a reload let go of an obligation or a measure
    UNCOMMITTED = "uncommitted"  # records of a step never committed were set aside
    AUDIT_MISMATCH = "audit-mismatch"  # the audit log is not what the journal committed
    JOURNAL_RESET = "journal-reset"  # a journal the Manager refused was reset on purpose
    OBSERVER_REMOVED = "observer-removed"  # an observer raised and was removed


BY_VALUE: dict[str, Kind] = {k.value: k for k in Kind}
"""Each kind by its value: the member of a ``kind`` string read back (one dict lookup)."""
