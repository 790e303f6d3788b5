"""The one writer of the record format: a step's records as audit lines, a record as one object.

An audit line is one JSON object on one line, compact, its keys in this order::

    {"seq":7,"kind":"decision","time":12.5,"wall":"2026-01-01T00:00:00.000000+00:00",
     "mono":8123.25,"run":"1f0c...","rules":"06700cf8c39a7f6f","id":3,"rule":"R1",...}

``seq``, ``kind`` and ``time`` are the record's; ``wall`` (UTC, microseconds), ``mono``
(:func:`time.monotonic`), ``run`` and ``rules`` (the first 16 characters of the rules'
digest) are the log's header, the same for every record of one step (readers find a step's
records by them); then the fields of the kind (:data:`cosleec.records.FIELDS`). A record
whose data has its own ``time`` (a decision's; a fallback's is its deadline) is written at
that time, with one ``time`` key. A time that is not a finite number is written as
``null``. Values JSON cannot hold are written as their ``str``.
"""

from __future__ import annotations

import datetime
import json
import math
import time as clock
from collections.abc import Iterable, Mapping
from typing import Any

try:  # the fast encoder (a dependency; where no wheel installs, json alone)
    import orjson as _orjson

    # every value orjson would write otherwise than json (a dataclass, a datetime, a subclass
    # of str, int, dict or list: a named tuple, an IntEnum) goes to ``default``, which refuses
    # it; a key that is not a str makes orjson refuse the whole
    _OPTIONS = (
        _orjson.OPT_PASSTHROUGH_DATACLASS
        | _orjson.OPT_PASSTHROUGH_DATETIME
        | _orjson.OPT_PASSTHROUGH_SUBCLASS
    )
except ImportError:  # pragma: no cover
    _orjson = None  # type: ignore[assignment]
    _OPTIONS = 0

from cosleec.records.event import RuntimeEvent
from cosleec.records.kinds import Kind


def audit_lines(
    events: Iterable[RuntimeEvent],
    *,
    run: str,
    rules: str,
    wall: str | None = None,
    mono: float | None = None,
) -> list[str]:
    """The audit lines of one step's ``events``, without newlines, in order.

    ``run`` is the Manager's run id, ``rules`` the rules' digest (its first 16 characters
    are written). ``wall`` and ``mono`` are read from the clocks once, for the whole step,
    unless given (a test gives them, to compare bytes).
    """
    if wall is None:
        wall = datetime.datetime.now(datetime.UTC).isoformat(timespec="microseconds")
    if mono is None:
        mono = clock.monotonic()
    head = f',"wall":"{wall}","mono":{mono!r},"run":"{run}","rules":"{rules[:16]}"'
    lines = []
    for ev in events:
        data, t = ev.data, ev.time
        if "time" in data:  # a decision's own time (a fallback's is its deadline) is the record's:
            data = data.copy()  # one "time" key, as a dict of the record has it, never two
            t = data.pop("time")  # (a copy then a pop: the other keys keep their order)
        body = encode(data) if ev.kind in _MADE else _json(data)
        lines.append(
            f'{{"seq":{ev.seq},"kind":"{ev.kind}","time":{_number(t)}{head}'
            + (f",{body[1:]}" if len(body) > 2 else "}")
        )
    return lines


def as_object(kind: Kind | str, time: float, data: Mapping[str, Any]) -> dict[str, Any]:
    """A record as one JSON object without the audit log's header: ``{"kind", "time", **data}``.

    The form of an MCAP message (``/cosleec/<kind>``) and of ``cosleec demo --json``; as
    in the audit log, a ``time`` of the data (a decision's own) is the record's time.
    """
    return {"kind": kind, "time": time, **data}


#: ``json.dumps(data, default=str, separators=(",", ":"))`` without making an encoder per
#: record; stateless, so shared by threads
_json = json.JSONEncoder(default=str, separators=(",", ":")).encode


#: the kinds of record the runtime makes from values it checked (finite numbers, names,
#: its own fields): written by :func:`encode`; any other (a front end's ``note``, which
#: keeps what it was given) by ``json`` alone
_MADE = frozenset(
    {
        Kind.DECISION,
        Kind.OBLIGATION,
        Kind.OCCURRENCE,
        Kind.CONTEXT,
        Kind.LAYERS,
        Kind.TASK_DONE,
        Kind.TASK_FAILED,
    }
)


def _refuse(x: object) -> object:
    raise TypeError(type(x).__name__)  # orjson would write it otherwise than json: json writes it


def encode(data: Mapping[str, Any]) -> str:
    """``data`` -- a record the runtime made, or a journal row -- as compact JSON text: what
    ``json.dumps(data, default=str, separators=(",", ":"))`` gives, ASCII only (``\\u``
    escapes), made by orjson (several times faster: a step writes several records, a
    decision's about 2 KB) where orjson writes it alike, else by ``json``: text that is
    not printable ASCII, an integer beyond 64 bits, a key that is not a ``str``, any
    value that is not a ``str``, ``int``, ``float``, ``bool``, ``None``, ``dict``,
    ``list`` or ``tuple`` itself (a subclass, a dataclass, a datetime, a path: json
    writes it, as its ``str`` where json's ``default`` does), or no orjson installed. A number reads back the same either
    way; only a float's exponent may be spelt differently (``1e16``, ``1e+16``). What the
    runtime makes from checked values never holds the two that orjson would still write
    otherwise: a float that is not finite (``null``, where json writes ``NaN``) and an
    ``Enum`` member that is not also a ``str`` or an ``int`` (its value, where json writes
    its ``str``); a record that may hold what a caller gave is written by ``json``
    (:func:`audit_lines`). ``tests/unit/test_records.py`` holds the two equal on
    generated records."""
    if _orjson is not None:
        try:
            out = _orjson.dumps(data, default=_refuse, option=_OPTIONS)
        except TypeError:  # (orjson.JSONEncodeError is one) beyond what orjson writes alike
            return _json(data)
        if out.isascii() and b"\x7f" not in out:  # (json escapes DEL too)
            return out.decode()
    return _json(data)


def _number(x: object) -> str:
    """A time as JSON: non-finite values (never from a checked clock) as null."""
    return repr(x) if isinstance(x, int | float) and math.isfinite(x) else "null"
