"""C++ can use cosleec_interfaces, on real ROS 2 and ROS 1 (COSLEEC_ROS_BACKEND).

One small translation unit per backend (``tests/ros/cpp/cosleec_<backend>.cpp``) is compiled
with g++ against what ``scripts/build-interfaces`` generated (``cpp_build``): on ROS 2 the
rosidl C++ headers and type support beside the ros-jazzy-* wheels' ``rcl``; on ROS 1 Debian's
roscpp and the gencpp headers. It fills a ``Decision`` and a permission request and response
and prints them with the generators' own printers (``to_yaml``, ``operator<<``); what it
prints and the bytes it serializes are read back with the Python types (rclpy, genpy), so the
C++ and Python sides must agree field for field on the wire. Then the same binary asks a
running Manager node's permission service (over rcl on ROS 2, inside the test's network
namespace; over roscpp on ROS 1) and must get the answer the rules give, while the Manager
publishes the refusal with the source the C++ caller gave.

A service named ``Request`` could not be compiled as C++ at all (a struct ``Request`` nested
in ``Request``): these tests fail if the interfaces lose their C++ side again.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from cosleec.ros.demo import System
from cosleec.ros.driver import Driver

from .cpp_build import build
from .test_interfaces import Typed, manager, manager_service

EXPLANATION = "R1: do not open the curtains, because userUndressed was true"


@pytest.fixture(scope="module")
def program(backend: str, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    """The backend's C++ program, compiled once for this module into a temporary directory."""
    binary, env, took = build(backend, tmp_path_factory.mktemp("cpp") / f"cosleec_{backend}")
    print(f"g++ built {binary.name} in {took:.1f} s")
    return binary, env


