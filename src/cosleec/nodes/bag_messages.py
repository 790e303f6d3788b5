"""A runtime record as the ROS 2 message a recording holds: typed where ``cosleec_interfaces``
has a type that carries the whole record, ``std_msgs/String`` (the record as JSON) otherwise.

=================  =====================================
record kind        message type
=================  =====================================
``decision``       ``cosleec_interfaces/msg/Decision``
``obligation``     ``cosleec_interfaces/msg/Obligation``
``conflict``       ``cosleec_interfaces/msg/Conflict``
``refused``        ``cosleec_interfaces/msg/Refusal``
``layers``         ``cosleec_interfaces/msg/LayerState``
any other kind     ``std_msgs/msg/String``
=================  =====================================

Every message holds the record whole, as the JSON copy writes it (``{"kind", "time", ...}``:
:func:`cosleec.records.as_object`): in ``record`` (the typed ones) or ``data`` (a
``String``), so reading a recording back loses nothing. The typed fields are filled as the
typed wire fills the same types (:mod:`cosleec.ros.interfaces`), for Foxglove, PlotJuggler
and robot code. ``ContextUpdate``, ``Event`` and ``Rejected`` have no ``record`` field, so
``context``, ``event`` and ``rejected`` records are written as ``String``: a typed one
would lose the fields they have no place for (a context's ``version`` and ``stale``...).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import Any

from cosleec.nodes.bag_types import RosTypes

TEXT = "std_msgs/msg/String"
"""The type of a record whose kind has no typed message: its JSON in ``data``."""

TYPES = {
    "decision": "cosleec_interfaces/msg/Decision",
    "obligation": "cosleec_interfaces/msg/Obligation",
    "conflict": "cosleec_interfaces/msg/Conflict",
    "refused": "cosleec_interfaces/msg/Refusal",
    "layers": "cosleec_interfaces/msg/LayerState",
}
"""Record kind -> its typed message; every other kind is written as :data:`TEXT`."""

RECORD_FIELDS = ("record", "data")
"""The fields a recorded message holds its record in (JSON text)."""


def type_of(kind: str) -> str:
    """The message type a record of ``kind`` is recorded as."""
    return TYPES.get(kind, TEXT)


def encode(types: RosTypes, kind: str, stamp_ns: int, record: dict[str, Any]) -> tuple[str, Any]:
    """(type, message) for ``record`` (a whole record, with ``kind`` and ``time``) stamped ``stamp_ns``."""
    text = json.dumps(record, default=str)
    typename = type_of(kind)
    if typename == TEXT:
        return typename, types.make(TEXT, data=text)
    header = types.make(
        "std_msgs/msg/Header",
        stamp=types.make("builtin_interfaces/msg/Time", sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9),
    )
    fields = _FILL[kind](types, header, record)
    return typename, types.make(typename, header=header, record=text, **fields)


def record_of(message: Any) -> dict[str, Any] | None:
    """The record a recorded message holds (its ``record`` or ``data`` field), or None if it holds none."""
    for name in RECORD_FIELDS:
        text = getattr(message, name, None)
        if isinstance(text, str) and text:
            try:
                parsed = json.loads(text)
            except ValueError:
                return None
            return parsed if isinstance(parsed, dict) else None
    return None


# ---------------------------------------------------------------------- typed fields
def _uint(x: Any) -> int:
    return x if isinstance(x, int) and not isinstance(x, bool) and 0 <= x < 2**64 else 0


def _float(x: Any, default: float = 0.0) -> float:
    return float(x) if isinstance(x, int | float) and not isinstance(x, bool) else default


def _strings(xs: Any) -> list[str]:
    return [str(x) for x in xs] if isinstance(xs, list) else []


def _value(types: RosTypes, name: str, v: Any) -> Any:
    """One measure value as a ``MeasureValue`` (None -> UNKNOWN), as the typed wire writes it."""
    mv = "cosleec_interfaces/msg/MeasureValue"
    if v is None:
        return types.make(mv, name=str(name), kind=0)
    if isinstance(v, bool):
        return types.make(mv, name=str(name), kind=1, boolean=v)
    if isinstance(v, int | float):
        return types.make(mv, name=str(name), kind=2, number=float(v))
    return types.make(mv, name=str(name), kind=3, text=str(v))


def _values(types: RosTypes, values: Any) -> list[Any]:
    return [_value(types, k, v) for k, v in values.items()] if isinstance(values, dict) else []


def _item(types: RosTypes, header: Any, o: Any, decision: dict[str, Any]) -> Any:
    """An obligation ``decision`` requires, its window from the decision's trigger."""
    o = o if isinstance(o, dict) else {}
    at = _float(decision.get("time"))
    lo, hi = o.get("from_s"), o.get("within_s")
    return types.make(
        "cosleec_interfaces/msg/Obligation",
        header=header,
        decision=_uint(decision.get("id")),
        rule=str(o.get("rule") or decision.get("rule") or ""),
        event=str(o.get("event") or ""),
        prohibition=bool(o.get("negated", False)),
        window_start=at + _float(lo),
        deadline=at + hi if isinstance(hi, int | float) and not isinstance(hi, bool) else math.inf,
    )


