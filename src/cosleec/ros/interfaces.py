"""The typed wire: node records <-> ``cosleec_interfaces`` messages, on ROS 2 and ROS 1 alike.

The nodes of :mod:`cosleec.nodes` speak in records (dicts, the audit log's form). On ROS
each cosleec topic carries a message type of the ``cosleec_interfaces`` package (built by
``scripts/setup-ros``), so that ``ros2 topic echo`` shows fields and robot code programs
against types. Every output message also carries its whole record as JSON in ``record``:
the typed fields are for programs, the record keeps the audit form lossless for tools.
Inputs (``ContextUpdate``, ``Event``, ``PermissionQuery``, ``/clock``) are read from their
typed fields alone, so a robot's own node can publish them without knowing JSON.

===================  ========================================  =========
topic                 type                                       direction
===================  ========================================  =========
``context``          ``cosleec_interfaces/ContextUpdate``       in
``events``           ``cosleec_interfaces/Event``               in
``request``          ``cosleec_interfaces/PermissionQuery``     in
``request_reply``    ``cosleec_interfaces/Permission``          out
``decisions``        ``cosleec_interfaces/Decision``            out
``obligations``      ``cosleec_interfaces/Decision``            out (to task nodes)
``violations``       ``cosleec_interfaces/Violation``           out
``conflicts``        ``cosleec_interfaces/Conflict``            out
``refusals``         ``cosleec_interfaces/Refusal``             out
``layers``           ``cosleec_interfaces/LayerState``          out, latched
``status``           ``cosleec_interfaces/Status``              out
``rejected``         ``cosleec_interfaces/Rejected``            out
``clock``            ``rosgraph_msgs/Clock`` on ``/clock``      in (``use_sim_time``)
===================  ========================================  =========

Each message's ``sender`` and ``seq`` carry the numbering :class:`~cosleec.nodes.Node` puts
on what it publishes (``_from``, ``_n``), so lost messages are counted on this wire too.
"""

from __future__ import annotations

import json
import math
import threading
from collections.abc import Callable
from typing import Any, ClassVar

from cosleec.errors import UserError
from cosleec.nodes import MessageError, dumps

#: topic name (last part) -> cosleec_interfaces message type
TYPES = {
    "context": "ContextUpdate",
    "events": "Event",
    "request": "PermissionQuery",
    "request_reply": "Permission",
    "decisions": "Decision",
    "obligations": "Decision",
    "violations": "Violation",
    "conflicts": "Conflict",
    "refusals": "Refusal",
    "layers": "LayerState",
    "status": "Status",
    "rejected": "Rejected",
}
#: the standard simulated-time topic, read when ``use_sim_time`` is on
CLOCK_TOPIC = "/clock"
CLOCK_TYPE = "rosgraph_msgs/Clock"


class InterfacesMissingError(UserError):
    """The typed wire needs the ``cosleec_interfaces`` package, which is not built here."""


def interfaces() -> tuple[Any, Any]:
    """The ``cosleec_interfaces`` msg and srv modules; :class:`InterfacesMissingError` if absent."""
    try:
        from cosleec_interfaces import msg, srv
    except ImportError:
        raise InterfacesMissingError(
            "the ROS interfaces of cosleec (cosleec_interfaces) are not built in this environment",
            hint="run `bash scripts/setup-ros`, or use `--wire json` (JSON text in std_msgs/String)",
        ) from None
    return msg, srv


def kind_of(topic: str) -> str | None:
    """The cosleec topic kind of a full topic name (``/cosleec/decisions`` -> ``decisions``), or None."""
    last = topic.rsplit("/", 1)[-1]
    return last if last in TYPES or last == "clock" else None


