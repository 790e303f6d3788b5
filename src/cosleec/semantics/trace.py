"""Timed traces: what happened, when -- the input of the reference semantics.

A trace is a list of :class:`Step` in non-decreasing time (seconds). A step sets measure
values (from its time on), reports one event occurrence, or only says that time has
advanced. Several steps may share a time; their order is the causal order (a value set
before an event at the same time is read by it).

Two files become traces (issue 12), both JSON Lines, one object a line:

- a written trace (:func:`read_trace`): ``{"t": 0, "set": {"assentToSupportCalls": false}}``,
  ``{"t": 0, "event": "UserFallen"}``, ``{"t": 360}``;
- the Manager's own audit log (:func:`read_audit`), so a real run can be checked ex post.

:func:`read` tells them apart, :func:`check_trace` holds a trace against the declarations of
a specification. Every problem is a :class:`TraceError` naming ``file:line``. This module
reads the audit log's records itself: ``semantics`` sits beside ``runtime`` and imports only
``lang`` (and ``errors``), so the record layout is restated here, from what
``cosleec.runtime`` writes (``Manager._commit``: ``seq``, ``kind``, ``time``, then the
record's data at the top level).
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeGuard

from cosleec.errors import UserError, clip, show
from cosleec.lang import Specification, ast

Value = bool | int | float | str  # a scale measure's value is its literal's name

KEYS = ("t", "set", "event")
"""The keys of a trace line."""

EXAMPLE = '{"t": 0, "set": {"assentToSupportCalls": false}} or {"t": 0, "event": "UserFallen"} or {"t": 360}'


@dataclass(frozen=True, slots=True)
class Step:
    """One line of a trace: at ``t``, set ``values``, and/or an ``event`` occurred.

    When a step has both, the values are set first (the event reads them). ``line`` is
    where the step came from, for messages (0: built in code). A ``None`` value makes the
    measure unknown again (an audit log's stale value).
    """

    t: float
    event: str | None = None
    values: Mapping[str, Value | None] = field(default_factory=dict)
    line: int = 0


class TraceError(UserError):
    """A trace or audit log that cannot be read, or that names what the rules do not declare.

    Raised by :func:`read_trace`, :func:`read_audit`, :func:`read` and :func:`check_trace`;
    ``where`` is ``file:line`` (``file:line:col`` for a JSON syntax error), ``hint`` says
    how to fix the line. ``cosleec conforms`` prints it and exits 2.
    """


def read(path: str | Path) -> list[Step]:
    """The steps of a trace file or of a Manager's audit log, whichever ``path`` is.

    Use it when the user may give either (``cosleec conforms``). An audit log is
    recognised by its first record, which has ``seq`` and ``kind``; anything else is read
    as a written trace, and its errors are a trace's errors.
    """
    first = _first_line(path)
    try:
        record = json.loads(first)
    except (ValueError, RecursionError):  # a torn first (and only) record still starts like one
        is_audit = first.lstrip().startswith('{"seq":')
    else:
        is_audit = isinstance(record, dict) and "seq" in record and "kind" in record
    return read_audit(path) if is_audit else read_trace(path)


def read_trace(path: str | Path) -> list[Step]:
    """The steps of a JSON Lines trace file, in file order; blank lines are skipped.

    Each line is an object with ``t`` (seconds, a finite number, never less than the line
    before) and optionally ``set`` (measure name -> true/false, a number, a scale literal's
    name, or null for unknown) and ``event`` (an event's name); ``set`` applies first.
    Raises :class:`TraceError` naming the line for anything else. Names are not checked
    against rules here: that is :func:`check_trace`.
    """
    return list(_trace_steps(path, _lines(path)))


def read_audit(path: str | Path) -> list[Step]:
    """The trace a Manager's audit log records: what it was told, and when.

    ``event`` records become event steps and ``context`` records set steps (a value that
    went stale is ``None``: unknown); every other record (decisions, obligations, tasks,
    rejections...) only advances time, so the trace ends at the last record's time. A torn
    last line -- the process crashed while writing it -- is ignored; any other line that is
    not an audit record raises :class:`TraceError`.
    """
    return list(_audit_steps(path, _lines(path)))


def check_trace(spec: Specification, steps: Iterable[Step], *, path: str | Path = "") -> None:
    """Raise :class:`TraceError` unless every name and value of ``steps`` fits ``spec``.

    Every event must be declared as an event, every measure set as a measure, and each
    value must have the measure's type (boolean: true/false; numeric: a number; scale: the
    name of one of its literals; null always). Call it before judging a trace read from a
    file, so a typo is an input error rather than a silent "conforms". ``path`` is the
    trace file, for the message's ``file:line``.
    """
    events = {d.name for d in spec.events}
    measures = {d.name: d.type for d in spec.measures}
    for step in steps:
        where = _where(path, step.line)
        if step.event is not None and step.event not in events:
            raise TraceError(
                f"event {show(step.event)} is not declared in {spec.path}",
                where=where,
                hint=_unknown_hint(step.event, events, measures, "event"),
            )
        for name, value in step.values.items():
            kind = measures.get(name)
            if kind is None:
                raise TraceError(
                    f"measure {show(name)} is not declared in {spec.path}",
                    where=where,
                    hint=_unknown_hint(name, set(measures), events, "measure"),
                )
            problem = _type_problem(kind, value)
            if problem:
                raise TraceError(
                    f"measure {clip(name)} is {kind}: {problem}", where=where, hint=_type_hint(kind)
                )


# ---------------------------------------------------------------------------- reading lines


def _lines(path: str | Path) -> list[tuple[int, str]]:
    """``(line number, text)`` for each line of the file (UTF-8, a BOM allowed); TraceError if unreadable."""
    try:
        data = Path(path).read_bytes()
    except OSError as e:
        raise TraceError(f"cannot read the trace: {e.strerror or e}", where=str(path)) from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise TraceError(
            "the trace is not UTF-8 text", where=f"{path}:{line}", hint="save it as UTF-8 JSON Lines"
        ) from None
    # JSON Lines separates records by "\n" only: str.splitlines would also split inside a line
    # at \x1c, \u2028 and friends, and the line numbers in messages would drift
    return [(n, raw.removesuffix("\r")) for n, raw in enumerate(text.split("\n"), 1)]


def _first_line(path: str | Path) -> str:
    """The first non-blank line, read alone ("" when there is none or the file cannot be
    read: the reader then reports what is wrong, with its line)."""
    try:
        with Path(path).open("rb") as fh:
            for raw in fh:
                if raw.strip():
                    return raw.decode("utf-8-sig", "replace")
    except OSError:
        pass
    return ""


def _parse(path: str | Path, n: int, text: str, hint: str, *, unique: bool = True) -> object:
    """One line's JSON value; TraceError with line and column when it is not JSON.

    ``unique``: a key given twice in one object is an error (in a trace, which value was
    meant?). Audit records are read with ``unique=False``: the Manager writes its header
    keys (``rules``: the digest) before a record's data, which may reuse a name, and the
    data's value is the one that counts (as any JSON reader takes the last).
    """
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates if unique else None)
    except json.JSONDecodeError as e:
        raise TraceError(f"not valid JSON: {e.msg}", where=f"{path}:{n}:{e.colno}", hint=hint) from None
    except _DuplicateKey as e:
        raise TraceError(
            f"the key {show(e.key)} appears twice in one object",
            where=f"{path}:{n}",
            hint="give each key once",
        ) from None
    except RecursionError:
        raise TraceError("the line is nested too deeply to read", where=f"{path}:{n}", hint=hint) from None
    except ValueError as e:  # Python's limit on integer digits
        if "integer string conversion" in str(e):
            raise TraceError(
                "a number in the line has more than 4,300 digits",
                where=f"{path}:{n}",
                hint="no time or measure needs that many; write a smaller number",
            ) from None
        raise TraceError(
            f"cannot read the line: {clip(str(e), 100)}", where=f"{path}:{n}", hint=hint
        ) from None


class _DuplicateKey(ValueError):
    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


# ---------------------------------------------------------------------------- written traces


def _trace_steps(path: str | Path, lines: Sequence[tuple[int, str]]) -> Iterator[Step]:
    last: float | None = None
    for n, text in lines:
        if not text.strip():
            continue
        where = f"{path}:{n}"
        obj = _parse(path, n, text, f"each line is one JSON object, e.g. {EXAMPLE}")
        if not isinstance(obj, dict):
            raise TraceError(
                f"a trace line is a JSON object, not {_kind(obj)}", where=where, hint=f"write e.g. {EXAMPLE}"
            )
        for key in obj:
            if key not in KEYS:
                close = difflib.get_close_matches(key, KEYS, n=1) if len(key) < 200 else []
                raise TraceError(
                    f"unknown key {show(key)}",
                    where=where,
                    hint=f"did you mean {close[0]!r}?"
                    if close
                    else 'a line has "t", and "set" and/or "event"',
                )
        t = _time(obj.get("t"), "t" in obj, where)
        if last is not None and t < last:
            raise TraceError(
                f"time goes back: t is {_s(t)}, after {_s(last)} on an earlier line",
                where=where,
                hint="times are non-decreasing: order the lines by time",
            )
        last = t
        event = obj.get("event")
        if "event" in obj and (not isinstance(event, str) or not event):
            raise TraceError(
                f'"event" is the name of an event, not {show(event)}',
                where=where,
                hint='write e.g. "event": "UserFallen"',
            )
        values: dict[str, Value | None] = {}
        if "set" in obj:
            given = obj["set"]
            if not isinstance(given, dict):
                raise TraceError(
                    f'"set" is an object of measure values, not {_kind(given)}',
                    where=where,
                    hint='write e.g. "set": {"assentToSupportCalls": false, "level": "high"}',
                )
            values = _values(given, where)
        yield Step(t=t, event=event, values=values, line=n)


def _time(t: object, present: bool, where: str, key: str = "t") -> float:
    """A line's ``t`` (an audit record's ``time``) as float seconds; TraceError unless a finite number."""
    if not present:
        raise TraceError(
            f'the line has no time "{key}"',
            where=where,
            hint=f'add "{key}": the time in seconds, e.g. {{"{key}": 0, ...}}',
        )
    if isinstance(t, bool) or not isinstance(t, int | float):
        raise TraceError(
            f'"{key}" is a number of seconds, not {show(t)}', where=where, hint=f'write e.g. "{key}": 360'
        )
    try:
        seconds = float(t)
    except OverflowError:  # an integer past a float's range
        seconds = math.inf
    if not math.isfinite(seconds):
        raise TraceError(
            f'"{key}" must be a finite number, not {show(t, 40)}',
            where=where,
            hint="give the time in seconds",
        )
    return seconds


def _values(given: Mapping[str, object], where: str) -> dict[str, Value | None]:
    """The measure values of a ``set``; TraceError for anything but bool, finite number, string, null."""
    out: dict[str, Value | None] = {}
    for name, value in given.items():
        if _is_value(value):
            out[name] = value
        else:
            raise TraceError(
                f"measure {show(name)}: {show(value)} is not a value"
                + (" (not a finite number)" if isinstance(value, int | float) else ""),
                where=where,
                hint="a value is true/false, a finite number, a scale literal's name as a string, or null (unknown)",
            )
    return out


def _is_value(x: object) -> TypeGuard[Value | None]:
    """Is ``x`` a measure value: null, a boolean, a string or a finite number?"""
    if x is None or isinstance(x, bool | str):
        return True
    return isinstance(x, int | float) and _finite(x)


def _finite(x: int | float) -> bool:
    try:
        return math.isfinite(x)
    except OverflowError:
        return False


# ---------------------------------------------------------------------------- audit logs


def _audit_steps(path: str | Path, lines: Sequence[tuple[int, str]]) -> Iterator[Step]:
    lines = [(n, text) for n, text in lines if text.strip()]
    last: float | None = None
    run: object = None
    for i, (n, text) in enumerate(lines):
        where = f"{path}:{n}"
        try:
            rec = _parse(path, n, text, "an audit log line is one record the Manager wrote", unique=False)
        except TraceError:
            if i == len(lines) - 1 and _torn(path):
                return  # the process died mid-write: the record never happened
            raise
        if not isinstance(rec, dict) or "seq" not in rec or not isinstance(rec.get("kind"), str):
            raise TraceError(
                "not an audit record (a JSON object with seq, kind and time)",
                where=where,
                hint="give either a Manager's audit log or a trace, not a mix of both",
            )
        kind: str = rec["kind"]
        t = _time(rec.get("time"), "time" in rec, where, "time")
        if kind in ("event", "context") and last is not None and t < last:
            again = " (a new run starts here)" if rec.get("run") != run else ""
            raise TraceError(
                f"time goes back in the audit log: {_s(t)} after {_s(last)}{again}",
                where=where,
                hint="check each run of the log on its own: split it where the `run` field changes",
            )
        run = rec.get("run")
        if kind == "event":
            event = rec.get("event")
            if not isinstance(event, str) or not event:
                raise TraceError(f"an event record names no event: {show(event)}", where=where)
            yield Step(t=t, event=event, line=n)
        elif kind == "context":
            values = rec.get("values")
            if not isinstance(values, dict):
                raise TraceError(f"a context record has no values: {show(values)}", where=where)
            yield Step(t=t, values=_values(values, where), line=n)
        elif last is None or t > last:
            # a record at an earlier time (a fallback's decision carries its deadline) is no step back
            yield Step(t=t, line=n)
        else:
            continue
        last = t if last is None else max(last, t)


def _torn(path: str | Path) -> bool:
    """Does the file end without a newline, as a write cut by a crash leaves it?"""
    try:
        with Path(path).open("rb") as fh:
            if fh.seek(0, 2) == 0:
                return False
            fh.seek(-1, 2)
            return fh.read(1) != b"\n"
    except OSError:
        return False


# ---------------------------------------------------------------------------- names and types


def _type_problem(kind: ast.MeasureType, value: Value | None) -> str:
    """Why ``value`` does not fit a measure of type ``kind`` ("" when it does)."""
    if value is None:
        return ""
    if isinstance(kind, ast.BooleanType):
        return "" if isinstance(value, bool) else f"give true or false, not {show(value)}"
    if isinstance(kind, ast.NumericType):
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        return "" if ok else f"give a number, not {show(value)}"
    if isinstance(value, str) and value in kind.literals:
        return ""
    return f"give one of its literals as a string, not {show(value)}"


def _type_hint(kind: ast.MeasureType) -> str:
    if isinstance(kind, ast.BooleanType):
        return 'e.g. "set": {"name": true}; null makes it unknown'
    if isinstance(kind, ast.NumericType):
        return 'e.g. "set": {"name": 42}; null makes it unknown'
    return "one of " + clip(", ".join(f'"{lit}"' for lit in kind.literals), 200) + "; null makes it unknown"


def _unknown_hint(name: str, pool: Iterable[str], other: Iterable[str], what: str) -> str:
    """A "did you mean ...?", or that ``name`` is declared as the other kind, or how to declare it."""
    if name in set(other):
        return (
            f'{clip(name)} is a measure: set it with "set": {{"{clip(name)}": ...}}'
            if what == "event"
            else f'{clip(name)} is an event: write "event": "{clip(name)}"'
        )
    close = difflib.get_close_matches(name, sorted(pool), n=1) if len(name) < 200 else []
    if close:
        return f"did you mean {close[0]!r}?"
    return f"declare `{what} {clip(name)}` in the def block, or fix the name"


def _where(path: str | Path, line: int) -> str:
    if path and line:
        return f"{path}:{line}"
    return str(path) if path else (f"line {line}" if line else "")


def _kind(obj: object) -> str:
    names = {list: "a list", str: "a string", bool: "a boolean", int: "a number", float: "a number"}
    return "null" if obj is None else names.get(type(obj), type(obj).__name__)


def _s(x: float) -> str:
    """Seconds for a message: ``360``, ``0.5``, ``17873.099``."""
    return str(int(x)) if x == int(x) and abs(x) < 1e15 else f"{x:.3f}".rstrip("0").rstrip(".")
