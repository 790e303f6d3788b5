"""The paper's nodes, independent of the middleware: Manager, Context Listener, Layer Manager,
the task-node base and the guard, written against the :class:`Transport` protocol (which
lives here).

``cosleec.ros`` runs them on ROS 2 or ROS 1; :class:`LocalBus` runs them in one process.
Each node is built from a :class:`~cosleec.runtime.RuleSet`
(``RuleSet.from_file("rules.sleec")``).
"""

from cosleec.nodes.base import LogLimiter, MessageError, Node
from cosleec.nodes.fieldbag import BagError, BagStep, BagTrace, Origin, is_bag, replay
from cosleec.nodes.guard_node import GuardError, GuardNode, Route, load_routes, route
from cosleec.nodes.layers_node import LayersNode
from cosleec.nodes.listener import ListenerNode
from cosleec.nodes.manager_node import DECIDE, DEFAULT_DECIDE, ManagerNode
from cosleec.nodes.mapping import Mapping, MappingError
from cosleec.nodes.qos import Qos, QosError
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
    record,
    topic,
)

__all__ = [
    "DECIDE",
    "DEFAULT_DECIDE",
    "DEFAULT_NAMESPACE",
    "LATCHED",
    "BagError",
    "BagStep",
    "BagTrace",
    "GuardError",
    "GuardNode",
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
    "Origin",
    "Qos",
    "QosError",
    "Route",
    "TaskNode",
    "Transport",
    "dumps",
    "is_bag",
    "load_routes",
    "read_recording",
    "record",
    "replay",
    "route",
    "topic",
]
