"""What each kind of record carries: its fields, their JSON types, and which a reader may rely on.

A record is ``kind``, ``time`` and the fields of its kind. In the audit log each line also
starts with the log's header (:data:`HEADER`: ``seq``, ``wall``, ``mono``, ``run``,
``rules``), then the fields at the top level of the same object.

:data:`FIELDS` is the definition, kind by kind. A *required* field is part of the kind's
contract: a record without it (or with it of another type) is malformed, and a reader that
checks the kind (:func:`problem`) refuses it. An *optional* field is written by today's
Manager too, but a reader must do without it (logs of older versions lack it); its type is
checked only on request (``optional=True``). Fields not listed here are not refused: a
newer Manager may add some.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import Enum
from typing import Any, NamedTuple

from cosleec.errors import show
from cosleec.records.kinds import BY_VALUE, Kind

HEADER = ("seq", "kind", "time", "wall", "mono", "run", "rules")
"""The keys an audit line starts with, in this order: the record's number, kind and time,
then the log's header (UTC wall time and monotonic time of the step, the run's id, the
first 16 characters of the rules' digest)."""


class Json(Enum):
    """A JSON type a field may hold, as :func:`json.loads` gives it (a boolean is no number)."""

    NAME = "a non-empty string"
    TEXT = "a string"
    INT = "a whole number"
    NUMBER = "a number"
    BOOL = "true or false"
    LIST = "a list"
    OBJECT = "an object"
    NULL = "null"
    ANY = "any value"

    def holds(self, value: object) -> bool:
        """Is ``value`` of this type?"""
        if self is Json.ANY:
            return True
        if self is Json.NULL:
            return value is None
        if isinstance(value, bool) != (self is Json.BOOL):  # JSON true is not the number 1
            return False
        return isinstance(value, _PYTHON[self]) and not (self is Json.NAME and value == "")


_PYTHON: dict[Json, type | tuple[type, ...]] = {
    Json.NAME: str,
    Json.TEXT: str,
    Json.INT: int,
    Json.NUMBER: (int, float),
    Json.BOOL: bool,
    Json.LIST: list,
    Json.OBJECT: dict,
}


class Field(NamedTuple):
    """One field of a kind: its key, the types it may hold, whether a reader may rely on it,
    and what a record lacking it "has not" (``names no event``), for the message."""

    name: str
    types: tuple[Json, ...]
    required: bool
    bad: str = ""


def _need(name: str, *types: Json, bad: str = "") -> Field:
    return Field(name, types, True, bad)


def _may(name: str, *types: Json) -> Field:
    return Field(name, types, False)


_TASK = (  # task-done and task-failed: one implementation run of a decision
    _need("rule", Json.NAME),
    _need("decision", Json.INT),
    _may("clause", Json.INT, Json.NULL),
    _may("what", Json.TEXT),  # task, capability or fallback
    _may("event", Json.TEXT, Json.NULL),  # the event a capability performs
    _may("error", Json.TEXT, Json.NULL),
    _may("checked", Json.INT),  # the seq of the last record before the dispatch was admitted
)

