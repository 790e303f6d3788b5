"""Raw rclpy echo: /bench/ping -> /bench/pong (std_msgs/String), the transport floor."""

import signal
import threading

import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

rclpy.init()
node = rclpy.create_node("bench_pong")
qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
pub = node.create_publisher(String, "/bench/pong", qos)
node.create_subscription(String, "/bench/ping", lambda m: pub.publish(m), qos)
stop = threading.Event()
signal.signal(signal.SIGTERM, lambda *_: stop.set())
signal.signal(signal.SIGINT, lambda *_: stop.set())
executor = rclpy.executors.SingleThreadedExecutor()
executor.add_node(node)
t = threading.Thread(target=executor.spin, daemon=True)
t.start()
print("pong ready", flush=True)
stop.wait()
executor.shutdown()
t.join(5)
node.destroy_node()
rclpy.shutdown()
