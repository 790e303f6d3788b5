"""How cosleec nodes talk: a small transport interface, and an in-process implementation.

The node logic (``cosleec.nodes``) is written against :class:`Transport` only; ROS 2 and
ROS 1 adapters live in ``cosleec.ros`` and are the only code that imports rclpy or rospy.
Nodes publish records (dicts). The transport chooses the wire: on ROS, typed
``cosleec_interfaces`` messages by default (:mod:`cosleec.ros.interfaces`), or JSON text in
``std_msgs/String`` for tools without the types; in one process, JSON text. A handler
receives the record as a dict, or as JSON text that the node parses itself -- so a
malformed message is rejected, logged and counted by the receiver either way.

Topics, under a namespace (default ``/cosleec``):

===================  =====  ==========================================================
topic                 dir    payload
===================  =====  ==========================================================
``context``          in     ``{"values": {measure: value, ...}}`` (atomic update)
``events``           in     ``{"event": name}`` (a trigger, or a response that happened)
``request``          in     ``{"id": str, "event": name}`` (may a task do it now?)
``request_reply``    out    ``{"id", "event", "allowed": bool, "rules", "reason"}``
``clock``            in     ``{"t": seconds}`` (simulated time; ``/clock`` on ROS)
``decisions``        out    a decision record (rule, clause, layer, values, explanation)
``obligations``      out    a decision that chose a clause, for the task nodes (same record)
``violations``       out    an obligation that was violated (or a late event)
``conflicts``        out    rules that oblige and forbid one event, and the resolution
``refusals``         out    an action refused while a prohibition holds, with the rules
``layers``           out    ``{"active": [...], "switches": [...]}`` -- latched
``status``           out    a node's counters: every 0.5 s, and on change (``Node.status_each``)
``rejected``         out    ``{"node", "topic", "reason", "payload"}`` for every bad message
===================  =====  ==========================================================
"""

from __future__ import annotations

import json
import logging
import queue
import threading
from collections.abc import Callable
from typing import Any, Protocol

from cosleec.nodes.qos import Qos

log = logging.getLogger("cosleec.nodes")

DEFAULT_NAMESPACE = "/cosleec"
LATCHED = frozenset({"layers"})

#: a topic handler gets the record as a dict (typed wire) or as JSON text (the node parses it)
Handler = Callable[[Any], None]


def topic(namespace: str, name: str) -> str:
    """The topic ``name`` under ``namespace``, with one slash between them (``/cosleec/events``)."""
    return f"{namespace.rstrip('/')}/{name}"


class Transport(Protocol):
    """What a node needs from a middleware: publish and subscribe records on cosleec topics,
    and subscribe to the robot's own typed topics (delivered as a dict of the message fields)."""

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        """Send ``message`` (a record, or JSON text of one) on ``topic``."""
        ...

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler(record or JSON text)`` for every message on ``topic``, on a thread of the transport."""
        ...

    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        """Call ``handler(fields)`` for every ``type_name`` message (``std_msgs/Float64``) on ``topic``.

        For the robot's own topics, which the Context Listener reads; ``qos`` as the
        mapping says (:class:`~cosleec.nodes.qos.Qos`; None: reliable).
        """
        ...

    def advertise(self, topic: str, latched: bool = False) -> None:
        """Declare a topic this node publishes; ``latched`` keeps the last message for late subscribers."""
        ...

    def close(self) -> None:
        """Release the middleware; the transport is not used afterwards."""
        ...


def record(payload: Any) -> Any:
    """What a handler got, as the record it carries: JSON text is parsed, a decoder (typed
    wire) is called, a dict is itself. Raises what parsing raises (the caller rejects it)."""
    if callable(payload):
        return payload()
    if isinstance(payload, str | bytes):
        return json.loads(payload)
    return payload


def dumps(message: dict[str, Any]) -> str:
    """A message as compact JSON text, the form every topic carries; values JSON lacks go as ``str``."""
    return json.dumps(message, default=str, separators=(",", ":"))


class LocalBus:
    """An in-process bus: one delivery thread, messages in publication order (tests, embedding).

    Latched topics replay their last message to late subscribers, like ROS transient-local.
    Handlers run one at a time on the bus thread, except that replay: a late subscriber
    gets the last message at once, on the subscribing thread.
    """

    def __init__(self) -> None:
        self._subs: dict[str, list[Handler]] = {}
        self._latched: dict[str, str] = {}
        self._latched_topics: set[str] = set()
        self._q: queue.Queue[tuple[str, str] | None] = queue.Queue()
        self._lock = threading.Lock()
        self._idle = threading.Condition(self._lock)
        self._pending = 0
        self._thread = threading.Thread(target=self._run, name="cosleec-localbus", daemon=True)
        self._thread.start()

    def transport(self) -> LocalTransport:
        """A :class:`Transport` on this bus, to give to one node; they are cheap and share the bus."""
        return LocalTransport(self)

    def _run(self) -> None:
        while True:
            item = self._q.get()
            if item is None:
                return
            t, payload = item
            for h in list(self._subs.get(t, ())):
                try:
                    h(payload)
                except Exception:  # a subscriber's bug must not stop delivery to others
                    log.exception("handler for %s failed", t)
            with self._lock:
                self._pending -= 1
                if self._pending == 0:
                    self._idle.notify_all()

    def _publish(self, t: str, payload: str) -> None:
        with self._lock:
            if t in self._latched_topics:
                self._latched[t] = payload
            self._pending += 1
        self._q.put((t, payload))

    def _subscribe(self, t: str, h: Handler) -> None:
        with self._lock:
            self._subs.setdefault(t, []).append(h)
            last = self._latched.get(t)
        if last is not None:  # a late joiner of a latched topic gets the current state
            h(last)

    def wait_idle(self, timeout: float = 5.0) -> bool:
        """Block until every published message has been delivered; False if ``timeout`` (s) passed first.

        Messages published by handlers while it waits are waited for too.
        """
        with self._idle:
            return self._idle.wait_for(lambda: self._pending == 0, timeout)

    def close(self) -> None:
        """Stop the delivery thread once the messages already published are delivered (waits up to 5 s)."""
        self._q.put(None)
        self._thread.join(5)


class LocalTransport:
    """One node's handle on a :class:`LocalBus`: the :class:`Transport` of in-process runs and tests.

    Get one from :meth:`LocalBus.transport`.
    """

    def __init__(self, bus: LocalBus) -> None:
        self.bus = bus

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        """Queue ``message`` (as JSON text) for delivery on the bus thread; returns at once."""
        self.bus._publish(topic, message if isinstance(message, str) else dumps(message))

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Deliver ``topic`` to ``handler``; a latched topic's last message arrives at once."""
        self.bus._subscribe(topic, handler)

    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        """On the local bus a typed message is published as the JSON of its fields; ``qos`` is moot."""
        self.bus._subscribe(topic, lambda payload: handler(json.loads(payload)))

    def advertise(self, topic: str, latched: bool = False) -> None:
        """On the bus only latching matters: a latched topic keeps its last message from now on."""
        if latched:
            with self.bus._lock:
                self.bus._latched_topics.add(topic)

    def close(self) -> None:
        """Nothing to release: close the :class:`LocalBus` itself when every node is done."""
        pass
