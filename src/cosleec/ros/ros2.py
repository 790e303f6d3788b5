"""ROS 2 transport (rclpy, Fast DDS): JSON in std_msgs/String, latched topics transient-local.

Network safety is the caller's job and is checked here: see ``check_network`` (ros-setup.md §1).
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable
from typing import Any

from cosleec.ros.messages import message_class, to_dict
from cosleec.transport import Handler


def check_network() -> None:
    """Refuse to start DDS where discovery could leave loopback (fail closed)."""
    if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") != "LOCALHOST" and not os.environ.get(
        "COSLEEC_ALLOW_NETWORK"
    ):
        raise SystemExit(
            "cosleec: refusing to start ROS 2 without ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST "
            "(set COSLEEC_ALLOW_NETWORK=1 to deploy on a real robot network)"
        )


class Ros2Transport:
    def __init__(self, node_name: str) -> None:
        check_network()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from std_msgs.msg import String

        self._rclpy = rclpy
        self._String = String
        if not rclpy.ok():
            from rclpy.signals import SignalHandlerOptions

            # the node's own loop owns SIGINT/SIGTERM: a signal during start-up must not
            # invalidate the context under our feet
            rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node(node_name)
        self._pubs: dict[str, Any] = {}
        self._subs: list[Any] = []
        self._latched: set[str] = set()
        self._lock = threading.Lock()
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name=f"{node_name}-spin", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(Exception):  # shutdown races (context already invalid)
            self.executor.spin()

    def _qos(self, latched: bool) -> Any:
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

        if latched:
            return QoSProfile(
                depth=1,
                history=HistoryPolicy.KEEP_LAST,
                reliability=ReliabilityPolicy.RELIABLE,
                durability=DurabilityPolicy.TRANSIENT_LOCAL,
            )
        return QoSProfile(
            depth=1000,
            history=HistoryPolicy.KEEP_LAST,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.VOLATILE,
        )

    def advertise(self, topic: str, latched: bool = False) -> None:
        with self._lock:
            if latched:
                self._latched.add(topic)
            if topic not in self._pubs:
                self._pubs[topic] = self.node.create_publisher(
                    self._String, topic, self._qos(topic in self._latched)
                )

    def publish(self, topic: str, payload: str) -> None:
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._String(data=payload))

    def subscribe(self, topic: str, handler: Handler, latched: bool | None = None) -> None:
        is_latched = topic.rsplit("/", 1)[-1] == "layers" if latched is None else latched
        sub = self.node.create_subscription(
            self._String, topic, lambda m: handler(m.data), self._qos(is_latched)
        )
        self._subs.append(sub)

    def subscribe_typed(self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        cls = message_class(type_name)
        sub = self.node.create_subscription(cls, topic, lambda m: handler(to_dict(m)), self._qos(False))
        self._subs.append(sub)

    def publish_typed(self, topic: str, type_name: str, fields: dict[str, Any]) -> None:
        """Publish a typed message (simulators, tests): ``std_msgs/Bool``, ``{"data": True}``."""
        key = f"{topic}#{type_name}"
        pub = self._pubs.get(key)
        if pub is None:
            pub = self._pubs[key] = self.node.create_publisher(
                message_class(type_name), topic, self._qos(False)
            )
        pub.publish(message_class(type_name)(**fields))

    def typed_subscribers(self, topic: str, type_name: str) -> int:
        pub = self._pubs.get(f"{topic}#{type_name}")
        return pub.get_subscription_count() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        pub = self._pubs.get(topic)
        return pub.get_subscription_count() if pub is not None else 0

    def publishers(self, topic: str) -> int:
        return int(self.node.count_publishers(topic))

    def ok(self) -> bool:
        return bool(self._rclpy.ok())

    def close(self) -> None:
        """The shutdown order that avoids aborts at exit (ros-setup.md §2.6)."""
        with contextlib.suppress(Exception):
            self.executor.shutdown()
        self._thread.join(5)
        with contextlib.suppress(Exception):
            self.node.destroy_node()
        if self._rclpy.ok():
            with contextlib.suppress(Exception):
                self._rclpy.shutdown()