class Codec:
    """Encodes records into ``cosleec_interfaces`` messages and decodes them back.

    ``msg`` is the ``cosleec_interfaces.msg`` module of this middleware; ``stamp(t)``
    makes a header stamp from seconds, ``seconds(stamp)`` reads one (ROS 2 and ROS 1
    differ in their time types); ``now()`` is the wall clock for headers.
    """

    #: topic kind -> the method that fills its message / reads its message (set below)
    _encoders: ClassVar[dict[str, Callable[[Codec, Any, dict[str, Any]], None]]]
    _decoders: ClassVar[dict[str, Callable[[Codec, Any], dict[str, Any]]]]

    def __init__(
        self,
        msg: Any,
        stamp: Callable[[float], Any],
        seconds: Callable[[Any], float],
        now: Callable[[], float],
    ) -> None:
        self.msg = msg
        self.stamp = stamp
        self.seconds = seconds
        self.now = now

    def message_type(self, kind: str) -> Any:
        """The message class of topic ``kind``."""
        return getattr(self.msg, TYPES[kind])

    # ------------------------------------------------------------------ helpers
    def _header(self, m: Any) -> None:
        m.header.stamp = self.stamp(self.now())
        m.header.frame_id = ""

    def _numbered(self, m: Any, record: dict[str, Any]) -> None:
        sender, n = record.get("_from"), record.get("_n")
        m.sender = sender if isinstance(sender, str) else ""
        m.seq = n if isinstance(n, int) and not isinstance(n, bool) and 0 <= n < 2**63 else 0

    @staticmethod
    def _numbering(m: Any) -> dict[str, Any]:
        return {"_from": m.sender, "_n": int(m.seq)} if m.sender and m.seq else {}

    def value(self, name: str, v: Any) -> Any:
        """One measure value as a ``MeasureValue`` (None -> UNKNOWN)."""
        mv = self.msg.MeasureValue()
        mv.name = str(name)
        if v is None:
            mv.kind = mv.UNKNOWN
        elif isinstance(v, bool):
            mv.kind, mv.boolean = mv.BOOLEAN, v
        elif isinstance(v, int | float):
            mv.kind, mv.number = mv.NUMERIC, float(v)
        else:
            mv.kind, mv.text = mv.SCALE, str(v)
        return mv

    def values(self, items: Any) -> dict[str, Any]:
        """``MeasureValue[]`` -> ``{name: value}``; MessageError for a kind that is no value
        (UNKNOWN, or none of the four) or a name given twice."""
        out: dict[str, Any] = {}
        for mv in items:
            if mv.name in out:
                raise MessageError(f"measure {mv.name!r} is given twice in one update")
            if mv.kind == mv.BOOLEAN:
                out[mv.name] = bool(mv.boolean)
            elif mv.kind == mv.NUMERIC:
                out[mv.name] = _number(float(mv.number))
            elif mv.kind == mv.SCALE:
                out[mv.name] = str(mv.text)
            elif mv.kind == mv.UNKNOWN:  # outputs say "no value" so; an input cannot unset one
                raise MessageError(
                    f"measure {mv.name!r} has kind UNKNOWN: a value cannot be set to unknown; "
                    "leave it out, or give the Manager a max_age after which it forgets a value"
                )
            else:
                raise MessageError(
                    f"measure {mv.name!r} has kind {mv.kind}; kinds are 0 unknown, 1 boolean, 2 numeric, 3 scale"
                )
        return out

    def _obligation(self, o: dict[str, Any], parent: Any, decision: int = 0, at: Any = None) -> Any:
        """An ``Obligation`` inside ``parent`` (a Decision or Violation): it shares the parent's
        stamp, and its record is the parent's. A decision's items give their window from the
        trigger (``at``), a tracked obligation on the Manager's clock."""
        m = self.msg.Obligation()
        m.header.stamp = parent.header.stamp
        nested = o.get("obligation")
        inner: dict[str, Any] = nested if isinstance(nested, dict) else o
        m.id = int(o["id"]) if "obligation" in o and isinstance(o.get("id"), int) else 0
        m.decision = int(o.get("decision") or decision or 0)
        m.rule = str(o.get("rule") or inner.get("rule") or "")
        m.event = str(o.get("event") or inner.get("event") or "")
        m.prohibition = bool(o.get("negated", inner.get("negated", False)))
        window = o.get("window")
        if isinstance(window, list) and len(window) == 2:
            lo, hi = window
        else:  # an item of a decision: from its trigger
            base = float(at) if isinstance(at, int | float) else 0.0
            lo, hi = inner.get("from_s"), inner.get("within_s")
            lo = base + lo if isinstance(lo, int | float) else base
            hi = base + hi if isinstance(hi, int | float) else None
        m.window_start = float(lo) if isinstance(lo, int | float) else 0.0
        deadline = o.get("deadline", hi)
        m.deadline = float(deadline) if isinstance(deadline, int | float) else math.inf
        m.status = str(o.get("status") or "")
        return m

    # ------------------------------------------------------------------ encode
    def encode(self, kind: str, record: dict[str, Any]) -> Any:
        """The message for ``record`` on a topic of ``kind`` (KeyError for a kind with no type)."""
        m = self.message_type(kind)()
        self._header(m)
        self._numbered(m, record)
        clean = {k: v for k, v in record.items() if k not in ("_from", "_n")}
        self._encoders[kind](self, m, clean)
        return m

    def _encode_context(self, m: Any, r: dict[str, Any]) -> None:
        m.values = [self.value(k, v) for k, v in (r.get("values") or {}).items()]

    def _encode_events(self, m: Any, r: dict[str, Any]) -> None:
        m.event = str(r.get("event", ""))
        m.values = [self.value(k, v) for k, v in (r.get("values") or {}).items()]

    def _encode_request(self, m: Any, r: dict[str, Any]) -> None:
        m.id, m.event, m.source = str(r.get("id", "")), str(r.get("event", "")), str(r.get("source", ""))

    def _encode_request_reply(self, m: Any, r: dict[str, Any]) -> None:
        m.id, m.event = str(r.get("id", "")), str(r.get("event", ""))
        m.permitted = bool(r.get("allowed"))
        m.rules = [str(x) for x in r.get("rules", [])]
        m.reason = str(r.get("reason", ""))

    def _encode_decisions(self, m: Any, r: dict[str, Any]) -> None:
        m.id = int(r.get("id") or 0)
        m.session = str(r.get("session", ""))
        m.trigger = str(r.get("event", ""))
        m.rule = str(r.get("rule", ""))
        clause = r.get("clause")
        m.clause = -1 if clause is None else int(clause)
        m.layer = str(r.get("layer") or "")
        m.semantics = str(r.get("semantics", ""))
        m.values = [self.value(k, v) for k, v in (r.get("values") or {}).items()]
        m.obligations = [self._obligation(o, m, m.id, r.get("time")) for o in r.get("obligations", [])]
        m.missing = [str(x) for x in r.get("missing", [])]
        m.explanation = str(r.get("explanation") or r.get("reason") or "")
        m.record = dumps(r)

    def _encode_violations(self, m: Any, r: dict[str, Any]) -> None:
        m.obligation = self._obligation(r, m)
        m.rule = str(r.get("rule", ""))
        m.event = str(r.get("event", ""))
        m.late = bool(r.get("late"))
        m.explanation = str(r.get("explanation", "")) or _violation_text(r)
        m.record = dumps(r)

    def _encode_conflicts(self, m: Any, r: dict[str, Any]) -> None:
        m.event = str(r.get("event", ""))
        m.rules = [str(x) for x in r.get("between", [])]
        m.obligations = [int(x) for x in (r.get("obligation"), r.get("prohibition")) if isinstance(x, int)]
        m.resolution = str(r.get("resolution", ""))
        m.explanation = str(r.get("explanation", ""))
        m.record = dumps(r)

    def _encode_refusals(self, m: Any, r: dict[str, Any]) -> None:
        m.event = str(r.get("event", ""))
        m.rules = [str(x) for x in r.get("by", [])]
        m.reason = str(r.get("reason", ""))
        m.source = str(r.get("source", ""))
        m.record = dumps(r)

    def _encode_layers(self, m: Any, r: dict[str, Any]) -> None:
        m.active = [str(x) for x in r.get("active", [])]
        switches = []
        for s in r.get("switches", []):
            sw = self.msg.LayerSwitch()
            sw.rule, sw.previous, sw.current = str(s["rule"]), str(s["from"] or ""), str(s["to"] or "")
            switches.append(sw)
        m.switches = switches
        m.semantics = str(r.get("semantics", ""))
        m.version = int(r.get("version") or 0)
        m.record = dumps(r)

    def _encode_status(self, m: Any, r: dict[str, Any]) -> None:
        m.node = str(r.get("node", ""))
        m.session = str(r.get("session", ""))
        m.executor_alive = bool(r.get("executor_alive", True))
        counters = []
        for k, v in (r.get("counters") or {}).items():
            c = self.msg.Counter()
            c.name, c.value = str(k), int(v)
            counters.append(c)
        m.counters = counters
        m.record = dumps(r)

    def _encode_rejected(self, m: Any, r: dict[str, Any]) -> None:
        m.node, m.topic = str(r.get("node", "")), str(r.get("topic", ""))
        m.reason, m.payload = str(r.get("reason", "")), str(r.get("payload", ""))

    # ------------------------------------------------------------------ decode
    def decode(self, kind: str, m: Any) -> dict[str, Any]:
        """The record a message on a topic of ``kind`` carries; MessageError when it cannot be read.

        Outputs are read from their ``record``; inputs from their typed fields.
        """
        out = self._decoders.get(kind)
        if out is None:  # an output: its record is the whole of it
            record = getattr(m, "record", "")
            if not record:
                raise MessageError(f"a {TYPES[kind]} message without its `record` cannot be read here")
            parsed = json.loads(record)
            if not isinstance(parsed, dict):
                raise MessageError("`record` must hold a JSON object")
            return {**parsed, **self._numbering(m)}
        result: dict[str, Any] = out(self, m)
        return {**result, **self._numbering(m)}

    def _decode_context(self, m: Any) -> dict[str, Any]:
        return {"values": self.values(m.values)}

    def _decode_events(self, m: Any) -> dict[str, Any]:
        if m.values:
            return {"event": m.event, "values": self.values(m.values)}
        return {"event": m.event}

    def _decode_request(self, m: Any) -> dict[str, Any]:
        return {"id": m.id, "event": m.event, "source": m.source}

    def _decode_request_reply(self, m: Any) -> dict[str, Any]:
        out: dict[str, Any] = {"id": m.id, "event": m.event, "allowed": bool(m.permitted)}
        if m.rules:
            out["rules"] = list(m.rules)
        if m.reason:
            out["reason"] = m.reason
        return out

    def _decode_rejected(self, m: Any) -> dict[str, Any]:
        return {"node": m.node, "topic": m.topic, "reason": m.reason, "payload": m.payload}

    def clock(self, m: Any) -> dict[str, Any]:
        """A ``rosgraph_msgs/Clock`` as the Manager's clock record ``{"t": seconds}``."""
        return {"t": self.seconds(m.clock)}

    def decision(self, r: dict[str, Any]) -> Any:
        """A decision record as a ``Decision`` (for the Decide service's answer)."""
        m = self.msg.Decision()
        self._header(m)
        self._encode_decisions(m, r)
        return m