def run(program: tuple[Path, dict[str, str]], graph: dict[str, str], *args: str) -> str:
    """Run the program with ``args`` in the test's ROS environment; its stdout (it must exit 0)."""
    binary, env = program
    done = subprocess.run(
        [str(binary), *args], env={**os.environ, **graph, **env}, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, f"{binary.name} {' '.join(args)} exited {done.returncode}: {done.stderr}"
    return done.stdout


def sections(text: str) -> dict[str, str]:
    """The program's output split at its ``=== <title>`` lines: title -> the text below it."""
    out: dict[str, str] = {}
    title = None
    for line in text.splitlines(keepends=True):
        if line.startswith("=== "):
            title = line[4:].strip()
            out[title] = ""
        elif title is not None:
            out[title] += line
    return out


def check_decision(d: Any) -> None:
    """``d`` (a Decision read by the Python types) holds what the C++ program filled in."""
    assert (d.header.frame_id, d.id, d.session, d.trigger) == ("map", 7, "s-1", "CurtainOpenRequest")
    assert (d.rule, d.clause, d.layer, d.semantics) == ("R1", 1, "R1.1", "last-wins")
    assert [(v.name, v.kind, v.boolean) for v in d.values] == [("userUndressed", 1, True)]
    o = d.obligations[0]
    assert (o.decision, o.rule, o.event, o.prohibition, o.deadline) == (7, "R1", "CurtainOpened", True, 60.0)
    assert list(d.missing) == ["roomDark"]
    assert (d.explanation, d.sender, d.seq) == (EXPLANATION, "cpp", 3)


def check_ros2_print(out: dict[str, str]) -> None:
    """ROS 2: the to_yaml texts are YAML with the fields set, the CDR bytes decode in rclpy."""
    from cosleec_interfaces.msg import Decision
    from rclpy.serialization import deserialize_message, serialize_message

    assert list(out) == [
        "cosleec_interfaces/msg/Decision",
        "cosleec_interfaces/srv/AskPermission_Request",
        "cosleec_interfaces/srv/AskPermission_Response",
        "cosleec_interfaces/srv/AskPermission",
        "cdr",
    ]
    shown = yaml.safe_load(out["cosleec_interfaces/msg/Decision"])
    assert shown["layer"] == "R1.1" and shown["explanation"] == EXPLANATION
    assert shown["values"] == [
        {"name": "userUndressed", "kind": 1, "boolean": True, "number": 0.0, "text": ""}
    ]
    assert yaml.safe_load(out["cosleec_interfaces/srv/AskPermission_Request"]) == {
        "event": "OpenCurtains",
        "source": "cpp_planner",
    }
    assert yaml.safe_load(out["cosleec_interfaces/srv/AskPermission_Response"]) == {
        "permitted": False,
        "rules": ["R1"],
        "reason": "OpenCurtains is forbidden by R1",
    }
    cdr = bytes.fromhex(out["cdr"].strip())
    decoded = deserialize_message(cdr, Decision)
    check_decision(decoded)
    # rclpy's encoding has the same layout (the alignment padding bytes may differ: unset)
    assert len(serialize_message(decoded)) == len(cdr)


def check_ros1_print(out: dict[str, str]) -> None:
    """ROS 1: gencpp's type names and md5sums are genpy's, the roscpp bytes decode in genpy."""
    from cosleec_interfaces.msg import Decision
    from cosleec_interfaces.srv import AskPermission, AskPermissionRequest, AskPermissionResponse

    titles = [
        f"{t._type} {t._md5sum}"
        for t in (Decision, AskPermissionRequest, AskPermissionResponse, AskPermission)
    ]
    assert list(out) == [*titles, "wire"]
    assert AskPermission._type == "cosleec_interfaces/AskPermission"
    # ROS 1 matches a service by md5sum: still that of cosleec_interfaces 0.1.0's `Request`
    # (CHANGELOG.md), so a rospy or roscpp client built before the rename is still answered
    assert AskPermission._md5sum == "a82edcc221aa1854d95680b3f6a1f172"
    shown = out[titles[0]].splitlines()
    for line in ("rule: R1", "layer: R1.1", "  missing[0]: roomDark", f"explanation: {EXPLANATION}"):
        assert line in shown
    assert out[titles[1]].splitlines() == ["event: OpenCurtains", "source: cpp_planner"]
    assert out[titles[2]].splitlines() == [
        "permitted: 0",
        "rules[]",
        "  rules[0]: R1",
        "reason: OpenCurtains is forbidden by R1",
    ]
    wire = bytes.fromhex(out["wire"].strip())
    decoded = Decision().deserialize(wire)
    check_decision(decoded)
    assert decoded.header.stamp.secs == 12


def test_a_cpp_program_fills_the_generated_types_and_prints_them(
    backend: str, graph: dict[str, str], program: tuple[Path, dict[str, str]]
) -> None:
    out = sections(run(program, graph, "print"))
    if backend == "ros2":
        check_ros2_print(out)
    else:
        check_ros1_print(out)


def answer(backend: str, text: str) -> dict[str, Any]:
    """The printed AskPermission response as {permitted, rules, reason}."""
    if backend == "ros2":
        parsed: dict[str, Any] = yaml.safe_load(text)
        return parsed
    lines = text.splitlines()  # operator<<: "permitted: 0", "rules[]", "  rules[0]: R3", "reason: ..."
    return {
        "permitted": lines[0] == "permitted: 1",
        "rules": [line.split(": ", 1)[1] for line in lines if line.startswith("  rules[")],
        "reason": next(line[len("reason: ") :] for line in lines if line.startswith("reason: ")),
    }


def test_a_cpp_program_asks_the_manager_node_for_permission(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, program: tuple[Path, dict[str, str]]
) -> None:
    with System(backend, namespace, env=graph, nodes=[manager()]) as system:
        refusals = Typed(transport, f"{namespace}/refusals", "cosleec_interfaces/msg/Refusal")
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        service = manager_service(namespace, "request")
        yes = answer(backend, run(program, graph, "ask", service, "MoveNearUser", "cpp_planner", "30"))
        assert yes == {"permitted": True, "rules": [], "reason": yes["reason"]}
        driver.event("UserApproaches")  # R3: MoveNearUser is forbidden for 30 s
        no = answer(backend, run(program, graph, "ask", service, "MoveNearUser", "cpp_planner", "30"))
        assert no["permitted"] is False and no["rules"] == ["R3"]
        assert "R3" in no["reason"] and "MoveNearUser" in no["reason"]
        refusals.wait(
            lambda got: any(r["source"] == "cpp_planner" and r["event"] == "MoveNearUser" for r in got),
            what="the refusal of the C++ caller's request, with its source",
        )
        assert system.codes() == [None]
