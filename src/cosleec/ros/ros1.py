"""ROS 1 transport (rospy, TCPROS): JSON in std_msgs/String, latched topics latched.

Imported only when a ROS 1 transport is created, so the rest of cosleec runs without
rospy. Network safety: run with ROS_HOSTNAME=localhost and a master on 127.0.0.1
(:func:`cosleec.ros.env.ros1_env` sets both); unlike the ROS 2 transport, this one does
not check.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from cosleec.nodes import Handler
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.messages import message_class, to_dict


class Ros1Transport:
    """The :class:`~cosleec.nodes.Transport` on ROS 1: the process's one rospy node.

    One per node process (see :func:`cosleec.ros.run.transport`); it needs the master of
    ``ROS_MASTER_URI``. rospy's signal handlers are off: the node's own loop owns
    SIGINT/SIGTERM. rospy calls handlers on its own threads, so they may run concurrently.
    A handler that raises is counted in ``errors`` and logged rate-limited
    (:class:`~cosleec.ros.guard.CallbackGuard`), not left to rospy's unbounded log.
    """

    def __init__(self, node_name: str) -> None:
        import rospy
        from std_msgs.msg import String

        self._rospy = rospy
        self._String = String
        # signals are ours: the node's main loop stops cleanly on SIGINT/SIGTERM
        rospy.init_node(node_name, anonymous=False, disable_signals=True)
        self._pubs: dict[str, Any] = {}
        self._subs: list[Any] = []
        self._latched: set[str] = set()
        self._lock = threading.Lock()
        self._guard = CallbackGuard()

    @property
    def errors(self) -> int:
        """Callbacks that raised (and were caught): node status reports it as ``transport_errors``."""
        return self._guard.errors

    def alive(self) -> bool:
        """False once rospy has shut down (stopped, or evicted by a node of the same name)."""
        return not self._rospy.is_shutdown()

    def advertise(self, topic: str, latched: bool = False) -> None:
        """Create the publisher of ``topic``, latched when ``latched``; the first call decides.

        Thread-safe.
        """
        with self._lock:
            if latched:
                self._latched.add(topic)
            if topic not in self._pubs:
                self._pubs[topic] = self._rospy.Publisher(
                    topic, self._String, queue_size=1000, latch=topic in self._latched, tcp_nodelay=True
                )

    def publish(self, topic: str, payload: str) -> None:
        """Publish JSON text on ``topic``, advertising it (not latched) on first use."""
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._String(data=payload))

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler`` with the JSON text of every message on ``topic``.

        Latching is the publisher's business in ROS 1: a late subscriber gets a latched
        topic's last message without asking.
        """
        self._subs.append(
            self._rospy.Subscriber(
                topic,
                self._String,
                self._guard.wrap(topic, lambda m: handler(m.data)),
                queue_size=1000,
                tcp_nodelay=True,
            )
        )

    def subscribe_typed(self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, as nested dicts.

        ValueError or ImportError for a message type that cannot be loaded.
        """
        cls = message_class(type_name)
        self._subs.append(
            self._rospy.Subscriber(
                topic, cls, self._guard.wrap(topic, lambda m: handler(to_dict(m))), queue_size=1000
            )
        )

    def publish_typed(self, topic: str, type_name: str, fields: dict[str, Any]) -> None:
        """Publish a typed message (simulators, tests): ``std_msgs/Bool``, ``{"data": True}``."""
        key = f"{topic}#{type_name}"
        pub = self._pubs.get(key)
        if pub is None:
            pub = self._pubs[key] = self._rospy.Publisher(topic, message_class(type_name), queue_size=100)
        pub.publish(message_class(type_name)(**fields))

    def typed_subscribers(self, topic: str, type_name: str) -> int:
        """Connections of this transport's typed publisher on ``topic`` (0 before :meth:`publish_typed`)."""
        pub = self._pubs.get(f"{topic}#{type_name}")
        return pub.get_num_connections() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        """Subscribers connected to this transport's publisher on ``topic`` (0 if it has none).

        ROS 1 delivers nothing to a subscriber before its connection is made: wait for it.
        """
        pub = self._pubs.get(topic)
        return pub.get_num_connections() if pub is not None else 0

    def ok(self) -> bool:
        """False once rospy has shut down: :func:`cosleec.ros.serve` then stops the node."""
        return self.alive()

    def close(self) -> None:
        """Unregister every subscriber and publisher, then shut rospy down for this process."""
        for s in self._subs:
            s.unregister()
        for p in self._pubs.values():
            p.unregister()
        self._rospy.signal_shutdown("cosleec node stopped")