Codec._encoders = {
    "context": Codec._encode_context,
    "events": Codec._encode_events,
    "request": Codec._encode_request,
    "request_reply": Codec._encode_request_reply,
    "decisions": Codec._encode_decisions,
    "obligations": Codec._encode_decisions,
    "violations": Codec._encode_violations,
    "conflicts": Codec._encode_conflicts,
    "refusals": Codec._encode_refusals,
    "layers": Codec._encode_layers,
    "status": Codec._encode_status,
    "rejected": Codec._encode_rejected,
}
# inputs are read from their typed fields; every other kind from its `record`
Codec._decoders = {
    "context": Codec._decode_context,
    "events": Codec._decode_events,
    "request": Codec._decode_request,
    "request_reply": Codec._decode_request_reply,
    "rejected": Codec._decode_rejected,
}

#: service kind -> cosleec_interfaces service type
SERVICES = {"request": "AskPermission", "decide": "Decide", "reload": "Reload"}


class ServiceCodec:
    """Service requests and responses <-> dicts, for the Manager's ``~/request``, ``~/decide``
    and ``~/reload`` services and their clients (the guard). ``srv`` is the
    ``cosleec_interfaces.srv`` module, ``codec`` the :class:`Codec` of the same middleware."""

    def __init__(self, srv: Any, codec: Codec) -> None:
        self.srv = srv
        self.codec = codec

    def service_type(self, kind: str) -> Any:
        """The service class of ``kind`` (request, decide, reload)."""
        return getattr(self.srv, SERVICES[kind])

    def read_request(self, kind: str, req: Any) -> dict[str, Any]:
        """A service request as the dict the node's handler takes (MessageError if unreadable)."""
        if kind == "request":
            return {"event": req.event, "source": req.source}
        if kind == "decide":
            return {"values": self.codec.values(req.values), "event": req.event}
        return {"rules": req.rules}

    def fill_response(self, kind: str, resp: Any, answer: dict[str, Any]) -> Any:
        """Write the handler's ``answer`` into the response object ``resp``; returns it."""
        if kind == "request":
            resp.permitted = bool(answer.get("permitted"))
            resp.rules = [str(r) for r in answer.get("rules", [])]
            resp.reason = str(answer.get("reason", ""))
        elif kind == "decide":
            resp.accepted = bool(answer.get("accepted"))
            resp.error = str(answer.get("error", ""))
            resp.decisions = [self.codec.decision(d) for d in answer.get("decisions", [])]
        else:
            resp.success = bool(answer.get("success"))
            resp.message = str(answer.get("message", ""))
            resp.previous_hash = str(answer.get("previous_hash", ""))
            resp.current_hash = str(answer.get("current_hash", ""))
        return resp

    def make_request(self, kind: str, fields: dict[str, Any]) -> Any:
        """A request object of ``kind`` from ``fields`` (a client's side)."""
        cls = self.service_type(kind)
        req = getattr(cls, "Request", None) or getattr(self.srv, f"{SERVICES[kind]}Request")
        r = req()
        if kind == "decide":
            r.values = [self.codec.value(k, v) for k, v in (fields.get("values") or {}).items()]
            r.event = str(fields.get("event", ""))
        else:
            for k, v in fields.items():
                setattr(r, k, v)
        return r

    def read_response(self, kind: str, resp: Any) -> dict[str, Any]:
        """A response object as a dict (a client's side)."""
        if kind == "request":
            return {"permitted": bool(resp.permitted), "rules": list(resp.rules), "reason": resp.reason}
        if kind == "decide":
            return {
                "accepted": bool(resp.accepted),
                "error": resp.error,
                "decisions": [json.loads(d.record) for d in resp.decisions if d.record],
            }
        return {
            "success": bool(resp.success),
            "message": resp.message,
            "previous_hash": resp.previous_hash,
            "current_hash": resp.current_hash,
        }