def _decision(types: RosTypes, header: Any, r: dict[str, Any]) -> dict[str, Any]:
    clause = r.get("clause")
    return {
        "id": _uint(r.get("id")),
        "session": str(r.get("session") or ""),
        "trigger": str(r.get("event") or ""),
        "rule": str(r.get("rule") or ""),
        "clause": clause if isinstance(clause, int) and -(2**31) <= clause < 2**31 else -1,
        "layer": str(r.get("layer") or ""),
        "semantics": str(r.get("semantics") or ""),
        "values": _values(types, r.get("values")),
        "obligations": [_item(types, header, o, r) for o in r.get("obligations") or []],
        "missing": _strings(r.get("missing")),
        "explanation": str(r.get("explanation") or r.get("reason") or ""),
    }


def _obligation(types: RosTypes, header: Any, r: dict[str, Any]) -> dict[str, Any]:
    return {
        "id": _uint(r.get("id")),
        "decision": _uint(r.get("decision")),
        "rule": str(r.get("rule") or ""),
        "event": str(r.get("event") or ""),
        "prohibition": bool(r.get("negated", False)),
        "window_start": _float(r.get("start")),
        "deadline": _float(r.get("deadline"), math.inf),
        "status": str(r.get("status") or ""),
    }


def _conflict(types: RosTypes, header: Any, r: dict[str, Any]) -> dict[str, Any]:
    ids = [_uint(r.get(k)) for k in ("obligation", "prohibition") if isinstance(r.get(k), int)]
    return {
        "event": str(r.get("event") or ""),
        "rules": _strings(r.get("between")),
        "obligations": ids,
        "resolution": str(r.get("resolution") or ""),
        "explanation": str(r.get("explanation") or ""),
    }


def _refused(types: RosTypes, header: Any, r: dict[str, Any]) -> dict[str, Any]:
    return {
        "event": str(r.get("event") or ""),
        "rules": _strings(r.get("by")),
        "reason": str(r.get("reason") or ""),
        "source": str(r.get("source") or ""),
    }


def _layers(types: RosTypes, header: Any, r: dict[str, Any]) -> dict[str, Any]:
    switches = [
        types.make(
            "cosleec_interfaces/msg/LayerSwitch",
            rule=str(s.get("rule") or ""),
            previous=str(s.get("from") or ""),
            current=str(s.get("to") or ""),
        )
        for s in r.get("switches") or []
        if isinstance(s, dict)
    ]
    return {
        "active": _strings(r.get("active")),
        "switches": switches,
        "semantics": str(r.get("semantics") or ""),
        "version": _uint(r.get("version")),
    }


_FILL: dict[str, Callable[[RosTypes, Any, dict[str, Any]], dict[str, Any]]] = {
    "decision": _decision,
    "obligation": _obligation,
    "conflict": _conflict,
    "refused": _refused,
    "layers": _layers,
}
