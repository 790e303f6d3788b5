"""A restarted Manager node publishes again what it may never have published -- to the task
nodes, not merely to whoever happened to be matched first.

On ROS 2 a restarted node's ``obligations`` publisher is new: DDS matches each subscriber
on its own, seconds apart when a participant's discovery is slow (the kill campaign saw a
task node matched 2.5 s after the driver). :class:`Discovery` plays that on the in-process
bus: the Manager's transport says how many subscribers it has matched (as rclpy's
``get_subscription_count``), and the task node hears ``obligations`` only once it is matched.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from cosleec.nodes import LocalBus, ManagerNode, TaskNode, manager_node
from cosleec.nodes.transport import LocalTransport
from cosleec.runtime import Manager, RuleSet, VirtualClock

from .support import collect

RULES = RuleSet.from_text(
    "def_start event X event A def_end rule_start R1 when X then A within 10 seconds rule_end"
)


class Discovery:
    """Who the Manager's ``obligations`` publisher has matched: a watcher (a driver, a recorder)
    at once, the task node only once :attr:`task_matched` is set."""

    def __init__(self) -> None:
        self.watchers = 1
        self.task_matched = False
        self.others = 0  # subscribers matched later still (a task node restarted, a recorder)

    def manager(self, bus: LocalBus) -> LocalTransport:
        """The Manager's transport: it counts the subscribers matched on ``obligations``."""
        discovery = self

        class Matched(LocalTransport):
            def subscribers(self, topic: str) -> int:
                return (
                    discovery.watchers + discovery.task_matched + discovery.others
                    if topic.endswith("/obligations")
                    else 1
                )

        return Matched(bus)

    def task(self, bus: LocalBus) -> LocalTransport:
        """The task node's transport: ``obligations`` sent before it was matched never reach it."""
        discovery = self

        class Unmatched(LocalTransport):
            def subscribe(self, topic: str, handler: Callable[[str], None]) -> None:
                if topic.endswith("/obligations"):
                    inner = handler

                    def handler(payload: str) -> None:
                        if discovery.task_matched:
                            inner(payload)

                super().subscribe(topic, handler)

        return Unmatched(bus)


def decided_never_published(tmp_path: Path) -> Path:
    """A journal holding a decision (R1: A) that a killed Manager node committed and never published."""
    journal = tmp_path / "state.db"
    m = Manager(RULES, journal=journal, dispatch=False, clock=VirtualClock())
    m.event("X")
    m.journal.close()  # type: ignore[union-attr]  # no close(): nothing of a clean stop
    return journal


def heartbeat(node: ManagerNode, until: Callable[[], bool], what: str, timeout: float = 5.0) -> None:
    """Call the node's status as its heartbeat does (:func:`cosleec.ros.serve`) until ``until()``."""
    end = time.monotonic() + timeout
    while not until():
        assert time.monotonic() < end, f"timed out waiting for {what}: {node.counters}"
        node.status()
        time.sleep(0.01)


def beats(node: ManagerNode, seconds: float) -> None:
    """Heartbeats for ``seconds``."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        node.status()
        time.sleep(0.01)


@pytest.fixture
def quick(monkeypatch: pytest.MonkeyPatch) -> None:
    """Subscribers settle in 50 ms; a republished decision is confirmed after 0.3 s of no change."""
    monkeypatch.setattr(manager_node, "REPUBLISH_SETTLE_S", 0.05)
    monkeypatch.setattr(manager_node, "REPUBLISH_WINDOW_S", 0.3)


def test_a_task_node_matched_after_the_republish_still_runs_it(
    bus: LocalBus, tmp_path: Path, quick: None
) -> None:
    journal = decided_never_published(tmp_path)
    discovery = Discovery()
    task = TaskNode(discovery.task(bus), RULES)
    ran: list[tuple[int, str]] = []
    task.capability("A")(lambda ob, d: ran.append((d.id, "A")))
    task.start()
    watcher = collect(bus, "/cosleec/obligations")  # matched at once: the subscriber count is 1, steady
    node = ManagerNode(discovery.manager(bus), RULES, journal=str(journal), sim_time=True)
    heartbeat(node, lambda: node.counters.get("republished", 0) == 1, "the republish")
    node.manager.event("X")  # decided now, while the task node is still not matched
    assert bus.wait_idle()
    assert len(watcher) == 2 and task.handled_total == 0  # both sent to the watcher alone
    discovery.task_matched = True  # before: never heard, and the journal's outbox let decision 1 go
    heartbeat(node, lambda: task.handled_total == 2, "the task node to run both")
    assert bus.wait_idle()
    assert ran == [(1, "A"), (2, "A")] and len(watcher) == 4
    # sent again to whoever was matched late, counted apart: `obligations` counts decisions handed on
    assert node.counters["obligations"] == 2 and node.counters["resent"] == 2
    heartbeat(node, lambda: not node._unconfirmed, "the window to pass")  # the subscribers stayed the same
    discovery.others = 1  # a subscriber matched after that (a restarted task node) gets nothing again
    beats(node, 0.2)
    assert bus.wait_idle()
    assert node.counters["resent"] == 2 and len(watcher) == 4 and task.handled_total == 2
    node.close()
    task.close()


def test_a_republished_decision_leaves_the_outbox_only_once_the_subscribers_stayed_the_same(
    bus: LocalBus, tmp_path: Path, quick: None
) -> None:
    journal = decided_never_published(tmp_path)
    discovery = Discovery()
    first = ManagerNode(discovery.manager(bus), RULES, journal=str(journal), sim_time=True)
    heartbeat(first, lambda: first.counters.get("republished", 0) == 1, "the republish")
    first.manager.tick()  # a step commits: before, the decision left the outbox with it
    first.manager.journal.close()  # type: ignore[union-attr]  # killed before the window passed
    second = ManagerNode(discovery.manager(bus), RULES, journal=str(journal), sim_time=True)
    # perhaps still unheard (a task node may have been matched later): published again
    heartbeat(second, lambda: second.counters.get("republished", 0) == 1, "the republish")
    heartbeat(second, lambda: not second._unconfirmed, "the window to pass")  # the subscribers stayed 0.3 s
    second.manager.tick()
    second.manager.journal.close()  # type: ignore[union-attr]
    third = ManagerNode(discovery.manager(bus), RULES, journal=str(journal), sim_time=True)
    beats(third, 0.1)
    assert third.counters.get("republished", 0) == 0 and third.counters.get("obligations", 0) == 0
    third.close()


def test_status_says_how_many_decisions_are_held_until_the_task_nodes_can_hear_them(
    bus: LocalBus, tmp_path: Path, quick: None
) -> None:
    journal = decided_never_published(tmp_path)
    discovery = Discovery()
    discovery.watchers = 0  # nobody listens yet
    statuses = collect(bus, "/cosleec/status")
    node = ManagerNode(discovery.manager(bus), RULES, journal=str(journal), sim_time=True, status_each=True)
    node.manager.event("X")  # decided while the republish waits: held behind it, in order
    node.status()
    assert bus.wait_idle()
    last: dict[str, Any] = statuses[-1]
    # a harness waiting for "every obligation handed on" must see these: `obligations` is still 0
    assert last["holding"] == 2 and last["counters"].get("obligations", 0) == 0
    discovery.watchers = 1
    heartbeat(node, lambda: node.counters.get("obligations", 0) == 2, "both handed on")
    node.status()
    assert bus.wait_idle()
    assert statuses[-1]["holding"] == 0
    node.close()
