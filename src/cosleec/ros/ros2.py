"""ROS 2 transport (rclpy, Fast DDS): JSON in std_msgs/String, latched topics transient-local.

Imported only when a ROS 2 transport is created, so the rest of cosleec runs without
rclpy. Network safety is checked here, fail closed: the transport refuses to start unless
DDS discovery is confined to this machine (:func:`check_network`).

An exception raised into the executor would end ``spin()`` and leave the node deaf, so
every callback is guarded (:class:`~cosleec.ros.guard.CallbackGuard`), and if the spin
thread ends anyway the transport says so: :meth:`Ros2Transport.alive` and
:meth:`Ros2Transport.ok` turn False and :func:`cosleec.ros.serve` stops the node.
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import Handler
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.messages import message_class, to_dict

log = logging.getLogger("cosleec.ros")


class UnsafeNetworkError(UserError):
    """ROS 2 discovery could leave this machine: cosleec refuses to start (fail closed)."""


def check_network() -> None:
    """Refuse to start DDS where discovery could leave loopback (fail closed).

    Passes when ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (as
    :func:`cosleec.ros.env.ros2_env` sets it) or ``COSLEEC_ALLOW_NETWORK`` is set, for a
    deployment on a real robot network; raises :class:`UnsafeNetworkError` otherwise.
    """
    if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") != "LOCALHOST" and not os.environ.get(
        "COSLEEC_ALLOW_NETWORK"
    ):
        raise UnsafeNetworkError(
            "refusing to start ROS 2 without ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST",
            hint="set COSLEEC_ALLOW_NETWORK=1 to deploy on a real robot network",
        )


class Ros2Transport:
    """The :class:`~cosleec.nodes.Transport` on ROS 2: one rclpy node, spun on its own thread.

    One per node process (see :func:`cosleec.ros.run.transport`). It checks the network
    first (:class:`UnsafeNetworkError`), and initialises rclpy if needed without rclpy's
    signal handlers: the node's own loop owns SIGINT/SIGTERM. A single-threaded executor
    runs every handler of this transport, one at a time, on the spin thread; a handler
    that raises is counted in ``errors`` and the executor goes on. ``spin_error`` holds
    what ended the spin thread, if something did.
    """

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
        self._guard = CallbackGuard()
        self._lost = 0
        self._closing = False
        self.spin_error: BaseException | None = None
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name=f"{node_name}-spin", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception as e:
            if not self._closing:  # not a shutdown race: the node has gone deaf, say why
                self.spin_error = e
                log.error("the ROS 2 executor stopped: %s: %s", type(e).__name__, e, exc_info=e)
        if not self._closing and self.spin_error is None:
            log.error("the ROS 2 executor stopped (rclpy shut down?)")

    @property
    def lost(self) -> int:
        """Messages DDS reports lost on this transport's subscriptions (the middleware's own count)."""
        return self._lost

    def _events(self) -> Any:
        """QoS event callbacks of a subscription: count what the middleware says it lost."""
        from rclpy.event_handler import SubscriptionEventCallbacks

        def lost(status: Any) -> None:
            with self._lock:
                self._lost += int(status.total_count_change)

        return SubscriptionEventCallbacks(message_lost=lost)

    @property
    def errors(self) -> int:
        """Callbacks that raised (and were caught): node status reports it as ``transport_errors``."""
        return self._guard.errors

    def alive(self) -> bool:
        """Is the spin thread still delivering messages? False once it has ended, for whatever reason.

        Node status reports it as ``executor_alive``.
        """
        return self._thread.is_alive()

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
        """Create the publisher of ``topic``, reliable; transient-local with depth 1 when ``latched``.

        The first call for a topic fixes its QoS. Thread-safe.
        """
        with self._lock:
            if latched:
                self._latched.add(topic)
            if topic not in self._pubs:
                self._pubs[topic] = self.node.create_publisher(
                    self._String, topic, self._qos(topic in self._latched)
                )

    def publish(self, topic: str, payload: str) -> None:
        """Publish JSON text on ``topic``, advertising it (not latched) on first use."""
        if topic not in self._pubs:
            self.advertise(topic)
        self._pubs[topic].publish(self._String(data=payload))

    def subscribe(self, topic: str, handler: Handler, latched: bool | None = None) -> None:
        """Call ``handler`` with the JSON text of every message on ``topic``.

        ``latched`` asks for transient-local QoS, to receive a latched publisher's last
        message; None decides by the name (a topic ending in ``layers``).
        """
        is_latched = topic.rsplit("/", 1)[-1] == "layers" if latched is None else latched
        sub = self.node.create_subscription(
            self._String,
            topic,
            self._guard.wrap(topic, lambda m: handler(m.data)),
            self._qos(is_latched),
            event_callbacks=self._events(),
        )
        self._subs.append(sub)

    def subscribe_typed(self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        """Call ``handler`` with every ``type_name`` message on ``topic``, as nested dicts.

        ValueError or ImportError for a message type that cannot be loaded.
        """
        cls = message_class(type_name)
        sub = self.node.create_subscription(
            cls,
            topic,
            self._guard.wrap(topic, lambda m: handler(to_dict(m))),
            self._qos(False),
            event_callbacks=self._events(),
        )
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
        """Subscribers of this transport's typed publisher on ``topic`` (0 before :meth:`publish_typed`)."""
        pub = self._pubs.get(f"{topic}#{type_name}")
        return pub.get_subscription_count() if pub is not None else 0

    def subscribers(self, topic: str) -> int:
        """Subscribers matched to this transport's publisher on ``topic`` (0 if it has none).

        Node status reports these, so a harness can tell the graph is connected.
        """
        pub = self._pubs.get(topic)
        return pub.get_subscription_count() if pub is not None else 0

    def ok(self) -> bool:
        """False once rclpy has shut down or the spin thread has ended: :func:`cosleec.ros.serve` then stops the node."""
        return bool(self._rclpy.ok()) and self.alive()

    def close(self) -> None:
        """Shut down in the order that avoids aborts at exit: executor, spin thread, node, rclpy.

        Errors along the way (a context already invalid) are ignored.
        """
        self._closing = True
        with contextlib.suppress(Exception):
            self.executor.shutdown()
        self._thread.join(5)
        with contextlib.suppress(Exception):
            self.node.destroy_node()
        if self._rclpy.ok():
            with contextlib.suppress(Exception):
                self._rclpy.shutdown()
