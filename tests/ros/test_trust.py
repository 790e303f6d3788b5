"""Trustworthy enforcement over real ROS 2 / ROS 1 (COSLEEC_ROS_BACKEND), nodes in their own
processes: malformed messages never deafen a node, a dead executor is reported and ends the
node, a decision sent twice runs once, a silent Manager means no, and two Managers in
different namespaces do not evict each other."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from cosleec.demo.runner import rules_path
from cosleec.nodes import record
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver
from cosleec.ros.launch import node_command, start, stop
from cosleec.runtime import Manager, RuleSet
from tests.ros.test_system import env_with_tests

DEEP = "[" * 100_000  # json.loads raises RecursionError: before, it ended the ROS 2 executor
BIG = "x" * 1_000_000


class Watch:
    """Collects the JSON messages of some topics and waits for conditions on them."""

    def __init__(self, transport: Any, topics: list[str]) -> None:
        self.got: dict[str, list[dict[str, Any]]] = {t: [] for t in topics}
        self._cv = threading.Condition()
        for t in topics:
            transport.subscribe(t, self._sink(t))

    def _sink(self, topic: str) -> Callable[[str], None]:
        def sink(payload: Any) -> None:
            with self._cv:
                self.got[topic].append(record(payload))
                self._cv.notify_all()

        return sink

    def last(self, topic: str, **match: Any) -> dict[str, Any]:
        with self._cv:
            found = [m for m in self.got[topic] if all(m.get(k) == v for k, v in match.items())]
        return max(found, key=lambda m: m.get("seq", 0)) if found else {}

    def wait(self, predicate: Callable[[], bool], timeout: float = 30.0, what: str = "condition") -> None:
        end = time.monotonic() + timeout
        with self._cv:
            while not predicate():
                left = end - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"timed out waiting for {what}")
                self._cv.wait(min(left, 0.2))


def wait_subscribed(transport: Any, topic: str, timeout: float = 20.0) -> None:
    """Advertise ``topic`` and wait until someone subscribes (ROS 1 delivers nothing before)."""
    transport.advertise(topic)
    end = time.monotonic() + timeout
    while transport.subscribers(topic) < 1:
        assert time.monotonic() < end, f"nobody subscribes to {topic}"
        time.sleep(0.02)
    time.sleep(0.3)


def test_malformed_payloads_never_deafen_the_nodes(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, json_wire: str
) -> None:
    with System(backend, namespace, env=graph, wire=json_wire) as system:
        driver = Driver(transport, namespace)
        driver.ready()
        driver.advance(5)
        bad = [
            ("context", DEEP),
            ("events", DEEP),
            ("request", DEEP),
            ("clock", DEEP),
            ("context", '"not an object"'),
            ("events", "null"),
            ("clock", '{"t": ' + "9" * 400 + "}"),
            ("clock", '{"t": NaN}'),
            ("clock", '{"t": Infinity}'),
            ("clock", '{"t": -Infinity}'),
            ("clock", json.dumps({"t": 1})),  # back in time
            ("context", '{"values": {"heartRate": NaN}}'),
            ("context", '{"values": {"heartRate": ' + "9" * 400 + "}}"),
            ("context", json.dumps({"values": {"heartRate": "fast"}})),
            ("context", json.dumps({"values": {BIG: True}})),
            ("events", json.dumps({"event": BIG})),
            ("events", json.dumps({"event": ["CurtainOpenRequest"]})),
            ("request", json.dumps({"id": {"a": 1}, "event": "RecordVideo"})),
        ]
        for topic, payload in bad:
            driver.raw(topic, payload)
        # the task node's input too: it must still run the next real obligation
        wait_subscribed(transport, f"{namespace}/obligations")
        for payload in (DEEP, "[]", json.dumps({"rule": "R1"}), json.dumps({"rule": "R1", "id": "x"})):
            transport.publish(f"{namespace}/obligations", payload)
        driver.quiet(60)

        def manager() -> dict[str, Any]:
            return driver.status.get("manager", {})

        driver.wait(lambda: manager()["counters"]["rejected"] == len(bad), what="every rejection counted")
        driver.wait(
            lambda: driver.status.get("task", {}).get("counters", {}).get("rejected") == 4, what="task"
        )
        reasons = [r["reason"] for r in driver.rejected if r["node"] == "manager"]
        assert all(len(r) < 250 for r in reasons)
        assert any("clock went back" in r for r in reasons)
        assert any("too large for a float" in r for r in reasons)
        # ...and the system still decides, and the task node still runs what it is sent
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.event("CurtainOpenRequest")
        assert (driver.decisions[-1]["rule"], driver.decisions[-1]["clause"]) == ("R1", 1)
        assert manager()["time"] == 5.0
        for name in ("manager", "task", "layers"):
            s = driver.status[name]
            assert s["executor_alive"] is True and s["transport_errors"] == 0, s
            assert s["counters"]["errors"] == 0, s
        assert driver.status["task"]["handled"] == manager()["counters"]["obligations"] >= 1
        assert system.codes() == [None, None, None]


def test_a_callback_that_raises_is_counted_and_the_transport_goes_on(
    backend: str, transport: Any, namespace: str
) -> None:
    got: list[str] = []
    topic = f"{namespace}/guarded"

    def handler(payload: str) -> None:
        if payload == "bad":
            raise RuntimeError("a handler with a bug")
        got.append(payload)

    transport.subscribe(topic, handler)
    wait_subscribed(transport, topic)
    before = transport.errors
    for _ in range(3):
        transport.publish(topic, "bad")
    transport.publish(topic, "good")
    end = time.monotonic() + 20
    while not got:
        assert time.monotonic() < end, "the transport went deaf"
        time.sleep(0.02)
    assert got == ["good"] and transport.errors - before == 3
    assert transport.alive() and transport.ok()


DEAF = """
import sys
from cosleec.nodes import Node
from cosleec.ros.run import serve
from std_msgs.msg import String

