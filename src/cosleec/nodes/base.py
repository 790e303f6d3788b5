"""What every node shares: topic names, JSON handling, rejection of bad messages, counters.

It exists so that the Manager, the Layer Manager, the Context Listener and the task nodes
behave alike on the wire: a bad message is rejected and counted, never fatal.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes.transport import DEFAULT_NAMESPACE, LATCHED, Transport, dumps, topic

log = logging.getLogger("cosleec.nodes")


class MessageError(UserError, ValueError):
    """A message on a topic cannot be used (not JSON, a field missing or of the wrong type).

    Raise it from a topic handler: :meth:`Node.on` rejects the message -- logged, counted
    and published on ``rejected`` -- and the node keeps running.
    """


def context_values(msg: dict[str, Any]) -> dict[str, Any]:
    """The ``values`` of a ``context`` message (Manager and Layer Manager read the same stream)."""
    values = msg.get("values")
    if not isinstance(values, dict) or not values:
        raise MessageError("context message needs a non-empty object `values`")
    return values


class Node:
    """A node publishes and subscribes JSON objects on ``<namespace>/<name>`` topics.

    A message that is not a JSON object, or that the handler rejects with ValueError, is
    logged, counted and reported on ``rejected``; the node keeps running.
    """

    name = "node"
    #: publish status after every rejection, so a harness sees counts change at once;
    #: nodes whose status is a heartbeat in deployment turn this off
    status_each = True

    def __init__(self, transport: Transport, namespace: str = DEFAULT_NAMESPACE) -> None:
        self.transport = transport
        self.namespace = namespace
        self.counters: dict[str, int] = {"received": 0, "rejected": 0, "published": 0}
        self._count_lock = threading.Lock()
        self._status_lock = threading.RLock()  # snapshots are published in the order they are taken
        self._status_seq = 0
        self._advertised: list[str] = []  # what status reports subscriber counts for
        for t in ("rejected", "status"):
            self.advertise(t)

    def topic(self, name: str) -> str:
        """The full name of topic ``name`` under this node's namespace (``/cosleec/decisions``)."""
        return topic(self.namespace, name)

    def advertise(self, name: str) -> None:
        """Declare that this node publishes on ``name`` (latched if it is in ``LATCHED``).

        Advertise every output in the constructor: :meth:`status` reports the subscriber
        count of each advertised topic, which is how a harness sees the graph is connected.
        """
        self.transport.advertise(self.topic(name), latched=name in LATCHED)
        self._advertised.append(name)

    def publish(self, name: str, message: dict[str, Any]) -> None:
        """Send ``message`` as JSON on topic ``name`` and count it (values JSON lacks go as ``str``)."""
        self.transport.publish(self.topic(name), dumps(message))
        self._count("published")

    def on(self, name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        """Call ``handler`` with every JSON object received on topic ``name``.

        A payload that is not a JSON object, or that the handler refuses by raising
        ValueError, TypeError or KeyError, is :meth:`reject`-ed and the node carries on;
        any other exception goes to the transport. The handler runs on a thread of the
        transport, not the caller's.
        """
        full = self.topic(name)

        def receive(payload: str) -> None:
            self._count("received")
            try:
                message = json.loads(payload)
                if not isinstance(message, dict):
                    raise MessageError("expected a JSON object")
                handler(message)
            except (ValueError, TypeError, KeyError) as e:
                self.reject(full, str(e) or type(e).__name__, payload)

        self.transport.subscribe(full, receive)

    def reject(self, where: str, reason: str, payload: Any) -> None:
        """Log, count and publish on ``rejected`` a message this node cannot use.

        ``where`` is the topic it came from; the payload is published cut to 500
        characters. With ``status_each`` a status message follows at once.
        """
        self._count("rejected")
        log.warning("%s: rejected message on %s: %s", self.name, where, reason)
        text = (
            payload
            if isinstance(payload, str)
            else dumps(payload)
            if isinstance(payload, dict)
            else repr(payload)
        )
        self.publish("rejected", {"node": self.name, "topic": where, "reason": reason, "payload": text[:500]})
        if self.status_each:
            self.status()  # the count just changed: say so

    def _count(self, key: str, n: int = 1) -> None:
        with self._count_lock:
            self.counters[key] = self.counters.get(key, 0) + n

    def status(self, **extra: Any) -> None:
        """Publish the node's counters on ``status``; snapshots go out in the order they are taken.

        ``extra`` fields join the message, with the subscriber count of every advertised
        topic when the transport can tell. :func:`cosleec.ros.serve` calls it every 0.5 s
        as a heartbeat.
        """
        with self._status_lock:
            with self._count_lock:
                counters = dict(self.counters)
            subs = {}
            count = getattr(self.transport, "subscribers", None)
            if count is not None:  # who listens to what this node publishes: is the graph complete?
                subs = {n: count(self.topic(n)) for n in self._advertised}
            self._status_seq += 1
            message = {"node": self.name, "seq": self._status_seq, "counters": counters, "subscribers": subs}
            self.publish("status", {**message, **extra})
