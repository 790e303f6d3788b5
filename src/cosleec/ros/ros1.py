"""ROS 1 transport (rospy, TCPROS): JSON in std_msgs/String, latched topics latched.

Network safety: run with ROS_HOSTNAME=localhost and a 127.0.0.1 master (ros-setup.md §1).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from cosleec.ros.messages import message_class, to_dict
from cosleec.transport import Handler


class Ros1Transport:
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

    def advertise(self, topic: str, latched: bool = False) -> None:
        with self._lock:
            if latched:
                self._latched.add(topic)
            if topic not in self._pubs:
                self._pubs[topic] = self._rospy.Publisher(
                    topic, self._String, queue_size=1000, latch=topic in self._latched, tcp_nodelay=True
                )

    def publish(self, topic: str, payload: str) -> None:
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._String(data=payload))

    def subscribe(self, topic: str, handler: Handler) -> None:
        self._subs.append(
            self._rospy.Subscriber(
                topic, self._String, lambda m: handler(m.data), queue_size=1000, tcp_nodelay=True
            )
        )

    def subscribe_typed(self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        cls = message_class(type_name)
        self._subs.append(self._rospy.Subscriber(topic, cls, lambda m: handler(to_dict(m)), queue_size=1000))

    def publish_typed(self, topic: str, type_name: str, fields: dict[str, Any]) -> None:
        """Publish a typed message (simulators, tests): ``std_msgs/Bool``, ``{"data": True}``."""
        key = f"{topic}#{type_name}"
        pub = self._pubs.get(key)
        if pub is None:
            pub = self._pubs[key] = self._rospy.Publisher(topic, message_class(type_name), queue_size=100)
        pub.publish(message_class(type_name)(**fields))

    def typed_subscribers(self, topic: str, type_name: str) -> int:
        pub = self._pubs.get(f"{topic}#{type_name}")
        return pub.get_num_connections() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        pub = self._pubs.get(topic)
        return pub.get_num_connections() if pub is not None else 0

    def ok(self) -> bool:
        return not self._rospy.is_shutdown()

    def close(self) -> None:
        for s in self._subs:
            s.unregister()
        for p in self._pubs.values():
            p.unregister()
        self._rospy.signal_shutdown("cosleec node stopped")
