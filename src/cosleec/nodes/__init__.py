"""The paper's nodes, independent of the middleware: Manager, Context Listener, Layer Manager
and the task-node base, written against the :class:`Transport` protocol (which lives here).

``cosleec.ros`` runs them on ROS 2 or ROS 1; :class:`LocalBus` runs them in one process.
Each node is built from a :class:`~cosleec.runtime.RuleSet`
(``RuleSet.from_file("rules.sleec")``).
"""

from cosleec.nodes.base import LogLimiter, MessageError, Node
from cosleec.nodes.layers_node import LayersNode
from cosleec.nodes.listener import ListenerNode, Mapping, MappingError
from cosleec.nodes.manager_node import ManagerNode
from cosleec.nodes.recording import McapRecorder, read_recording
from cosleec.nodes.task_node import ManagerUnavailable, TaskNode
from cosleec.nodes.transport import (
    DEFAULT_NAMESPACE,
    LATCHED,
    Handler,
    LocalBus,
    LocalTransport,
    Transport,
    dumps,
    topic,
)

__all__ = [
    "DEFAULT_NAMESPACE",
    "LATCHED",
    "Handler",
    "LayersNode",
    "ListenerNode",
    "LocalBus",
    "LocalTransport",
    "LogLimiter",
    "ManagerNode",
    "ManagerUnavailable",
    "Mapping",
    "MappingError",
    "McapRecorder",
    "MessageError",
    "Node",
    "TaskNode",
    "Transport",
    "dumps",
    "read_recording",
    "topic",
]
