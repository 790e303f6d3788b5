"""A py_trees tree guarded by the real Manager node over ROS 2 (cosleec.ros.bt_client.RosLink).

The Manager runs in its own process (started and stopped by PID by ``System``), inside the
test's network namespace; the tree's condition is answered by its ``request`` service and
its rule task by its ``decide`` service. ROS 2 only (the link's services are rclpy's here).
"""

from __future__ import annotations

import importlib.util
import time
from typing import Any

import pytest

from cosleec.ros.demo import System
from cosleec.ros.driver import Driver

from .test_interfaces import ask, manager, manager_service

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("py_trees") is None, reason="py_trees (the bt extra) is not installed here"
)


def test_a_trees_condition_and_rule_task_are_answered_by_the_manager_node(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    if backend != "ros2":
        pytest.skip("the behaviour-tree link is tested on ROS 2")
    import py_trees
    from py_trees.common import Status

    from cosleec.bt import Permitted, RuleTask
    from cosleec.ros.bt_client import RosLink

    with System(backend, namespace, env=graph, nodes=[manager("--decide", "events-only")]) as system:
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        service = manager_service(namespace, "request")
        ask(transport, service, "MoveNearUser")  # the service is up
        link = RosLink(transport, manager=service.rsplit("/", 1)[0], namespace=namespace, timeout=5.0)
        cond = Permitted("MoveNearUser", link)
        tree = py_trees.trees.BehaviourTree(cond)
        tree.setup()
        tree.tick()
        assert cond.status == Status.SUCCESS, cond.feedback_message
        driver.event("UserApproaches")  # the vacuum's R3: not MoveNearUser for a while
        tree.tick()
        assert cond.status == Status.FAILURE
        assert "R3" in cond.feedback_message and "MoveNearUser" in cond.feedback_message
        # the rule task: the node decides R1 on CleanRequest; the layer picks the subtree
        driver.set({"userAsleep": True, "userNearby": False})

        def leaf(name: str) -> py_trees.behaviour.Behaviour:
            return py_trees.behaviours.Success(name)

        task = RuleTask(
            "R1", "CleanRequest", link, default=leaf("default"), clauses=[leaf("R1.1"), leaf("R1.2")]
        )
        py_trees.trees.BehaviourTree(task).tick()
        assert task.status == Status.SUCCESS, task.feedback_message
        assert task.decision is not None and task.decision.layer == "R1.1"
        ran = [c.name for c in task.children if c.status == Status.SUCCESS]
        assert ran == ["R1.1"]
        assert [(o["rule"], o["event"], o["deadline"]) for o in link.outstanding()] == [
            ("R1", "Refuse", None)
        ]
        link.event("Refuse")  # reported on the events topic: met, and the Manager hears it
        assert link.outstanding() == []
        end = time.monotonic() + 10  # the node published the decision: the driver heard it
        while "R1" not in [d["rule"] for d in driver.decisions] and time.monotonic() < end:
            time.sleep(0.05)
        assert [d["rule"] for d in driver.decisions] == ["R3", "R1"]
        driver.wait(lambda: driver.status["manager"]["stats"].get("events", 0) >= 3, what="the Refuse report")
        assert system.codes() == [None]
