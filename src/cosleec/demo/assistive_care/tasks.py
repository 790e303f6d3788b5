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

from cosleec.runtime import Decision, Manager, Obligation, Task, hedge

USER_EVENTS = frozenset({"RetryAgreed", "MedicationTaken"})


@dataclass
class Robot:
    manager: Manager
    failing: set[str] = field(default_factory=set)  # actions the robot cannot complete right now
    log: list[str] = field(default_factory=list)
    said: list[str] = field(default_factory=list)

    def do(self, event: str) -> bool:
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
        self.manager.report(event)
        return True

    def say(self, text: str) -> None:
        self.said.append(text)


class CurtainTask(Task):
    """R1: WHEN CurtainOpenRequest THEN OpenCurtains UNLESS UserUndressed ... UNLESS UserDistressed ..."""

    rule = "R1"

    def __init__(self, robot: Robot) -> None:
        self.robot = robot

    def default(self, decision: Decision) -> None:
        self.robot.do("OpenCurtains")

    @hedge(1)  # R1.1: unless userUndressed then Refuse and ExplainWhy
    def refuse_and_explain(self, decision: Decision) -> None:
        self.robot.do("Refuse")
        self.robot.say(decision.explanation)
        self.robot.do("ExplainWhy")

    @hedge(2)  # R1.2: unless userDistressed >= high then WarnUser and OpenCurtains
    def warn_then_open(self, decision: Decision) -> None:
        self.robot.do("WarnUser")
        self.robot.do("OpenCurtains")


def install(manager: Manager) -> Robot:
    """Bind the tasks and capabilities of this example to ``manager``; returns the robot."""
    robot = Robot(manager)
    manager.bind(CurtainTask(robot))
    events = {e.name for e in manager.spec.events}
    for event in sorted(events):

        def capability(ob: Obligation, decision: Decision, event: str = event) -> None:
            if event == "ExplainWhy":
                robot.say(decision.explanation)
            robot.do(event)

        manager.capability(event)(capability)
    return robot
