"""CO-SLEEC on ROS 2 (rclpy) and ROS 1 (rospy): the only package that imports either.

The nodes of :mod:`cosleec.nodes` run here on a real middleware: :func:`serve` runs one
node until SIGINT/SIGTERM, :func:`launch` starts the nodes of a launch file, and
:func:`run_demo` plays the assistive-care scenario across processes; a ROS 2 Manager is a
lifecycle node (:class:`ManagedManager`). rclpy and rospy are
imported only when a transport is created, so this face imports without either.
"""

from cosleec.ros.demo import main as run_demo
from cosleec.ros.launch import launch, node_command, start, stop
from cosleec.ros.lifecycle import ManagedManager
from cosleec.ros.messages import MessageTypeError, message_class
from cosleec.ros.run import MiddlewareMissingError, load_module, serve, transport

__all__ = [
    "ManagedManager",
    "MessageTypeError",
    "MiddlewareMissingError",
    "launch",
    "load_module",
    "message_class",
    "node_command",
    "run_demo",
    "serve",
    "start",
    "stop",
    "transport",
]