def make(t):
    node = Node(t, "{ns}")
    node.name = "deaf"
    def boom(message):
        raise RuntimeError("a callback outside every guard")
    t.node.create_subscription(String, "{ns}/boom", boom, 10)  # raw: no guard
    return node

sys.exit(serve("ros2", "deaf", make, "cosleec_deaf"))
"""


def test_a_dead_ros2_executor_is_reported_and_ends_the_node(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    if backend != "ros2":
        pytest.skip("the ROS 2 executor stops on an exception; rospy goes on")
    watch = Watch(transport, [f"{namespace}/status"])
    proc = subprocess.Popen(
        [sys.executable, "-c", DEAF.format(ns=namespace)], env=graph, stderr=subprocess.PIPE, text=True
    )
    try:
        watch.wait(lambda: watch.last(f"{namespace}/status", node="deaf").get("executor_alive") is True)
        wait_subscribed(transport, f"{namespace}/boom")
        transport.publish(f"{namespace}/boom", "anything")
        assert proc.wait(20) == 1  # not a deaf node with a heartbeat
        watch.wait(lambda: watch.last(f"{namespace}/status", node="deaf").get("executor_alive") is False)
        assert proc.stderr is not None
        assert "the middleware stopped under the deaf node (RuntimeError" in proc.stderr.read()
    finally:
        stop(proc)


@contextmanager
def task_node_alone(
    backend: str, graph: dict[str, str], namespace: str, *args: str
) -> Iterator[subprocess.Popen[bytes]]:
    cmd = [
        "task",
        rules_path(),
        "--module",
        "tests.ros.requesting_tasks",
        "--only",
        "R1",
        "--status-each",
        *args,
    ]
    proc = start(node_command(backend, cmd, namespace), env=env_with_tests(graph))
    try:
        yield proc
    finally:
        stop(proc)


@pytest.mark.parametrize(("choice", "events", "failures"), [("refuse", ["Refuse"], 0), ("raise", [], 1)])
def test_with_no_manager_a_task_request_is_refused_or_raises_and_a_duplicate_runs_once(
    backend: str,
    graph: dict[str, str],
    transport: Any,
    namespace: str,
    choice: str,
    events: list[str],
    failures: int,
) -> None:
    status, events_topic, obligations = (f"{namespace}/{t}" for t in ("status", "events", "obligations"))
    watch = Watch(transport, [status, events_topic])
    transport.advertise(obligations)
    m = Manager(RuleSet.from_file(rules_path()))
    m.update(userUndressed=True, userDistressed="low")
    decision = json.dumps({**m.event("CurtainOpenRequest")[0].to_json(), "session": "forged"})
    with task_node_alone(
        backend, graph, namespace, "--when-manager-down", choice, "--request-timeout", "0.5"
    ) as proc:
        watch.wait(lambda: bool(watch.last(status, node="task")), what="the task node")
        wait_subscribed(transport, obligations)
        transport.publish(obligations, decision)
        transport.publish(obligations, decision)  # the same decision again: not run again

        def settled() -> bool:
            s = watch.last(status, node="task")
            return s.get("handled") == 1 and s["counters"]["duplicates"] == 1

        watch.wait(settled, what="one run and one duplicate")
        time.sleep(1.0)  # nothing more happens
        s = watch.last(status, node="task")
        assert s["handled"] == 1 and s["counters"]["request_timeouts"] == 1 and s["failures"] == failures
        assert [e["event"] for e in watch.got[events_topic]] == events
        assert proc.poll() is None


def test_two_managers_in_different_namespaces_both_stay_up(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    spaces = [f"{namespace}/robot1", f"{namespace}/robot2"]  # same kind, same graph
    watch = Watch(transport, [f"{ns}/status" for ns in spaces])
    procs = [
        start(node_command(backend, ["manager", rules_path(), "--sim-time"], ns), env=graph) for ns in spaces
    ]
    try:
        for ns in spaces:
            watch.wait(lambda ns=ns: bool(watch.last(f"{ns}/status")), what=f"the manager of {ns}")
        seqs = [watch.last(f"{ns}/status")["seq"] for ns in spaces]
        time.sleep(3.0)  # on ROS 1 an evicted node is shut down within moments
        assert [p.poll() for p in procs] == [None, None]
        for ns, seq in zip(spaces, seqs):  # both heartbeats go on
            watch.wait(
                lambda ns=ns, seq=seq: watch.last(f"{ns}/status")["seq"] > seq + 3, what=f"{ns} beating"
            )
    finally:
        for p in procs:
            stop(p)
