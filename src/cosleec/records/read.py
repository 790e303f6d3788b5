"""The one reader of the record format: audit lines back into typed records.

:func:`read_records` reads an audit log file, :func:`records_in` lines already read (what
``cosleec conforms`` does, which reads a file once, pipes included). Each line is checked:
it is JSON (else ``file:line:col``), an object with an integer ``seq``, a string ``kind``
and a finite ``time`` (else ``file:line``), and becomes an :class:`AuditRecord`. Two
tolerances, as the log is written:

- a *torn* last line -- the text does not end with a newline and its last line is not
  JSON: the process died writing it, the record never happened -- is skipped;
- ``lenient=True`` (the runtime's own :func:`cosleec.runtime.read_audit`) skips every line
  that is not a record instead of refusing it, and keeps a ``null`` time (what the writer
  makes of a time that is not finite).

The fields of a kind are checked only on request (:func:`check_fields`): a reader checks
the kinds it reads, so an older log whose other records lack a field is still read.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeGuard

from cosleec.errors import UserError, clip, show
from cosleec.records.fields import HEADER, problem
from cosleec.records.kinds import BY_VALUE, Kind

LINE_HINT = "an audit log line is one record the Manager wrote"
"""The hint of a line that is not JSON."""


class RecordError(UserError):
    """A line of an audit log that is not a record; ``where`` is ``file:line`` (``file:line:col``
    for a JSON syntax error), ``hint`` how to fix it."""


@dataclass(frozen=True, slots=True)
class AuditRecord:
    """One record of an audit log, read back: its number, kind and time, the log's header,
    and the fields of its kind (``data``, the rest of the line's object).

    ``kind`` is a :class:`Kind`, or the string of a kind this version does not know.
    ``time`` is the number the line gives (a finite one; None only when read leniently from
    a ``null``). ``run``, ``rules``, ``wall`` and ``mono`` are None when the line lacks them
    (or holds another type there: such a value stays in ``data``). ``line`` is the line it
    was read from (0: not from a file).
    """

    seq: int
    kind: Kind | str
    time: float | None
    data: Mapping[str, Any] = field(default_factory=dict)
    run: str | None = None
    rules: str | None = None
    wall: str | None = None
    mono: float | None = None
    line: int = 0

    def to_json(self) -> dict[str, Any]:
        """The record as the line's JSON object (what :func:`json.loads` of the line gives)."""
        out: dict[str, Any] = {"seq": self.seq, "kind": str(self.kind), "time": self.time}
        for key in ("wall", "mono", "run", "rules"):
            value = getattr(self, key)
            if value is not None:
                out[key] = value
        out.update(self.data)
        return out


def read_records(path: str | Path, *, lenient: bool = False) -> list[AuditRecord]:
    """Every record of the audit log at ``path``, in order (see the module's note).

    OSError when the file cannot be read; RecordError for a line that is not a record
    (unless ``lenient``) and, unless ``lenient``, for a file that is not UTF-8 text.
    """
    data = Path(path).read_bytes()
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        if lenient:
            text = data.decode("utf-8-sig", "replace")
        else:
            line = data.count(b"\n", 0, e.start) + 1
            raise RecordError("the audit log is not UTF-8 text", where=f"{path}:{line}") from None
    lines = [(n, raw.removesuffix("\r")) for n, raw in enumerate(text.split("\n"), 1)]
    return list(records_in(lines, str(path), complete=text.endswith("\n"), lenient=lenient))


def records_in(
    lines: Iterable[tuple[int, str]], source: str, *, complete: bool = True, lenient: bool = False
) -> Iterator[AuditRecord]:
    """The records of numbered ``lines`` of ``source`` (blank lines skipped); ``complete``:
    the text ended with a newline (else its last line may be torn)."""
    numbered = [(n, text) for n, text in lines if text.strip()]
    for i, (n, text) in enumerate(numbered):
        where = f"{source}:{n}"
        try:
            obj = load_json(text, where, LINE_HINT)
        except RecordError:
            if lenient:
                continue
            if i == len(numbered) - 1 and not complete:
                return  # the process died mid-write: the record never happened
            raise
        record = _record(obj, where, n, lenient)
        if record is not None:
            yield record


def check_fields(record: AuditRecord, source: str) -> None:
    """Refuse ``record`` (RecordError at ``source:line``) unless it has the required fields of
    its kind (:data:`cosleec.records.FIELDS`)."""
    said = problem(record.kind, record.data)
    if said is not None:
        raise RecordError(said, where=f"{source}:{record.line}")


def starts_audit_log(first: str) -> bool:
    """Is ``first``, the first non-blank line of a file, the first record of an audit log?

    An object with ``seq`` and ``kind``, or a torn line that starts like one (a log whose
    only record a crash cut short); anything else is not an audit log.
    """
    try:
        obj = json.loads(first)
    except (ValueError, RecursionError):
        return first.lstrip().startswith('{"seq":')
    return isinstance(obj, dict) and "seq" in obj and "kind" in obj


def load_json(
    text: str, where: str, hint: str, *, hook: Callable[[list[tuple[str, Any]]], Any] | None = None
) -> object:
    """One line's JSON value; RecordError at ``where`` (``:col`` added for a syntax error).

    ``hook`` is :func:`json.loads`'s ``object_pairs_hook``; an exception it raises that is
    not a ValueError reaches the caller as it is.
    """
    try:
        return json.loads(text, object_pairs_hook=hook)
    except json.JSONDecodeError as e:
        raise RecordError(f"not valid JSON: {e.msg}", where=f"{where}:{e.colno}", hint=hint) from None
    except RecursionError:
        raise RecordError("the line is nested too deeply to read", where=where, hint=hint) from None
    except ValueError as e:  # Python's limit on integer digits
        if "integer string conversion" in str(e):
            raise RecordError(
                "a number in the line has more than 4,300 digits",
                where=where,
                hint="no time or measure needs that many; write a smaller number",
            ) from None
        raise RecordError(f"cannot read the line: {clip(str(e), 100)}", where=where, hint=hint) from None


def seconds(t: object, present: bool, where: str, key: str) -> float:
    """A line's time ``key`` as float seconds; RecordError unless it is there as a finite number."""
    if not present:
        raise RecordError(
            f'the line has no time "{key}"',
            where=where,
            hint=f'add "{key}": the time in seconds, e.g. {{"{key}": 0, ...}}',
        )
    if isinstance(t, bool) or not isinstance(t, int | float):
        raise RecordError(
            f'"{key}" is a number of seconds, not {show(t)}', where=where, hint=f'write e.g. "{key}": 360'
        )
    try:
        value = float(t)
    except OverflowError:  # an integer past a float's range
        value = math.inf
    if not math.isfinite(value):
        raise RecordError(
            f'"{key}" must be a finite number, not {show(t, 40)}',
            where=where,
            hint="give the time in seconds",
        )
    return value + 0.0  # -0.0 is 0


_NOT_A_RECORD = "not an audit record (a JSON object with seq, kind and time)"


def _record(obj: object, where: str, line: int, lenient: bool) -> AuditRecord | None:
    """The record of one line's JSON value; None (lenient) or RecordError when it is none."""
    seq = obj.get("seq") if isinstance(obj, dict) else None
    kind = obj.get("kind") if isinstance(obj, dict) else None
    if not isinstance(obj, dict) or not isinstance(kind, str) or not _whole(seq):
        if lenient:
            return None
        raise RecordError(
            _NOT_A_RECORD, where=where, hint="give either a Manager's audit log or a trace, not a mix of both"
        )
    t = obj.get("time")
    null = lenient and t is None and "time" in obj  # what the writer makes of a non-finite time
    if not null:
        try:
            seconds(t, "time" in obj, where, "time")
        except RecordError:
            if lenient:
                return None
            raise
    data = {k: v for k, v in obj.items() if k not in HEADER}
    return AuditRecord(
        seq=seq,
        kind=BY_VALUE.get(kind, kind),
        time=t,
        data=data,
        run=_take(obj, "run", str, data),
        rules=_take(obj, "rules", str, data),
        wall=_take(obj, "wall", str, data),
        mono=_take(obj, "mono", (int, float), data),
        line=line,
    )


def _whole(x: object) -> TypeGuard[int]:
    """Is ``x`` a whole number (JSON true is none)?"""
    return isinstance(x, int) and not isinstance(x, bool)


def _take(obj: Mapping[str, Any], key: str, types: type | tuple[type, ...], data: dict[str, Any]) -> Any:
    """The header value ``key`` when it has the header's type; otherwise kept in ``data`` (a
    field of the record's kind that reuses the name) and None."""
    if key not in obj:
        return None
    value = obj[key]
    if isinstance(value, types) and not isinstance(value, bool):
        return value
    data[key] = value
    return None
