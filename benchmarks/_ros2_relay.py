"""The node design's floor over ROS 2: a node of the same shape as a cosleec node, doing nothing
but forwarding the benchmark's messages (``ros2_latency``'s third path).

``python _ros2_relay.py ROLE SHAPE.json``: ROLE is ``manager`` or ``task``; SHAPE lists the
publishers, subscriptions and services the running cosleec node of that role has (read from
the ROS graph by the benchmark). This node makes the same entities with the same message
and service types, renamed from ``/bench_cosleec`` to ``/bench_relay`` (global names under
``/bench_relay_<role>``), each with the QoS-event callbacks the cosleec nodes give theirs, and
spins the same executor. Only the path is live: the manager relay answers a ``Ping`` event
with an obligation message, the task relay answers that message with a ``Pong`` event. So
the three hops and four messages of the end-to-end path cross rclpy nodes of the same size
and shape with none of cosleec's work: what the design costs in rclpy before cosleec does
anything.
"""

import importlib
import json
import sys
from typing import Any

import rclpy
from cosleec_interfaces.msg import Event
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.qos import QoSProfile, ReliabilityPolicy

from _ros2_serve import serve

NS, RELAY = "/bench_cosleec", "/bench_relay"


def kind(type_name: str) -> Any:
    """The message or service class of ``pkg/msg/Name`` or ``pkg/srv/Name``."""
    pkg, sub, name = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.{sub}"), name)


def renamed(name: str, role: str) -> str:
    """``/bench_cosleec/x`` -> ``/bench_relay/x``; a global name under ``/bench_relay_<role>``."""
    return RELAY + name[len(NS) :] if name.startswith(NS + "/") else f"{RELAY}_{role}{name}"


def main() -> None:
    role, shape_file = sys.argv[1], sys.argv[2]
    with open(shape_file, encoding="utf-8") as f:
        shape = json.load(f)[role]
    rclpy.init()
    node = rclpy.create_node(f"relay_{role}")
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    publishers: dict[str, Any] = {}
    for topic, type_name in shape["publishers"]:
        publishers[renamed(topic, role)] = node.create_publisher(
            kind(type_name),
            renamed(topic, role),
            qos,
            event_callbacks=PublisherEventCallbacks(incompatible_qos=print),
        )
    obligations = publishers.get(f"{RELAY}/obligations")
    events = publishers.get(f"{RELAY}/events")

    def on_event(m: Any) -> None:  # the manager relay: a trigger -> an obligation
        if role == "manager" and m.event == "Ping" and obligations is not None:
            obligations.publish(obligations.msg_type())

    def on_obligation(_m: Any) -> None:  # the task relay: an obligation -> the response event
        if role == "task" and events is not None:
            events.publish(Event(event="Pong", sender="relay_task"))

    live = {f"{RELAY}/events": on_event, f"{RELAY}/obligations": on_obligation}
    for topic, type_name in shape["subscriptions"]:
        name = renamed(topic, role)
        node.create_subscription(
            kind(type_name),
            name,
            live.get(name, lambda _m: None),
            qos,
            event_callbacks=SubscriptionEventCallbacks(message_lost=print, incompatible_qos=print),
        )
    for service, type_name in shape["services"]:
        cls = kind(type_name)
        node.create_service(cls, renamed(service, role), lambda _req, res: res)
    serve(node, f"relay {role} ready")


if __name__ == "__main__":
    main()
