"""The Context Listener node: the robot's own topics -> measure values and trigger events.

What it reads, and how, is a :class:`~cosleec.nodes.mapping.Mapping` (a YAML file, checked
before the node starts; :mod:`cosleec.nodes.mapping`, ``docs/mapping.md``). The node
subscribes once to each topic of the mapping, turns every message into the values of the
entries that read it (:meth:`~cosleec.nodes.mapping.Entry.value`), and publishes them.

All measures read from one incoming message are sent as one atomic context update.

A value is checked before it leaves: a number must be finite and fit a float (NaN, inf
and a 400-digit integer are rejected), a measure taken as it is must be of its measure's
kind (no ``"fast"`` for a numeric measure), and without the rules to say the kind it must
at least be a boolean, a number or a short string. A rejected value is counted and
reported on ``rejected``; the rest of the message still counts.
"""

from __future__ import annotations

import logging
from typing import Any

from cosleec.nodes.base import Node
from cosleec.nodes.mapping import Entry, Mapping

log = logging.getLogger("cosleec.nodes")

__all__ = ["ListenerNode"]


class ListenerNode(Node):
    """Subscribes to the mapped robot topics; publishes ``context`` updates and ``events``.

    Run one per robot, next to the Manager node. The mapping's ``namespace``, when set,
    wins over ``namespace``. Each topic is subscribed once, with the QoS of
    :meth:`Mapping.qos_of`, for all the entries that read it. A message a mapping entry
    cannot read is rejected for that entry; the other entries of the message still count.
    Whatever a message holds, the node rejects it and goes on: no error leaves a typed
    topic's callback.
    """

    name = "listener"

    def __init__(self, transport: Any, mapping: Mapping, *, namespace: str = "/cosleec") -> None:
        super().__init__(transport, mapping.namespace or namespace)
        self.mapping = mapping
        #: per event: whether its condition held on the last message that could be read
        self.edges: dict[str, bool] = {}
        for t in ("context", "events"):
            self.advertise(t)
        by_topic: dict[str, list[Entry]] = {}
        for e in mapping.entries:
            by_topic.setdefault(e.topic, []).append(e)
        for t, type_name in mapping.topics().items():
            entries = by_topic[t]
            qos = mapping.qos_of(t)
            log.info("listener: reading %s (%s) with qos %s", t, type_name, qos.describe())
            transport.subscribe_typed(
                t, type_name, lambda msg, entries=entries, t=t: self._message(t, entries, msg), qos
            )

    def _message(self, where: str, entries: list[Entry], message: dict[str, Any]) -> None:
        self._count("received")
        try:
            self._read(where, entries, message)
        except Exception as err:  # never into the transport: its thread must go on delivering
            self.reject_error(where, err, message)

    def _read(self, where: str, entries: list[Entry], message: dict[str, Any]) -> None:
        values: dict[str, Any] = {}
        fired: list[str] = []
        for e in entries:
            try:
                v = e.value(message)
            except Exception as err:  # this entry cannot read it; the others may
                self.reject_error(where, err, message)
                continue
            if e.kind == "measure":
                values[e.name] = v
            else:
                before = self.edges.get(e.name, False)
                self.edges[e.name] = bool(v)
                if v and (e.fire == "each" or not before):
                    fired.append(e.name)
        if values:
            self.publish("context", {"values": values})
        for name in fired:
            # the values read from the same message travel with the event: topics have no order
            # between them (ROS 1 reads each on its own thread), and the rules must decide on
            # what this message said, not on the update before it
            self.publish("events", {"event": name, "values": values} if values else {"event": name})
