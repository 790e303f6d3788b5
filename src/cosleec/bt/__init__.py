"""Behaviour trees guarded by the Manager (``py_trees`` 2.x: ``pip install 'cosleec[bt]'``).

A mission written as a ``py_trees`` tree asks the Manager before acting and tells it what
the robot did, with the same calls a task makes:

- :class:`Permitted` -- a condition: is this event permitted now? (the reason as feedback);
- :class:`Guarded` -- a decorator: ask before the child runs, report the event when it succeeds;
- :class:`RuleTask` -- a rule as a subtree: on its trigger, run the default subtree or the
  subtree of the ``unless`` clause the Manager's decision names (the paper's COP mapping);
- :class:`Obligations` -- what the robot still owes, on the blackboard at :data:`OBLIGATIONS_KEY`.

Each takes an embedded :class:`~cosleec.runtime.Manager` or any :class:`Link`; on ROS 2,
:class:`cosleec.ros.bt_client.RosLink` asks the Manager node's services. This package
never imports ROS. The guide: docs/bt.md.
"""

from cosleec.bt.behaviours import OBLIGATIONS_KEY, Guarded, Obligations, Permitted
from cosleec.bt.link import EmbeddedLink, Link, LinkError, link_for, owed
from cosleec.bt.rule import DECISION_KEY, RuleTask

__all__ = [
    "DECISION_KEY",
    "OBLIGATIONS_KEY",
    "EmbeddedLink",
    "Guarded",
    "Link",
    "LinkError",
    "Obligations",
    "Permitted",
    "RuleTask",
    "link_for",
    "owed",
]
