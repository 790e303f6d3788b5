"""CO-SLEEC nodes, independent of the middleware: Manager, Context Listener, Layer Manager
and the task-node base. ``cosleec.ros`` runs them on ROS 2 or ROS 1; ``LocalBus`` runs them
in one process."""

from cosleec.nodes.base import Node
from cosleec.nodes.layers_node import LayersNode
from cosleec.nodes.listener import ListenerNode, Mapping, MappingError
from cosleec.nodes.manager_node import ManagerNode
from cosleec.nodes.task_node import TaskNode

__all__ = ["LayersNode", "ListenerNode", "ManagerNode", "Mapping", "MappingError", "Node", "TaskNode"]
