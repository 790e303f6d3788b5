"""Tasks of the assistive-care robot, in both styles the runtime offers.

- R1, the paper's curtain rule, is a *task* (paper style): a default behaviour and one
  layer-bound implementation per hedge clause.
- Every other rule is served by *capabilities*: one handler per response event, composed
  by the runtime for whichever clause is active.

The robot is simulated: it performs what it is asked, reports it, and checks prohibitions
before acting. User-side events (RetryAgreed, MedicationTaken) are only asked for; the
scenario decides whether the user complies.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cosleec.nodes import TaskNode
from cosleec.runtime import Decision, Manager, Obligation, Task, hedge

Host = Manager | TaskNode  # the embedded Manager, or a task node on ROS

USER_EVENTS = frozenset({"RetryAgreed", "MedicationTaken"})


@dataclass
class Robot:
    """The demo's robot: performs actions by reporting their events to its host."""

    manager: Host
    failing: set[str] = field(default_factory=set)  # actions the robot cannot complete right now
    log: list[str] = field(default_factory=list)
    said: list[str] = field(default_factory=list)

    def do(self, event: str) -> bool:
        """Try to perform ``event``: ask whether it is allowed, then report it; True if done.

        Reports nothing and returns False for a user event (only asked for), an action in
        ``failing``, or an action a prohibition forbids.
        """
        if event in USER_EVENTS:
            self.log.append(f"asks the user for {event}")
            return False
        if event in self.failing:
            self.log.append(f"could not {event}")
            return False
        if not self.manager.request(event):  # a prohibition forbids it: do not act
            self.log.append(f"refrains from {event} (forbidden)")
            return False
        self.log.append(event)
        self.manager.event(event)
        return True

    def say(self, text: str) -> None:
        """Record what the robot says (its explanations); the runtime is not told."""
        self.said.append(text)


class CurtainTask(Task):
    """R1, the paper's curtain rule, as a paper-style task.

    R1: when CurtainOpenRequest then OpenCurtains, unless userUndressed (R1.1), unless
    userDistressed >= high (R1.2).
    """

    rule = "R1"

    def __init__(self, robot: Robot) -> None:
        self.robot = robot

    def default(self, decision: Decision) -> None:
        """R1's default response: open the curtains."""
        self.robot.do("OpenCurtains")

    @hedge(1)  # R1.1: unless userUndressed then Refuse and ExplainWhy
    def refuse_and_explain(self, decision: Decision) -> None:
        """R1.1: refuse, say the decision's explanation, and report ExplainWhy."""
        self.robot.do("Refuse")
        self.robot.say(decision.explanation)
        self.robot.do("ExplainWhy")

    @hedge(2)  # R1.2: unless userDistressed >= high then WarnUser and OpenCurtains
    def warn_then_open(self, decision: Decision) -> None:
        """R1.2: warn the distressed user, then open the curtains anyway."""
        self.robot.do("WarnUser")
        self.robot.do("OpenCurtains")


def install(manager: Host) -> Robot:
    """Bind the tasks and capabilities of this example to ``manager``; returns the robot."""
    robot = Robot(manager)
    manager.bind(CurtainTask(robot))
    for event in sorted(manager.ruleset.responds):  # what some rule may oblige: a capability each

        def capability(ob: Obligation, decision: Decision, event: str = event) -> None:
            if event == "ExplainWhy":
                robot.say(decision.explanation)
            robot.do(event)

        manager.capability(event)(capability)
    return robot