class Once:
    """Calls ``fn`` the first time only (an answer, or the timeout that stands in for one)."""

    def __init__(self, fn: Callable[[Any], None]) -> None:
        self.fn = fn
        self.done = False
        self.lock = threading.Lock()

    def __call__(self, value: Any) -> None:
        """Pass ``value`` on, unless something was passed on already."""
        with self.lock:
            if self.done:
                return
            self.done = True
        self.fn(value)


def record_of(message: dict[str, Any] | str) -> dict[str, Any]:
    """A record given as a dict or as JSON text, as a dict (ValueError if not a JSON object)."""
    if isinstance(message, str):
        parsed = json.loads(message)
        if not isinstance(parsed, dict):
            raise ValueError("expected a JSON object")
        return parsed
    return message


def failure(kind: str, error: Exception) -> dict[str, Any]:
    """The answer a service gives when its handler failed: never "permitted" (fail closed)."""
    why = f"{type(error).__name__}: {error}"
    if kind == "request":
        return {"permitted": False, "rules": [], "reason": f"the Manager could not decide: {why}"}
    if kind == "decide":
        return {"accepted": False, "error": why, "decisions": []}
    return {"success": False, "message": why}


def _number(x: float) -> float | int:
    """A whole number as an int (as JSON carries it), so a record reads the same on every wire."""
    return int(x) if x.is_integer() and abs(x) < 2**53 else x


def _violation_text(r: dict[str, Any]) -> str:
    what = r.get("event", "?")
    rule = r.get("rule", "?")
    if r.get("late"):
        return f"{rule}: {what} came after its deadline"
    return f"{rule}: {'a forbidden ' if r.get('negated') else ''}{what} obligation was violated"
