"""Timed traces: what happened, when -- the input of the reference semantics.

A trace is a list of :class:`Step` in non-decreasing time (seconds). A step sets measure
values (from its time on), reports one event occurrence, or only says that time has
advanced. Several steps may share a time; their order is the causal order (a value set
before an event at the same time is read by it).

Two files become traces (issue 12), both JSON Lines, one object a line:

- a written trace (:func:`read_trace`): ``{"t": 0, "set": {"assentToSupportCalls": false}}``,
  ``{"t": 0, "event": "UserFallen"}``, ``{"t": 360}``;
- the Manager's own audit log (:func:`read_audit_trace`), so a real run can be checked ex post.

:func:`read_recording` reads a file of either kind -- once, so a pipe (``/dev/stdin``,
``<(cat trace.jsonl)``) is read whole -- and tells them apart; for an audit log it also
returns the options the run used (the Manager's ``options`` record) and the semantics its
decisions were made with. :func:`read` is its steps alone. :func:`check_trace` holds a
written trace against the declarations of a specification; :func:`fit_trace` fits an audit
log to rules that may be a newer version than those it ran (what they do not declare is
dropped, and said). Every problem is a :class:`TraceError` naming ``file:line``. The audit
log's lines are read by the one reader of the record format, :mod:`cosleec.records` (a floor
below both ``semantics`` and ``runtime``: the format is shared, what a record means for the
rules is not); this module turns the records into steps.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import sys
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeGuard

from cosleec.errors import UserError, clip, show
from cosleec.lang import Reading, Specification, Unknowns, ast
from cosleec.records import (
    AuditRecord,
    Kind,
    RecordError,
    check_fields,
    load_json,
    records_in,
    seconds,
    starts_audit_log,
)

Value = bool | int | float | str  # a scale measure's value is its literal's name

KEYS = ("t", "set", "event")
"""The keys of a trace line."""

EXAMPLE = '{"t": 0, "set": {"assentToSupportCalls": false}} or {"t": 0, "event": "UserFallen"} or {"t": 360}'

STDIN = "-"
"""The name that reads the trace from standard input."""


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

    Raised by :func:`read_trace`, :func:`read_audit_trace`, :func:`read` and :func:`check_trace`;
    ``where`` is ``file:line`` (``file:line:col`` for a JSON syntax error), ``hint`` says
    how to fix the line. ``cosleec conforms`` prints it and exits 2.
    """


@dataclass(frozen=True, kw_only=True, slots=True)
class RunOptions(Reading):
    """The options a Manager ran with, as its ``options`` audit record states them: a
    :class:`~cosleec.lang.Reading` (``priorities`` are every declared pair, the rule file's
    and the Manager's), and which record said so.

    ``unknown`` is None when the record does not say (a Manager from before it did). ``line``
    and ``run`` say which record (they take no part in comparisons: two runs with equal
    options are equal).
    """

    unknown: Unknowns | None = None
    line: int = field(default=0, compare=False)
    run: str | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class Recording:
    """A trace file read once: its steps and, for a Manager's audit log, what the log says of the run.

    ``source``: the file's name in messages (``<stdin>`` for ``-``); ``audit``: the file
    is an audit log; ``options``: its last ``options`` record (None: a
    written trace, or a log from before the Manager recorded its options);
    ``options_differ``: the log holds options records that disagree (several runs, run
    differently: ``options`` is the last); ``decision_semantics``: how many ``decision``
    records were made with each clause semantics.
    """

    steps: list[Step]
    source: str = ""
    audit: bool = False
    options: RunOptions | None = None
    options_differ: bool = False
    decision_semantics: Mapping[str, int] = field(default_factory=dict)


def read_recording(path: str | Path) -> Recording:
    """A trace file or a Manager's audit log, whichever ``path`` is, read once.

    The file is read exactly once, whole, before anything is decided, so a pipe
    (``/dev/stdin``, a shell's ``<(...)``) is judged whole; ``-`` reads standard input. An
    audit log is recognised by its first record, which has ``seq`` and ``kind``; anything
    else is read as a written trace, and its errors are a trace's errors.
    """
    data = _bytes(path)
    path = _source(path)
    lines, complete = _lines(path, data)
    first = next((text for _, text in lines if text.strip()), "")
    if not starts_audit_log(first):
        return Recording(list(_trace_steps(path, lines)), path)
    reader = _AuditReader(path)
    steps = list(reader.steps(lines, complete))
    distinct = set(reader.options)
    return Recording(
        steps,
        path,
        audit=True,
        options=reader.options[-1] if reader.options else None,
        options_differ=len(distinct) > 1,
        decision_semantics=dict(reader.decision_semantics),
    )


def read(path: str | Path) -> list[Step]:
    """The steps of a trace file or of a Manager's audit log, whichever ``path`` is.

    Use it when the user may give either; :func:`read_recording` also returns what an
    audit log says of its run.
    """
    return read_recording(path).steps


