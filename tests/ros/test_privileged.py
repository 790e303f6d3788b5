"""Privileged operations stay privileged, and health tells the truth, on real ROS 2 / ROS 1
(COSLEEC_ROS_BACKEND): issue 28, findings 7, 12 and 14. Each test is named next to the
claim it backs in docs/ros.md, "Threat model".

- ``~/reload`` from another participant reads only what the operator allowed: a refused
  path gets one fixed answer, whatever it names, and every attempt is in the audit log
  with its caller where the middleware says who called (ROS 1), none where it cannot
  (ROS 2: rclpy does not tell a service callback who called).
- ``~/decide`` is off unless the operator turns it on.
- A typed message or service request that cannot be decoded gets a ``rejected`` record.
- A guard whose Manager is gone says ERROR on ``/diagnostics``, and OK once it answers.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from cosleec.cli.ros import node_name
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver
from cosleec.ros.launch import node_command, start, stop
from cosleec.ros.messages import message_class
from cosleec.runtime import RuleSet, read_audit

from .test_interfaces import RULES, Typed, _level, ask, manager, manager_service

SECRET = "root:x:0:0:root:/root:/bin/bash"
GROWN = "    R4 when BatteryLow then Refuse within 5 seconds\nrule_end"


def call(transport: Any, service: str, kind: str, fields: dict[str, Any]) -> dict[str, Any]:
    """Call one of the Manager's services through the test's transport and return its answer."""
    box: list[dict[str, Any] | None] = []
    done = threading.Event()
    transport.ask(service, kind, fields, lambda a: (box.append(a), done.set()), 20.0)
    assert done.wait(25) and box[0] is not None, f"{service} did not answer"
    return box[0]


def call_raw(backend: str, transport: Any, service: str, kind: str, fill: Any) -> Any:
    """Call ``service`` with a request ``fill`` writes by hand (a value no client of ours would send)."""
    cls = transport._wire.services().service_type(kind)
    if backend == "ros2":
        client = transport.node.create_client(cls, service)
        assert client.wait_for_service(timeout_sec=20)
        req = cls.Request()
        fill(req)
        future = client.call_async(req)
        end = time.monotonic() + 20
        while not future.done():
            assert time.monotonic() < end, f"{service} did not answer"
            time.sleep(0.02)
        return future.result()
    import rospy

    rospy.wait_for_service(service, 20)
    req = cls._request_class()
    fill(req)
    return rospy.ServiceProxy(service, cls)(req)


def records(path: Path, kind: str) -> list[dict[str, Any]]:
    return [r for r in read_audit(str(path)) if r["kind"] == kind]


def test_reload_and_decide_take_only_what_the_operator_allowed_and_every_attempt_is_recorded(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    run, allowed, outside = (tmp_path / d for d in ("run", "allowed", "outside"))
    for d in (run, allowed, outside):
        d.mkdir()
    rules = run / "rules.sleec"
    shutil.copy(RULES, rules)
    grown = rules.read_text().replace("rule_end", GROWN)
    (allowed / "grown.sleec").write_text(grown)
    (outside / "grown.sleec").write_text(grown)  # good rules in the wrong place
    (outside / "passwd").write_text(SECRET + "\n")
    audit = tmp_path / "audit.jsonl"
    nodes = [["manager", str(rules), "--sim-time", "--status-each", "--audit", str(audit), "--reload-dir", str(allowed)]]  # fmt: skip
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        before = driver.status["manager"]["rules_hash"]
        reload = manager_service(namespace, "reload")
        refused = [
            call(transport, reload, "reload", {"rules": path})
            for path in ("/etc/passwd", str(outside / "passwd"), str(outside / "grown.sleec"), "/nonexistent")
        ]
        assert len({r["message"] for r in refused}) == 1  # one fixed answer: no oracle
        assert all(r["success"] is False and r["current_hash"] == before for r in refused)
        assert refused[0]["message"].startswith("reload refused") and SECRET not in refused[0]["message"]
        ok = call(transport, reload, "reload", {"rules": str(allowed / "grown.sleec")})
        assert ok["success"] is True and ok["current_hash"] == RuleSet.from_text(grown).digest
        # ~/decide is off by default: another participant cannot set values through it
        decide = call(
            transport, manager_service(namespace, "decide"), "decide", {"values": {"userNearby": False}}
        )
        assert decide["accepted"] is False and decide["error"].startswith("~/decide is off")
        assert system.codes() == [None]
    attempts = records(audit, "reload-attempt")
    assert [r["outcome"] for r in attempts] == ["refused"] * 4 + ["reloaded"]
    assert [r["path"] for r in attempts][:2] == ["/etc/passwd", str(outside / "passwd")]
    assert all("file" not in r for r in attempts[:4])  # nothing refused was read
    assert (attempts[-1]["previous_hash"], attempts[-1]["current_hash"]) == (before, ok["current_hash"])
    # ROS 1 says who called (the caller's own claim); rclpy tells a service callback nothing
    callers = {r["caller"] for r in attempts}
    assert callers == ({"/cosleec_test_driver"} if backend == "ros1" else {None})
    (rejected,) = records(audit, "rejected")
    assert rejected["what"] == "decide" and rejected["reason"].startswith("~/decide is off")


def test_typed_messages_and_requests_that_cannot_be_decoded_get_their_rejected_record(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    audit = tmp_path / "audit.jsonl"
    with System(backend, namespace, env=graph, nodes=[manager("--audit", str(audit), "--decide", "all")]):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        value = message_class("cosleec_interfaces/MeasureValue")
        update = message_class("cosleec_interfaces/ContextUpdate")
        publisher = transport._pubs[f"{namespace}/context"]  # the driver's typed `context` publisher
        bad_kind = value(name="userNearby", kind=9)
        twice = [
            value(name="userNearby", kind=1, boolean=True),
            value(name="userNearby", kind=1, boolean=False),
        ]
        for values in ([bad_kind], twice):
            driver.sent += 1
            publisher.publish(update(values=values))
        driver.wait(lambda: driver.status["manager"]["counters"]["rejected"] == 2, what="two rejections")
        answer = call_raw(
            backend,
            transport,
            manager_service(namespace, "decide"),
            "decide",
            lambda req: setattr(req, "values", [value(name="userNearby", kind=9)]),
        )
        assert answer.accepted is False and "kind 9" in answer.error
        driver.wait(
            lambda: driver.status["manager"]["counters"]["rejected"] == 3, what="the Decide rejection"
        )
    got = records(audit, "rejected")
    assert [(r["what"], r["topic"]) for r in got] == [
        ("context", f"{namespace}/context"),
        ("context", f"{namespace}/context"),
        ("decide", "~/decide"),
    ]
    assert "kind 9" in got[0]["reason"] and "given twice" in got[1]["reason"] and "kind 9" in got[2]["reason"]
    assert got[2].get("caller") == ("/cosleec_test_driver" if backend == "ros1" else None)
    assert all("payload" not in r for r in got)  # a typed message that cannot be read shows nothing


def test_a_guard_whose_manager_is_gone_reports_error_on_diagnostics_and_ok_once_it_answers(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    diagnostics = Typed(transport, "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
    twist = "geometry_msgs/msg/Twist"
    source, target = f"{namespace}/planner/cmd_vel", f"{namespace}/cmd_vel"
    guard = ["guard", "--from", source, "--to", target, "--type", twist, "--event", "MoveNearUser", "--timeout", "0.3"]  # fmt: skip
    mine = node_name(namespace, "guard")

    def latest(got: list[dict[str, Any]]) -> tuple[int, str] | None:
        found = None
        for arr in got:
            for st in arr["status"]:
                if mine in st["name"]:
                    found = (_level(st["level"]), st["message"])
        return found

    def until(level: int, what: str) -> tuple[int, str]:
        end = time.monotonic() + 40
        while True:
            state = latest(diagnostics.got)
            if state is not None and state[0] == level:
                return state
            assert time.monotonic() < end, f"no {what}; last {state}"
            transport.publish_typed(source, twist, {})
            time.sleep(0.2)

    with System(backend, namespace, env=graph, nodes=[guard]) as system:
        _, message = until(2, "ERROR from the guard without its Manager")
        assert message.startswith(f"the Manager (/{node_name(namespace, 'manager')}/request) did not answer")
        assert "every guarded message is blocked" in message
        proc = start(node_command(backend, manager(), namespace), env=graph)
        try:
            ask(transport, manager_service(namespace, "request"), "MoveNearUser")  # it is up
            assert until(0, "OK once the Manager answers") == (0, "ok")
        finally:
            stop(proc)
        assert system.codes() == [None]


# ----------------------------------------------------------------------------- what cosleec cannot prevent


def test_an_impostor_answering_on_the_managers_request_service_is_believed_by_the_guard(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    # without authentication a service name proves nothing: whoever answers is "the Manager"
    twist = "geometry_msgs/msg/Twist"
    source, target = f"{namespace}/planner/cmd_vel", f"{namespace}/cmd_vel"
    guard = ["guard", "--from", source, "--to", target, "--type", twist, "--event", "MoveNearUser"]
    out = Typed(transport, target, twist)
    lies = {"permitted": True, "rules": [], "reason": "an impostor says yes"}
    transport.serve(manager_service(namespace, "request"), "request", lambda fields: lies)
    with System(backend, namespace, env=graph, nodes=[guard]) as system:
        end = time.monotonic() + 40
        while not out.got:
            assert time.monotonic() < end, "the guard never forwarded"
            transport.publish_typed(source, twist, {})
            time.sleep(0.2)
        assert system.codes() == [None]


def test_on_ros1_a_node_that_takes_the_managers_name_stops_it_and_enforcement_fails_closed(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    if backend != "ros1":
        pytest.skip("ROS 2 warns of two nodes of one name but stops neither; ROS 1 shuts the older down")
    first = start(node_command(backend, manager(), namespace), env=graph)
    try:
        ask(transport, manager_service(namespace, "request"), "MoveNearUser")  # the first is up
        second = start(node_command(backend, manager(), namespace), env=graph)
        try:
            assert first.wait(30) == 1  # "the middleware stopped under the manager node"
        finally:
            stop(second)
    finally:
        stop(first)


def test_the_ros2_wheels_dds_is_built_without_security_so_sros2_cannot_be_enabled(backend: str) -> None:
    if backend != "ros2":
        pytest.skip("about the ROS 2 wheels' Fast DDS")
    libs = sorted(Path(sys.prefix, "lib").glob("libfastrtps.so.*"))
    assert libs, f"no Fast DDS library under {sys.prefix}/lib"
    data = libs[-1].read_bytes()
    assert b"security is disabled" in data  # what it says to a peer that offers security tokens
    assert b"PKI-DH" not in data and b"Access-Permissions" not in data  # no built-in security plugin
