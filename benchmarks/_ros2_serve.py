"""Serve one rclpy node for a ROS 2 benchmark's helper process until SIGTERM or SIGINT.

The echo (``_ros2_pong.py``) and the relays (``_ros2_relay.py``) spin what the cosleec nodes
spin -- rclpy's SingleThreadedExecutor, in a thread -- so the paths compare like for like.
"""

import signal
import threading
from typing import Any

import rclpy


def serve(node: Any, ready: str) -> None:
    """Spin ``node`` until SIGTERM or SIGINT, saying ``ready`` once it spins; then shut rclpy down."""
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    t = threading.Thread(target=executor.spin, daemon=True)
    t.start()
    print(ready, flush=True)
    stop.wait()
    executor.shutdown()
    t.join(5)
    node.destroy_node()
    rclpy.shutdown()