def read_trace(path: str | Path) -> list[Step]:
    """The steps of a JSON Lines trace file, in file order; blank lines are skipped.

    Each line is an object with ``t`` (seconds, a finite number, never less than the line
    before) and optionally ``set`` (measure name -> true/false, a number, a scale literal's
    name, or null for unknown) and ``event`` (an event's name); ``set`` applies first.
    Raises :class:`TraceError` naming the line for anything else. Names are not checked
    against rules here: that is :func:`check_trace`.
    """
    data = _bytes(path)
    lines, _ = _lines(_source(path), data)
    return list(_trace_steps(_source(path), lines))


def read_audit_trace(path: str | Path) -> list[Step]:
    """The trace a Manager's audit log records: what it was told, and when.

    ``event`` records become event steps and ``context`` records set steps (a value that
    went stale is ``None``: unknown); every other record (decisions, obligations, tasks,
    rejections...) only advances time, so the trace ends at the last record's time. A torn
    last line -- the process crashed while writing it -- is ignored; any other line that is
    not an audit record raises :class:`TraceError`. An ``options`` record must be well
    formed (:class:`RunOptions`).
    """
    data = _bytes(path)
    lines, complete = _lines(_source(path), data)
    return list(_AuditReader(_source(path)).steps(lines, complete))


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


def fit_trace(spec: Specification, steps: Iterable[Step]) -> tuple[list[Step], list[str]]:
    """``steps`` fitted to ``spec``, and one note per kind of change (none when nothing changed).

    For an audit log checked against rules that may be a newer version than those it ran
    (issue 12): an event or a measure ``spec`` does not declare is dropped from the steps
    (a step left empty still marks the time), and a value of another type than ``spec``
    declares becomes unknown (``None``) -- not dropped, which would let the measure's
    earlier value stand past the moment it changed. A written trace is held to the rules
    instead (:func:`check_trace`).
    """
    events = {d.name for d in spec.events}
    measures = {d.name: d.type for d in spec.measures}
    unknown: dict[str, str] = {}  # name -> what it is in spec, if anything
    mistyped: dict[str, str] = {}  # measure -> its first value of the wrong type, and where
    out: list[Step] = []
    for step in steps:
        event = step.event
        if event is not None and event not in events:
            unknown.setdefault(event, " (a measure here)" if event in measures else "")
            event = None
        values: dict[str, Value | None] = {}
        for name, value in step.values.items():
            kind = measures.get(name)
            if kind is None:
                unknown.setdefault(name, " (an event here)" if name in events else "")
            elif _type_problem(kind, value):
                mistyped.setdefault(name, f"{clip(name)} ({kind}): {show(value, 40)}" + _at(step.line))
                values[name] = None
            else:
                values[name] = value
        same = event == step.event and values == step.values
        out.append(step if same else dataclasses.replace(step, event=event, values=values))
    notes = []
    if unknown:
        names = ", ".join(clip(name, 80) + unknown[name] for name in sorted(unknown))
        notes.append(f"not in these rules, ignored: {clip(names, 300)}")
    if mistyped:
        given = ", ".join(mistyped[name] for name in sorted(mistyped))
        notes.append(f"not of the type these rules declare, read as unknown: {clip(given, 300)}")
    return out, notes


# ---------------------------------------------------------------------------- reading lines


def _bytes(path: str | Path) -> bytes:
    """The whole file, read once (``-``: standard input); TraceError if it cannot be read."""
    try:
        if str(path) == STDIN:
            return sys.stdin.buffer.read()
        return Path(path).read_bytes()
    except OSError as e:
        raise TraceError(f"cannot read the trace: {e.strerror or e}", where=str(path)) from None


def _source(path: str | Path) -> str:
    """The name of ``path`` in messages."""
    return "<stdin>" if str(path) == STDIN else str(path)


