"""What the hospital delivery robot does for the rules of ``hospital.sleec`` (docs/tutorial.md).

Written by ``cosleec scaffold hospital.sleec -o hospital_tasks.py``, then each TODO replaced
by the robot's action. The robot is simulated: it prints what it does, and what is in
``robot.broken`` it cannot do right now (a nurse who does not answer). Embedded:
``install(manager)``; on ROS 2: ``cosleec ros2 task hospital.sleec --module hospital_tasks.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cosleec.runtime import Decision, Task, hedge

if TYPE_CHECKING:
    from cosleec.nodes import TaskNode
    from cosleec.runtime import Manager


@dataclass
class Robot:
    """The simulated robot: does an action and reports it, unless it is in ``broken``."""

    broken: set[str] = field(default_factory=set)
    said: list[str] = field(default_factory=list)

    def do(self, task: Task, action: str) -> None:
        """Do ``action`` and report it (obligations are judged by the events reported)."""
        if action in self.broken:
            print(f"robot: cannot {action}")
            return
        print(f"robot: {action}")
        task.event(action)

    def say(self, sentence: str) -> None:
        """Say ``sentence`` to the person in front of the robot."""
        print(f"robot says: {sentence}")
        self.said.append(sentence)


class RobotTask(Task):
    """A task of the simulated robot: its methods act through ``self.robot``."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot


class R1(RobotTask):
    """R1: medication information only to the patient, or to a nurse when the patient is a minor."""

    rule = "R1"

    def default(self, decision: Decision) -> None:
        """The requester is the patient: share."""
        self.robot.do(self, "ShareMedicationInfo")

    @hedge(1)
    def refuse(self, decision: Decision) -> None:
        """R1.1, unless not requesterIsPatient: refuse, and explain why to the person."""
        self.robot.do(self, "Refuse")
        self.robot.say(decision.for_people)
        self.robot.do(self, "ExplainWhy")

    @hedge(2)
    def share_with_nurse(self, decision: Decision) -> None:
        """R1.2, unless patientIsMinor and requesterIsNurse: share with the nurse."""
        self.robot.do(self, "ShareMedicationInfo")


class R2(Task):
    """R2: no video in a patient's room without consent (a prohibition: nothing to do)."""

    rule = "R2"

    def default(self, decision: Decision) -> None:
        """Nothing to do: the camera asks ``request("RecordVideo")`` before it records."""


class R3(RobotTask):
    """R3: a fall calls a nurse; if no nurse is called within a minute, raise the alarm."""

    rule = "R3"

    def default(self, decision: Decision) -> None:
        """Call a nurse."""
        self.robot.do(self, "CallNurse")

    def fallback(self, decision: Decision) -> None:
        """The `otherwise`: the nurse was not called in time, so raise the alarm."""
        self.robot.do(self, "RaiseAlarm")


class R4(RobotTask):
    """R4: a low battery sends the robot to its dock, unless it delivers urgent medication."""

    rule = "R4"

    def default(self, decision: Decision) -> None:
        """Go to the dock."""
        self.robot.do(self, "GoToDock")


def install(node: Manager | TaskNode, robot: Robot | None = None) -> Robot:
    """Bind the robot's tasks to ``node`` (a Manager, or a task node's ``--module``); the robot."""
    robot = robot or Robot()
    node.bind(R1(robot), R2(), R3(robot), R4(robot))
    return robot
