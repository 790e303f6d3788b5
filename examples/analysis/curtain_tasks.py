"""A task module that implements the curtain rule only: ``cosleec analyse --tasks`` lists the rest.

``install(manager)`` is the contract every task module keeps (the ROS task node calls it too).
"""

from __future__ import annotations

from cosleec import Manager
from cosleec.demo.assistive_care.tasks import CurtainTask, Robot


def install(manager: Manager) -> Robot:
    """Bind the curtain task of the assistive-care example, and nothing else."""
    robot = Robot(manager)
    manager.bind(CurtainTask(robot))
    return robot