def _lines(path: str, data: bytes) -> tuple[list[tuple[int, str]], bool]:
    """``(line number, text)`` for each line of ``data`` (UTF-8, a BOM allowed), and whether
    the text ends with a newline (else its last line may be torn); TraceError if not UTF-8."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise TraceError(
            "the trace is not UTF-8 text", where=f"{path}:{line}", hint="save it as UTF-8 JSON Lines"
        ) from None
    # JSON Lines separates records by "\n" only: str.splitlines would also split inside a line
    # at \x1c, \u2028 and friends, and the line numbers in messages would drift
    lines = [(n, raw.removesuffix("\r")) for n, raw in enumerate(text.split("\n"), 1)]
    return lines, not data or data.endswith(b"\n")


def _parse(path: str | Path, n: int, text: str, hint: str) -> object:
    """One line of a written trace as its JSON value; TraceError with line and column when it
    is not JSON (:func:`cosleec.records.load_json`), or when a key is given twice in one
    object (which value was meant?)."""
    try:
        return load_json(text, f"{path}:{n}", hint, hook=_no_duplicates)
    except RecordError as e:
        raise _traced(e) from None
    except _DuplicateKey as e:
        raise TraceError(
            f"the key {show(e.key)} appears twice in one object",
            where=f"{path}:{n}",
            hint="give each key once",
        ) from None


def _traced(e: RecordError) -> TraceError:
    """The record reader's refusal of a line, as this module's error (same words, place, hint)."""
    return TraceError(e.message, where=e.where, hint=e.hint)


class _DuplicateKey(Exception):  # not a ValueError: load_json lets it through
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
        if t < 0:
            raise TraceError(
                f"t is negative: {_s(t)}",
                where=where,
                hint="times are seconds from the start of the run, >= 0",
            )
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


def _time(t: object, present: bool, where: str) -> float:
    """A line's ``t`` as float seconds; TraceError unless a finite number
    (:func:`cosleec.records.seconds`, which checks an audit record's ``time`` alike)."""
    try:
        return seconds(t, present, where, "t")
    except RecordError as e:
        raise _traced(e) from None


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


class _AuditReader:
    """Reads an audit log's records into steps, collecting its ``options`` records and the
    clause semantics of its ``decision`` records on the way."""

    def __init__(self, path: str | Path) -> None:
        self.path = path
        self.options: list[RunOptions] = []
        self.decision_semantics: dict[str, int] = {}

    def steps(self, lines: Sequence[tuple[int, str]], complete: bool) -> Iterator[Step]:
        """The steps of ``lines``; ``complete``: the text ends with a newline (else the last
        line may be a write a crash cut short, and is ignored when it is not JSON)."""
        last: float | None = None
        run: str | None = None
        for rec in self._records(lines, complete):
            where = f"{self.path}:{rec.line}"
            assert rec.time is not None  # read strictly: a finite number
            t = float(rec.time) + 0.0  # -0.0 is 0
            if rec.kind in (Kind.OCCURRENCE, Kind.CONTEXT) and last is not None and t < last:
                again = " (a new run starts here)" if rec.run != run else ""
                raise TraceError(
                    f"time goes back in the audit log: {_s(t)} after {_s(last)}{again}",
                    where=where,
                    hint="check each run of the log on its own: split it where the `run` field changes",
                )
            run = rec.run
            if rec.kind == Kind.OPTIONS:
                self.options.append(_run_options(rec.to_json(), where, rec.line))
            elif rec.kind == Kind.DECISION and isinstance(rec.data.get("semantics"), str):
                name = clip(rec.data["semantics"], 40)
                self.decision_semantics[name] = self.decision_semantics.get(name, 0) + 1
            if rec.kind == Kind.OCCURRENCE:
                yield Step(t=t, event=self._checked(rec)["event"], line=rec.line)
            elif rec.kind == Kind.CONTEXT:
                yield Step(t=t, values=_values(self._checked(rec)["values"], where), line=rec.line)
            elif last is None or t > last:
                # a record at an earlier time (a fallback's decision carries its deadline) is no step back
                yield Step(t=t, line=rec.line)
            else:
                continue
            last = t if last is None else max(last, t)

    def _records(self, lines: Sequence[tuple[int, str]], complete: bool) -> Iterator[AuditRecord]:
        """The records of ``lines`` (:func:`cosleec.records.records_in`); a refused line is a TraceError."""
        try:
            yield from records_in(lines, str(self.path), complete=complete)
        except RecordError as e:
            raise _traced(e) from None

    def _checked(self, rec: AuditRecord) -> Mapping[str, Any]:
        """The fields of ``rec``, which this reader reads; TraceError unless its kind's required
        fields are there (:func:`cosleec.records.check_fields`)."""
        try:
            check_fields(rec, str(self.path))
        except RecordError as e:
            raise _traced(e) from None
        return rec.data


def _run_options(rec: Mapping[str, Any], where: str, line: int) -> RunOptions:
    """An ``options`` record's options; TraceError naming the field that is missing or wrong."""
    try:
        options = RunOptions.from_json(rec)
    except ValueError as e:
        raise TraceError(
            str(e),
            where=where,
            hint="this is not a record a Manager writes; fix the line, or delete it and give the options "
            "on the command line",
        ) from None
    run = rec.get("run")
    return dataclasses.replace(options, line=line, run=run if isinstance(run, str) else None)


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


def _at(line: int) -> str:
    return f" (line {line})" if line else ""


def _where(path: str | Path, line: int) -> str:
    if path and line:
        return f"{path}:{line}"
    return str(path) if path else (f"line {line}" if line else "")


def _kind(obj: object) -> str:
    names = {list: "a list", str: "a string", bool: "a boolean", int: "a number", float: "a number"}
    return "null" if obj is None else names.get(type(obj), type(obj).__name__)


def _s(x: float) -> str:
    """Seconds for a message: ``360``, ``0.5``, ``17873.099``."""
    if abs(x) >= 1e15:
        return f"{x:.6g}"
    return str(int(x)) if x == int(x) else f"{x:.3f}".rstrip("0").rstrip(".")
