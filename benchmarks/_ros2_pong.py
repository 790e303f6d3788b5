"""Raw rclpy echo, the transport floor: a ``cosleec_interfaces/msg/Event`` Ping on /bench/ping
is answered by a Pong Event (same seq) on /bench/pong.

The same message type as the end-to-end path carries, and the same executor as the cosleec
nodes spin (rclpy's SingleThreadedExecutor, :class:`cosleec.ros.ros2.Ros2Transport`), so the
comparison measures what cosleec adds, not a different type or executor.
"""

import rclpy
from cosleec_interfaces.msg import Event
from rclpy.qos import QoSProfile, ReliabilityPolicy

from _ros2_serve import serve

rclpy.init()
node = rclpy.create_node("bench_pong")
qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
pub = node.create_publisher(Event, "/bench/pong", qos)


def echo(m: Event) -> None:
    pub.publish(Event(event="Pong", sender="bench_pong", seq=m.seq))


node.create_subscription(Event, "/bench/ping", echo, qos)
serve(node, "pong ready")