FIELDS: Mapping[Kind, tuple[Field, ...]] = {
    Kind.OPTIONS: (
        _need("semantics", Json.TEXT),  # last-wins or nested
        _may("unknown", Json.TEXT),  # how a condition over a measure with no value reads
        _need("untimed", Json.TEXT, Json.NUMBER),  # "none", "immediate" or seconds
        _need("priorities", Json.LIST),  # [higher, lower] rule pairs
        _need("priority_semantics", Json.TEXT),
        _need("priority_lead", Json.NUMBER),
    ),
    Kind.OCCURRENCE: (
        _need("event", Json.NAME, bad="names no event"),
        _may("causal", Json.INT),  # its place in the causal order of occurrences
    ),
    Kind.CONTEXT: (
        _need("values", Json.OBJECT, bad="has no values"),  # measure -> value (null: unknown)
        _may("version", Json.INT),
        _may("stale", Json.LIST),  # the measures whose values went stale
    ),
    Kind.LAYERS: (
        _need("active", Json.LIST),
        _need("switches", Json.LIST),  # {"rule", "from", "to"}
        _may("semantics", Json.TEXT),
        _need("version", Json.INT),
    ),
    Kind.SEMANTICS: (
        _need("semantics", Json.TEXT),
        _may("before", Json.LIST),  # the active layers before the switch
        _may("active", Json.LIST),  # and after it
    ),
    Kind.DECISION: (  # Decision.to_json, its "time" the record's time
        _need("id", Json.INT),
        _need("rule", Json.NAME),
        _need("event", Json.NAME),  # the trigger ("otherwise" for a fallback)
        _need("clause", Json.INT, Json.NULL),  # 0: the default; None: undetermined
        _may("type", Json.TEXT),
        _may("layer", Json.TEXT, Json.NULL),
        _may("semantics", Json.TEXT),
        _may("values", Json.OBJECT),
        _may("conditions", Json.LIST),
        _may("obligations", Json.LIST),
        _may("missing", Json.LIST),
        _may("reason", Json.TEXT),
        _may("explanation", Json.TEXT),
        _may("for_people", Json.TEXT),  # what the robot says to people (Decision.for_people)
        _may("context_version", Json.INT),
        _may("violated", Json.INT, Json.NULL),  # the missed obligation a fallback answers
        _may("unknowns", Json.TEXT),
        _may("origin", Json.TEXT),  # trigger, or otherwise (a fallback)
        _may("missed", Json.OBJECT, Json.NULL),  # a fallback's missed obligation
        _may("dispatch", Json.TEXT),  # held or withheld, when it was not handed on at once
    ),
    Kind.OBLIGATION: (  # Tracked.to_json
        _need("id", Json.INT),
        _need("decision", Json.INT),
        _need("rule", Json.NAME),
        _need("event", Json.NAME),
        _need("status", Json.TEXT),  # pending, fulfilled, violated, respected, refused...
        _need("start", Json.NUMBER),
        _may("deadline", Json.NUMBER, Json.NULL),
        _may("at", Json.NUMBER, Json.NULL),  # when it was settled
        _may("type", Json.TEXT),
        _may("clause", Json.INT, Json.NULL),
        _may("causal", Json.INT),
        _may("obligation", Json.OBJECT),
        _may("negated", Json.BOOL),  # a prohibition
        _may("window", Json.LIST),
        _may("instance", Json.INT),
        _may("by", Json.TEXT, Json.NULL),  # the event that settled it
        _may("late", Json.LIST),  # when the event came after the violation
        _may("refused", Json.INT),
        _may("depth", Json.INT),
        _may("branches", Json.LIST),
        _may("met", Json.LIST),
    ),
    Kind.REFUSED: (
        _need("event", Json.NAME),
        _need("by", Json.LIST),  # the rules whose prohibitions forbid it
        _may("obligations", Json.LIST),
        _may("reason", Json.TEXT),
        _may("source", Json.TEXT),
    ),
    Kind.REJECTED: (
        _need("reason", Json.TEXT),
        _may("what", Json.TEXT),
        _may("hint", Json.TEXT),
        _may("update", Json.OBJECT),
        _may("topic", Json.TEXT),
        _may("payload", Json.ANY),
        _may("caller", Json.TEXT),
    ),
    Kind.CONFLICT: (
        _need("event", Json.NAME),
        _need("obligation", Json.INT),
        _need("prohibition", Json.INT),
        _need("between", Json.LIST),  # the obligation's rule, the prohibition's
        _may("at", Json.NUMBER),
        _may("clauses", Json.LIST),
        _may("resolution", Json.TEXT),
        _may("winner", Json.TEXT, Json.NULL),
        _may("explanation", Json.TEXT),
    ),
    Kind.CANCELLED: (
        _need("rule", Json.NAME),
        _may("instance", Json.INT),
        _may("by", Json.TEXT),
        _may("at", Json.NUMBER),
        _may("priority", Json.TEXT),
        _may("obligations", Json.LIST),
    ),
    Kind.HELD: (
        _need("decision", Json.INT),
        _need("rule", Json.NAME),
        _may("events", Json.LIST),
        _may("by", Json.LIST),
        _may("opens", Json.NUMBER, Json.NULL),
    ),
    Kind.DISPATCH: (_need("decision", Json.OBJECT),),  # the decision record handed on
    Kind.WITHHELD: (
        _need("decision", Json.INT),
        _need("rule", Json.NAME),
        _may("reason", Json.TEXT),
    ),
    Kind.TASK_DONE: _TASK,
    Kind.TASK_FAILED: _TASK,
    Kind.TASK_INTERRUPTED: (
        _need("reason", Json.TEXT),
        _may("decision", Json.INT),
        _may("rule", Json.TEXT),
        _may("event", Json.TEXT, Json.NULL),
    ),
    Kind.RESTORED: (
        _need("from", Json.TEXT, Json.NULL),  # the run restored (None: a fresh start)
        _may("lineage", Json.TEXT, Json.NULL),
        _may("rules_changed", Json.BOOL),
        _may("context", Json.LIST),
        _may("obligations", Json.INT),
        _may("dropped", Json.INT),
        _may("interrupted", Json.INT),
        _may("shift", Json.NUMBER),
    ),
    Kind.RELOADED: (
        _need("previous_hash", Json.TEXT),
        _need("current_hash", Json.TEXT),
        *(
            _may(name, Json.LIST)
            for name in (
                "added",
                "removed",
                "changed",
                "withdrawn",
                "relinked",
                "withheld",
                "measures_added",
                "measures_removed",
                "priorities",
            )
        ),
    ),
    Kind.RELOAD_ATTEMPT: (
        _need("via", Json.TEXT),
        _need("outcome", Json.TEXT),
        _may("caller", Json.TEXT, Json.NULL),
        _may("path", Json.TEXT, Json.NULL),
        _may("previous_hash", Json.TEXT),
        _may("current_hash", Json.TEXT),
        _may("file", Json.TEXT),
        _may("reason", Json.TEXT),
    ),
    Kind.DROPPED: (_need("what", Json.TEXT),),
    Kind.UNCOMMITTED: (
        _need("records", Json.INT),
        _may("first", Json.INT, Json.NULL),
        _may("last", Json.INT, Json.NULL),
        _may("to", Json.TEXT, Json.NULL),
    ),
    Kind.AUDIT_MISMATCH: (_need("reason", Json.TEXT),),
    Kind.JOURNAL_RESET: (
        _need("reason", Json.TEXT),
        _may("lineage", Json.TEXT, Json.NULL),
        _may("last_seq", Json.INT, Json.NULL),
        _may("journal", Json.OBJECT, Json.NULL),
    ),
    Kind.OBSERVER_REMOVED: (_need("observer", Json.TEXT), _need("reason", Json.TEXT)),
}
"""The fields of each kind of record (see the module's note on required and optional)."""


def problem(kind: str, data: Mapping[str, Any], *, optional: bool = False) -> str | None:
    """What is wrong with the fields ``data`` of a record of ``kind``; None when nothing is.

    A required field must be there with one of its types; with ``optional``, an optional
    field that is there must have one of its types too. A kind this version does not know
    has nothing to check. The answer names the kind, the field and the value found:
    ``an event record names no event: None``.
    """
    known = BY_VALUE.get(kind)
    if known is None:
        return None
    for f in FIELDS[known]:
        value = data.get(f.name)
        if f.name not in data:
            if f.required:
                return _say(known, f, value)
        elif (f.required or optional) and not any(t.holds(value) for t in f.types):
            return _say(known, f, value)
    return None


def _say(kind: Kind, f: Field, value: object) -> str:
    article = "an" if kind[0] in "aeiou" else "a"
    lack = f.bad or f"has no {f.name} ({' or '.join(t.value for t in f.types)})"
    return f"{article} {kind} record {lack}: {show(value)}"
