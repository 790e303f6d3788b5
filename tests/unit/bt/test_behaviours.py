"""cosleec.bt in real py_trees trees, ticked against an embedded Manager (the assistive-care rules).

Each test builds the tree a mission would, ticks it with py_trees' own machinery
(``BehaviourTree.tick``) and checks the outcome against what the Manager recorded.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from cosleec import Manager, VirtualClock
from cosleec.bt import DECISION_KEY, OBLIGATIONS_KEY, Guarded, Obligations, Permitted, RuleTask
from cosleec.runtime import read_audit

from .conftest import RULES


class Act(py_trees.behaviour.Behaviour):
    """A robot action that takes ``ticks`` ticks (RUNNING until then) and counts its runs."""

    def __init__(self, name: str, ticks: int = 1, result: Status = Status.SUCCESS) -> None:
        super().__init__(name)
        self.ticks, self.result = ticks, result
        self.runs = 0
        self.left = 0

    def initialise(self) -> None:
        self.runs += 1
        self.left = self.ticks

    def update(self) -> Status:
        self.left -= 1
        return Status.RUNNING if self.left > 0 else self.result


@pytest.fixture
def clock() -> VirtualClock:
    return VirtualClock()


@pytest.fixture
def audit(tmp_path: Path) -> Path:
    return tmp_path / "audit.jsonl"


@pytest.fixture
def manager(clock: VirtualClock, audit: Path) -> Any:
    m = Manager.from_file(RULES, clock=clock, audit=str(audit))
    m.start(check=False)  # the tree implements the rules: no tasks are bound
    m.update(userUndressed=False, userDistressed="low", userConsent=False, medicalEmergency=False)
    yield m
    m.close()


def tick(root: py_trees.behaviour.Behaviour) -> py_trees.trees.BehaviourTree:
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    tree.tick()
    return tree


def test_the_condition_says_permitted_or_refused_with_the_managers_reason(manager: Any) -> None:
    cond = Permitted("RecordVideo", manager)
    tree = tick(cond)
    assert cond.status == Status.SUCCESS
    assert cond.feedback_message == "RecordVideo is permitted: no prohibition in force forbids it now"
    manager.event("UserFallen")  # R6: not RecordVideo within 10 minutes, unless userConsent
    tree.tick()
    assert cond.status == Status.FAILURE
    assert cond.feedback_message.startswith("RecordVideo is forbidden by R6 for another 10 min")
    assert "userConsent was false" in cond.feedback_message


def test_the_condition_ticked_again_and_again_is_a_question_not_an_attempt(manager: Any, audit: Path) -> None:
    cond = Permitted("RecordVideo", manager)
    manager.event("UserFallen")
    tree = tick(cond)
    for _ in range(9):  # a tree ticks at 10 Hz: before, each tick counted a refusal
        tree.tick()
    assert cond.status == Status.FAILURE and manager.stats["refused"] == 0
    assert not [r for r in read_audit(audit) if r["kind"] == "refused"]


def test_the_decorator_blocks_a_forbidden_child_and_reports_it_after_success(
    manager: Any, clock: VirtualClock, audit: Path
) -> None:
    record = Act("record video", ticks=2)
    guard = Guarded("RecordVideo", record, manager)
    manager.event("UserFallen")
    tree = tick(guard)
    assert guard.status == Status.FAILURE and record.runs == 0  # the child never started
    assert "forbidden by R6" in guard.feedback_message
    clock.advance(601)  # the prohibition's window has closed
    manager.tick()
    tree.tick()
    assert guard.status == Status.RUNNING and record.runs == 1
    assert not [r for r in read_audit(audit) if r["kind"] == "event" and r["event"] == "RecordVideo"]
    tree.tick()
    assert guard.status == Status.SUCCESS
    records = read_audit(audit)
    refused = [r for r in records if r["kind"] == "refused"]
    assert [(r["event"], r["by"], r["source"]) for r in refused] == [
        ("RecordVideo", ["R6"], "Guard RecordVideo")
    ]
    occurred = [r["time"] for r in records if r["kind"] == "event" and r["event"] == "RecordVideo"]
    assert occurred == [601.0]  # reported once, when the child succeeded


def test_a_failed_child_reports_nothing(manager: Any, audit: Path) -> None:
    guard = Guarded("OpenCurtains", Act("open", result=Status.FAILURE), manager)
    tick(guard)
    assert guard.status == Status.FAILURE
    assert not [r for r in read_audit(audit) if r["kind"] == "event"]


def curtain_task(manager: Any) -> tuple[RuleTask, dict[str, Act]]:
    acts = {k: Act(k) for k in ("default", "R1.1", "R1.2")}
    task = RuleTask(
        "R1", "CurtainOpenRequest", manager, default=acts["default"], clauses=[acts["R1.1"], acts["R1.2"]]
    )
    return task, acts


@pytest.mark.parametrize(
    ("values", "runs"),
    [
        ({"userUndressed": False, "userDistressed": "low"}, "default"),
        ({"userUndressed": True, "userDistressed": "low"}, "R1.1"),
        ({"userUndressed": False, "userDistressed": "high"}, "R1.2"),
        ({"userUndressed": True, "userDistressed": "high"}, "R1.2"),  # the last clause that holds wins
    ],
)
def test_the_rule_task_runs_the_subtree_of_the_layer_the_manager_chose(
    manager: Any, values: dict[str, Any], runs: str
) -> None:
    manager.update(values)
    task, acts = curtain_task(manager)
    tick(task)
    assert task.status == Status.SUCCESS
    assert {k: a.runs for k, a in acts.items()} == {k: int(k == runs) for k in acts}
    assert task.decision is not None and (task.decision.layer or "default") == runs
    board = py_trees.blackboard.Client(name="reader")
    board.register_key(key=f"{DECISION_KEY}/R1", access=py_trees.common.Access.READ)
    assert board.get(f"{DECISION_KEY}/R1") is task.decision


def test_an_undetermined_decision_runs_nothing_and_fails_with_why(clock: VirtualClock) -> None:
    m = Manager.from_file(RULES, clock=clock)
    m.start(check=False)
    task, acts = curtain_task(m)
    tick(task)  # userUndressed has no value: no clause can be chosen
    assert task.status == Status.FAILURE and all(a.runs == 0 for a in acts.values())
    assert "undetermined" in task.feedback_message and "userUndressed" in task.feedback_message
    m.close()


def test_a_tree_with_too_few_subtrees_fails_naming_the_layer(manager: Any) -> None:
    manager.update(userDistressed="high")
    task = RuleTask("R1", "CurtainOpenRequest", manager, default=Act("open"), clauses=[Act("refuse")])
    tick(task)
    assert task.status == Status.FAILURE
    assert "R1.2" in task.feedback_message and "1 clause subtree" in task.feedback_message


def test_obligations_appear_on_the_blackboard_and_go_when_met(manager: Any, clock: VirtualClock) -> None:
    # the default subtree opens the curtains through a guard: the report meets R1's obligation
    opened = Guarded("OpenCurtains", Act("open", ticks=2), manager)
    task = RuleTask("R1", "CurtainOpenRequest", manager, default=opened, clauses=[Act("refuse"), Act("warn")])
    once = py_trees.decorators.OneShot("once", task, py_trees.common.OneShotPolicy.ON_SUCCESSFUL_COMPLETION)
    root = py_trees.composites.Sequence("mission", memory=False, children=[Obligations(manager), once])
    board = py_trees.blackboard.Client(name="reader")
    board.register_key(key=OBLIGATIONS_KEY, access=py_trees.common.Access.READ)
    tree = tick(root)  # the trigger is reported: R1 owes OpenCurtains within 30 s
    assert task.status == Status.RUNNING
    clock.advance(5)
    tree.tick()  # the Obligations leaf runs first: it sees what the first tick's decision owes
    owed = board.get(OBLIGATIONS_KEY)
    assert [(o["rule"], o["event"], o["deadline"], o["clause"]) for o in owed] == [
        ("R1", "OpenCurtains", 30.0, 0)
    ]
    assert root.children[0].feedback_message == "1 owed, next OpenCurtains by 30 s (R1)"
    assert task.status == Status.SUCCESS  # the guard reported OpenCurtains on this tick
    tree.tick()  # the one shot does not report the trigger again
    assert board.get(OBLIGATIONS_KEY) == []
    assert root.children[0].feedback_message == "0 owed"
    assert manager.outstanding() == []
