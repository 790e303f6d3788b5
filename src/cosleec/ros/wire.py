"""What a cosleec topic looks like on the wire: the half of a transport ROS 2 and ROS 1 share.

A node publishes records on cosleec topics (``/cosleec/decisions``). On the typed wire (the
default) each topic carries its ``cosleec_interfaces`` type and simulated time comes from
the standard ``/clock``; on the JSON wire every topic carries JSON text in
``std_msgs/String`` (the clock too, on ``<namespace>/clock``). :class:`Wire` decides, for
a topic, the name and type on the wire, turns a record into the message to send and a
received message into what the node's handler takes; the transports add only how their
middleware publishes and subscribes.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import Handler, dumps
from cosleec.ros.interfaces import (
    CLOCK_TOPIC,
    CLOCK_TYPE,
    Codec,
    ServiceCodec,
    interfaces,
    kind_of,
    record_of,
)
from cosleec.ros.messages import message_class

WIRES = ("typed", "json")


class Wire:
    """The wire form of cosleec topics for one transport.

    ``mode`` is ``"typed"`` or ``"json"`` (it may be changed later, for topics not yet
    advertised or subscribed); ``string`` is the middleware's ``std_msgs/String`` class;
    ``stamp(t)`` and ``seconds(stamp)`` convert between seconds and its time type. The
    interfaces are loaded at once on the typed wire, so a missing build fails at start-up
    with the fix (:class:`~cosleec.ros.interfaces.InterfacesMissingError`).
    """

    def __init__(
        self, mode: str, string: Any, stamp: Callable[[float], Any], seconds: Callable[[Any], float]
    ) -> None:
        if mode not in WIRES:
            raise UserError(f"wire {mode!r} is not one of {', '.join(WIRES)}")
        self.mode = mode
        self.string = string
        self.stamp = stamp
        self.seconds = seconds
        self._services: ServiceCodec | None = None
        if mode == "typed":
            self.services()

    def services(self) -> ServiceCodec:
        """The service codec (services are typed whatever the wire of the topics)."""
        if self._services is None:
            msg, srv = interfaces()
            self._services = ServiceCodec(srv, Codec(msg, self.stamp, self.seconds, time.time))
        return self._services

    @property
    def codec(self) -> Codec:
        """The typed wire's codec (loaded on first use: the JSON wire does without)."""
        return self.services().codec

    def route(self, topic: str) -> tuple[str, Any, str | None]:
        """(name on the wire, message class, cosleec kind or None for JSON text) of ``topic``."""
        kind = kind_of(topic) if self.mode == "typed" else None
        if kind == "clock":
            return CLOCK_TOPIC, message_class(CLOCK_TYPE), "clock"
        if kind is not None:
            return topic, self.codec.message_type(kind), kind
        return topic, self.string, None

    def outgoing(self, topic: str, message: dict[str, Any] | str) -> Any:
        """The message that carries ``message`` (a record, or JSON text of one) on ``topic``."""
        _, cls, kind = self.route(topic)
        if kind == "clock":
            return cls(clock=self.stamp(float(record_of(message)["t"])))
        if kind is None:
            return self.string(data=message if isinstance(message, str) else dumps(message))
        return self.codec.encode(kind, record_of(message))

    def incoming(self, topic: str, handler: Handler) -> Callable[[Any], None]:
        """The callback that hands each message on ``topic`` to ``handler``: JSON text, or (typed
        wire) a function that decodes the record, so the receiving node rejects what cannot be
        read; a clock as ``{"t": seconds}``."""
        _, _, kind = self.route(topic)
        if kind == "clock":
            seconds = self.seconds

            def clock(m: Any) -> None:
                handler({"t": seconds(m.clock)})

            return clock
        if kind is None:

            def text(m: Any) -> None:
                handler(m.data)

            return text
        codec = self.codec

        def typed(m: Any) -> None:
            handler(lambda: codec.decode(kind, m))

        return typed

    def diagnostics(self, fields: dict[str, Any]) -> Any:
        """A ``diagnostic_msgs/DiagnosticArray`` of one status (:class:`~cosleec.ros.diagnostics.Diagnostics`'s
        ``{"name", "level", "message", "values"}``), stamped now."""
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        level = fields["level"]  # a `byte` field: bytes on ROS 2, an int on ROS 1
        status = DiagnosticStatus(
            level=bytes([level]) if isinstance(DiagnosticStatus.OK, bytes) else level,
            name=fields["name"],
            message=fields["message"],
            hardware_id="",
            values=[KeyValue(key=k, value=v) for k, v in fields["values"]],
        )
        arr = DiagnosticArray(status=[status])
        arr.header.stamp = self.stamp(time.time())
        return arr


def is_status(topic: str) -> bool:
    """Does ``topic`` carry a node's status (summarised on ``/diagnostics`` too)?"""
    return topic.rsplit("/", 1)[-1] == "status"
