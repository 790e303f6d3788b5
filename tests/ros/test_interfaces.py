"""CO-SLEEC as a ROS developer expects it, on real ROS 2 / ROS 1 (COSLEEC_ROS_BACKEND):
typed ``cosleec_interfaces`` topics and services, QoS, parameters, ``/clock``,
``/diagnostics``, the lifecycle Manager, reloading rules and the guard.

Every node runs in its own process, started and stopped by PID; the vacuum robot of
``examples/ros/vacuum`` is the system under test, its topics moved under each test's
namespace so that tests cannot hear each other.
"""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from cosleec.cli.ros import node_name
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver

ROOT = Path(__file__).resolve().parents[2]
VACUUM = ROOT / "examples" / "ros" / "vacuum"
RULES = str(VACUUM / "rules.sleec")


class Typed:
    """Collects the typed messages of one topic (as dicts of their fields) and waits on them."""

    def __init__(self, transport: Any, topic: str, type_name: str, qos: Any = None) -> None:
        self.got: list[dict[str, Any]] = []
        self._cv = threading.Condition()
        transport.subscribe_typed(topic, type_name, self._sink, qos)

    def _sink(self, fields: dict[str, Any]) -> None:
        with self._cv:
            self.got.append(fields)
            self._cv.notify_all()

    def wait(
        self, predicate: Callable[[list[dict[str, Any]]], bool], timeout: float = 30.0, what: str = ""
    ) -> None:
        end = time.monotonic() + timeout
        with self._cv:
            while not predicate(self.got):
                left = end - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"timed out waiting for {what}; got {self.got[-3:]}")
                self._cv.wait(min(left, 0.2))


def ask(transport: Any, service: str, event: str, timeout: float = 20.0) -> dict[str, Any]:
    """Call the Manager's Request service until it answers (it may still be starting)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        done = threading.Event()
        box: list[dict[str, Any] | None] = []

        def answer(a: dict[str, Any] | None, box: list[Any] = box, done: threading.Event = done) -> None:
            box.append(a)
            done.set()

        transport.ask(service, "request", {"event": event, "source": "test"}, answer, 5.0)
        done.wait(6.0)
        if box and box[0] is not None:
            return box[0]
        time.sleep(0.2)
    raise TimeoutError(f"{service} did not answer")


def manager_service(namespace: str, what: str) -> str:
    return f"/{node_name(namespace, 'manager')}/{what}"


def vacuum_mapping(tmp_path: Path, namespace: str) -> Path:
    """The example mapping with every robot topic moved under ``namespace``."""
    doc = yaml.safe_load((VACUUM / "mapping.yaml").read_text())
    for section in ("measures", "events"):
        for spec in doc[section].values():
            spec["topic"] = namespace + spec["topic"]
    doc["guards"] = {
        namespace + src: {**spec, "to": namespace + spec["to"]} for src, spec in doc["guards"].items()
    }
    out = tmp_path / "mapping.yaml"
    out.write_text(yaml.safe_dump(doc))
    return out


def manager(*extra: str) -> list[str]:
    return ["manager", RULES, "--sim-time", "--status-each", *extra]


def test_a_typed_subscriber_receives_decisions_with_their_explanation(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    with System(backend, namespace, env=graph, nodes=[manager()]) as system:
        decisions = Typed(transport, f"{namespace}/decisions", "cosleec_interfaces/msg/Decision")
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.set({"userAsleep": True, "userNearby": False})
        driver.event("CleanRequest")
        decisions.wait(lambda got: len(got) >= 1, what="a typed Decision")
        d = decisions.got[-1]
        assert (d["rule"], d["clause"], d["layer"], d["trigger"]) == ("R1", 1, "R1.1", "CleanRequest")
        assert d["explanation"] == (
            "R1: Refuse [clause 1 (unless userAsleep)], because userAsleep was true; userNearby was false"
        )
        assert d["header"]["stamp"]["sec" if backend == "ros2" else "secs"] > 0
        assert d["sender"] and d["seq"] >= 1
        # the record travels with it, and cosleec's own subscribers read the same decision
        assert driver.decisions[-1]["explanation"] == d["explanation"]
        assert system.codes() == [None]


def test_the_request_service_says_no_while_a_prohibition_holds_and_which_rule(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    with System(backend, namespace, env=graph, nodes=[manager("--decide", "all")]):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        service = manager_service(namespace, "request")
        yes = ask(transport, service, "MoveNearUser")
        assert yes["permitted"] is True and yes["rules"] == []
        driver.event("UserApproaches")
        no = ask(transport, service, "MoveNearUser")
        assert no["permitted"] is False and no["rules"] == ["R3"]
        assert "R3" in no["reason"] and "MoveNearUser" in no["reason"]
        driver.advance(30.5)  # the prohibition's window has closed
        assert ask(transport, service, "MoveNearUser")["permitted"] is True
        unknown = ask(transport, service, "MoveNearUsr")
        assert unknown["permitted"] is False and "MoveNearUser" in unknown["reason"]  # did you mean
        # Decide: values and an event in one call, the decisions in the answer
        box: list[dict[str, Any] | None] = []
        done = threading.Event()
        fields = {"values": {"userAsleep": True, "userNearby": False}, "event": "CleanRequest"}
        transport.ask(
            manager_service(namespace, "decide"), "decide", fields, lambda a: (box.append(a), done.set()), 20
        )
        assert done.wait(25) and box[0] is not None
        assert box[0]["accepted"] is True
        assert [(d["rule"], d["clause"]) for d in box[0]["decisions"]] == [("R1", 1)]


def test_a_best_effort_battery_publisher_drives_a_rule(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    from cosleec.nodes.qos import Qos

    mapping = vacuum_mapping(tmp_path, namespace)
    nodes = [manager(), ["listener", str(mapping), "--rules", RULES]]
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        # the listener's outputs must reach the Manager before the first (edge) event fires
        driver.wait(
            lambda: driver.status.get("listener", {}).get("subscribers", {}).get("events", 0) >= 1,
            what="the listener's events reaching the Manager",
        )
        topic, kind = f"{namespace}/battery", "sensor_msgs/msg/BatteryState"
        # a driver's usual QoS: best effort (a RELIABLE subscription would never hear it)
        end = time.monotonic() + 30
        while not any(d["rule"] == "R2" for d in driver.decisions):
            assert time.monotonic() < end, f"no R2 decision; status {driver.status}"
            transport.publish_typed(topic, kind, {"percentage": 0.1}, Qos.SENSOR_DATA)
            time.sleep(0.2)
        d = next(d for d in driver.decisions if d["rule"] == "R2")
        assert d["event"] == "BatteryLow" and d["obligations"][0]["event"] == "ReturnToDock"
        # the level itself is a measure of the context: the Manager has it
        driver.wait(lambda: driver.status["manager"]["context_version"] >= 1, what="the battery level")
        # edge-triggered: a battery that stays low does not ask again and again
        decided = sum(d["rule"] == "R2" for d in driver.decisions)
        assert decided == 1
        # ...while a command fires on every message (`fire: each`): `clean`, `clean` asks twice
        command = f"{namespace}/voice/command"
        end = time.monotonic() + 30
        while transport.typed_subscribers(command, "std_msgs/msg/String") < 1:
            assert time.monotonic() < end, "the listener does not subscribe to the command"
            transport.publish_typed(command, "std_msgs/msg/String", {"data": "warm up"})
            time.sleep(0.1)
        time.sleep(0.5)
        for _ in range(2):
            transport.publish_typed(command, "std_msgs/msg/String", {"data": "clean"})
        driver.wait(lambda: sum(d["rule"] == "R1" for d in driver.decisions) == 2, what="two R1 decisions")
        assert system.codes() == [None, None]


def test_ros_parameters_choose_the_semantics(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    if backend == "ros2":
        params = tmp_path / "params.yaml"
        params.write_text(yaml.safe_dump({"/**": {"ros__parameters": {"unknown": "undetermined"}}}))
        extra = ["--ros-args", "-p", "semantics:=nested", "--params-file", str(params)]
    else:
        extra = ["_semantics:=nested"]
    with System(backend, namespace, env=graph, nodes=[manager(*extra)]):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.set({"userAsleep": False, "userNearby": True})
        driver.event("CleanRequest")
        # last-wins would choose clause 2 (userNearby); nested reads clause 2 only under clause 1
        d = driver.decisions[-1]
        assert (d["rule"], d["clause"], d["semantics"]) == ("R1", 0, "nested")
    if backend == "ros1":  # what a command line set is not left on the master for the next start
        import rospy

        assert not rospy.has_param(f"/{node_name(namespace, 'manager')}/semantics")


def test_an_unknown_parameter_is_an_error_with_a_suggestion(
    backend: str, graph: dict[str, str], namespace: str
) -> None:
    ros_args = ["--ros-args", "-p", "semantcs:=nested"] if backend == "ros2" else ["_semantcs:=nested"]
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "cosleec.cli.main",
            backend,
            "manager",
            RULES,
            "--namespace",
            namespace,
            *ros_args,
        ],
        env=graph,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 1, done.stderr
    assert "no parameter 'semantcs'" in done.stderr and "did you mean 'semantics'" in done.stderr
    assert "Traceback" not in done.stderr


def test_clock_drives_a_deadline_and_never_goes_back(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    violations_type = "cosleec_interfaces/msg/Violation"
    use_sim = ["--ros-args", "-p", "use_sim_time:=true"] if backend == "ros2" else ["_use_sim_time:=true"]
    nodes = [["manager", RULES, "--status-each", *use_sim]]
    with System(backend, namespace, env=graph, nodes=nodes):
        violations = Typed(transport, f"{namespace}/violations", violations_type)
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.set({"userAsleep": False, "userNearby": False})
        driver.event("CleanRequest")  # StartCleaning within 10 s, on /clock's time
        driver.advance(9.5)
        assert driver.violations == []
        driver.advance(1.0)  # 10.5 s: past the deadline
        violations.wait(lambda got: len(got) == 1, what="the violation")
        v = violations.got[0]
        assert (v["rule"], v["event"], v["late"]) == ("R1", "StartCleaning", False)
        assert v["obligation"]["deadline"] == 10.0
        assert driver.status["manager"]["time"] == 10.5
        driver.now = 3.0  # a /clock that goes back is rejected; time stays
        driver.advance(0.0)
        driver.wait(lambda: any("clock went back" in r["reason"] for r in driver.rejected), what="rejection")
        assert driver.status["manager"]["time"] == 10.5


def test_diagnostics_report_a_rejected_message(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    diagnostics = Typed(transport, "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
    with System(backend, namespace, env=graph, nodes=[manager()]):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        mine = node_name(namespace, "manager")
        # the node reports once a second while nothing changes: one report heard first means
        # this subscriber is connected, so the WARN (sent once, at the change) cannot pass it by
        diagnostics.wait(
            lambda got: any(mine in st["name"] for arr in got for st in arr["status"]),
            what="a first diagnostic of the Manager",
        )
        driver.event("NoSuchEvent")  # a typed Event naming what no rule declares: rejected

        def warned(got: list[dict[str, Any]]) -> bool:
            for arr in got:
                for st in arr["status"]:
                    values = {kv["key"]: kv["value"] for kv in st["values"]} if st["values"] else {}
                    if mine in st["name"] and values.get("rejected") == "1" and _level(st["level"]) == 1:
                        return "1 message(s) rejected" in st["message"]
            return False

        diagnostics.wait(warned, what="a WARN diagnostic counting the rejected message")
        # the rejected record comes on its own topic: it may arrive after the diagnostic
        driver.wait(
            lambda: any("unknown event 'NoSuchEvent'" in r["reason"] for r in driver.rejected),
            what="the rejected record",
        )


def _level(level: Any) -> int:
    return level[0] if isinstance(level, bytes | bytearray) else int(level)


def test_the_lifecycle_manager_enforces_only_while_active(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    if backend != "ros2":
        pytest.skip("ROS 1 has no lifecycle nodes")
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState, GetState

    rules = tmp_path / "rules.sleec"
    rules.write_text("this is not a rule file\n")  # configure must fail on it, and say so
    mgr = node_name(namespace, "manager")
    node = transport.node
    change = node.create_client(ChangeState, f"/{mgr}/change_state")
    get = node.create_client(GetState, f"/{mgr}/get_state")

    def call(client: Any, request: Any, timeout: float = 20.0) -> Any:
        assert client.wait_for_service(timeout_sec=20), "no lifecycle service"
        future = client.call_async(request)
        end = time.monotonic() + timeout
        while not future.done():
            if time.monotonic() >= end:
                return None
            time.sleep(0.02)
        return future.result()

    def settled(client: Any, request: Any) -> Any:
        """Call a request without effect until it is answered. Under load, Fast DDS can drop
        the first answer ("failed to send response (timeout)") while the client's answer
        reader is still being discovered; once one answer arrives, the path is there."""
        for _ in range(6):
            answer = call(client, request, timeout=5.0)
            if answer is not None:
                return answer
        raise AssertionError("the lifecycle service never answered")

    def state() -> str:
        return str(settled(get, GetState.Request()).current_state.label)

    def transition(tid: int) -> bool:
        answer = call(change, ChangeState.Request(transition=Transition(id=tid)))
        assert answer is not None, "no answer"
        return bool(answer.success)

    nodes = [["manager", str(rules), "--sim-time", "--status-each", "--no-autostart"]]
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        assert state() == "unconfigured"
        # a transition the state has not is refused and changes nothing, so it may be asked again
        activate = ChangeState.Request(transition=Transition(id=Transition.TRANSITION_ACTIVATE))
        assert settled(change, activate).success is False
        assert state() == "unconfigured"
        assert transition(Transition.TRANSITION_CONFIGURE) is False  # the broken file is refused
        assert state() == "unconfigured"
        shutil.copy(RULES, rules)
        assert transition(Transition.TRANSITION_CONFIGURE) is True
        assert state() == "inactive"
        service = manager_service(namespace, "request")
        no = ask(transport, service, "MoveNearUser")
        assert no["permitted"] is False and "inactive" in no["reason"]  # fail closed
        assert transition(Transition.TRANSITION_ACTIVATE) is True
        assert ask(transport, service, "MoveNearUser")["permitted"] is True
        # a transition the state has not (configure while active) is refused; the node goes on
        assert transition(Transition.TRANSITION_CONFIGURE) is False
        assert state() == "active" and system.codes() == [None]
        assert ask(transport, service, "MoveNearUser")["permitted"] is True
        assert transition(Transition.TRANSITION_DEACTIVATE) is True
        assert ask(transport, service, "MoveNearUser")["permitted"] is False
        assert transition(Transition.TRANSITION_ACTIVATE) is True
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.event("UserApproaches")
        assert driver.decisions[-1]["rule"] == "R3"
        assert ask(transport, service, "MoveNearUser")["permitted"] is False
        # cleanup forgets: configured again, the Manager starts afresh from the file
        assert transition(Transition.TRANSITION_DEACTIVATE) is True
        assert transition(Transition.TRANSITION_CLEANUP) is True
        assert state() == "unconfigured"
        assert transition(Transition.TRANSITION_CONFIGURE) is True
        assert transition(Transition.TRANSITION_ACTIVATE) is True
        assert ask(transport, service, "MoveNearUser")["permitted"] is True  # R3's prohibition is gone
        assert system.codes() == [None]


def test_reload_keeps_the_old_rules_on_error_and_takes_good_ones_between_decisions(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    rules = tmp_path / "rules.sleec"
    shutil.copy(RULES, rules)
    audit = tmp_path / "audit.jsonl"
    # the operator allows ~/reload to read the files of this test's directory
    nodes = [
        [
            "manager",
            str(rules),
            "--sim-time",
            "--status-each",
            "--audit",
            str(audit),
            "--reload-dir",
            str(tmp_path),
        ]
    ]
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.event("UserApproaches")  # R3's prohibition holds for 30 s: it must survive the reload
        before = driver.status["manager"]["rules_hash"]
        reload = manager_service(namespace, "reload")

        def call(path: str) -> dict[str, Any]:
            box: list[dict[str, Any] | None] = []
            done = threading.Event()
            transport.ask(reload, "reload", {"rules": path}, lambda a: (box.append(a), done.set()), 20.0)
            assert done.wait(25) and box[0] is not None
            return box[0]

        broken = tmp_path / "broken.sleec"
        broken.write_text(rules.read_text().replace("rule_end", "    R9 when Nope then Refuse\nrule_end"))
        bad = call(str(broken))
        assert bad["success"] is False and "broken.sleec:" in bad["message"]
        assert bad["previous_hash"] == bad["current_hash"] == before
        driver.event("CleanRequest")
        assert driver.decisions[-1]["rule"] == "R1"  # the old rules still decide

        grown = rules.read_text().replace(
            "rule_end", "    R4 when BatteryLow then Refuse within 5 seconds\nrule_end"
        )
        good = tmp_path / "good.sleec"
        good.write_text(grown)
        ok = call(str(good))
        assert ok["success"] is True and ok["previous_hash"] == before != ok["current_hash"]
        driver.event("BatteryLow")
        assert sorted(d["rule"] for d in driver.decisions[-2:]) == ["R2", "R4"]
        # R3's prohibition is still there
        assert ask(transport, manager_service(namespace, "request"), "MoveNearUser")["permitted"] is False

        # SIGHUP reads the file the Manager runs (now good.sleec) again
        good.write_text(grown.replace("    R4 when BatteryLow then Refuse within 5 seconds\n", ""))
        system.procs[0].send_signal(signal.SIGHUP)
        driver.wait(lambda: driver.status["manager"]["rules_hash"] == before, what="the SIGHUP reload")
        driver.event("BatteryLow")
        assert [d["rule"] for d in driver.decisions[-1:]] == ["R2"]
        assert system.codes() == [None]
    records = [r for r in _audit(audit) if r.get("kind") == "reloaded"]
    assert [r["previous_hash"] for r in records] == [before, ok["current_hash"]]


def _audit(path: Path) -> list[dict[str, Any]]:
    from cosleec.runtime import read_audit

    return read_audit(str(path))


def test_the_guard_blocks_a_twist_while_forbidden_and_forwards_it_after(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    mapping = vacuum_mapping(tmp_path, namespace)
    nodes = [manager(), ["guard", str(mapping), "--rules", RULES]]
    twist = "geometry_msgs/msg/Twist"
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        refusals = Typed(transport, f"{namespace}/refusals", "cosleec_interfaces/msg/Refusal")
        out = Typed(transport, f"{namespace}/cmd_vel", twist)
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        driver.wait(lambda: "guard" in driver.status, what="the guard")
        driver.event("UserApproaches")  # R3: not MoveNearUser within 30 s

        def send(x: float) -> None:
            transport.publish_typed(f"{namespace}/planner/cmd_vel", twist, {"linear": _vector(x)})

        def by_r3(got: list[dict[str, Any]]) -> list[dict[str, Any]]:
            return [r for r in got if r["rules"] == ["R3"]]

        end = time.monotonic() + 30
        while len(by_r3(refusals.got)) < 3:
            assert time.monotonic() < end, (driver.status.get("guard"), refusals.got[-3:])
            send(0.5)
            time.sleep(0.2)
        # before its first answer (a loaded machine, a service still being matched) the guard
        # blocks on its own, failing closed; it never forwards, and every other refusal is R3's
        first = refusals.got.index(by_r3(refusals.got)[0])
        assert all("did not answer" in r["reason"] and r["rules"] == [] for r in refusals.got[:first])
        r = refusals.got[first]
        assert r["event"] == "MoveNearUser" and r["rules"] == ["R3"]
        assert r["source"] == f"{namespace}/planner/cmd_vel" and "R3" in r["reason"]
        assert out.got == []  # nothing reached the base while forbidden
        driver.advance(31)
        send(0.25)  # one message: the guard's output was advertised at its start, so none is lost
        out.wait(lambda got: len(got) == 1, what="the forwarded Twist")
        assert out.got[0]["linear"]["x"] == 0.25  # forwarded unchanged
        for x in (1.0, 2.0, 3.0):
            send(x)
        out.wait(lambda got: len(got) == 4, what="three more")
        assert [m["linear"]["x"] for m in out.got] == [0.25, 1.0, 2.0, 3.0]  # in order
        assert system.codes() == [None, None]


def _vector(x: float) -> Any:
    from geometry_msgs.msg import Vector3

    return Vector3(x=x, y=0.0, z=0.0)


def test_the_vacuum_example_launches_with_paths_relative_to_its_launch_file(
    backend: str, graph: dict[str, str], tmp_path: Path
) -> None:
    from cosleec.ros.launch import stop

    example = tmp_path / "vacuum"
    shutil.copytree(VACUUM, example)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "cosleec.cli.main",
            backend,
            "launch",
            str(example / f"{backend}.launch.yaml"),
        ],
        env={**graph, "PYTHONPATH": str(ROOT / "src")},
        cwd=elsewhere,  # not where the launch file is
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        assert proc.stdout is not None
        ready, seen = 0, []
        while ready < 3:  # manager, listener and guard each say when they are up
            line = proc.stdout.readline()
            seen.append(line)
            assert line, "the launcher ended early: " + "".join(seen[-20:])
            ready += ": ready" in line
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        stop(proc)
    assert (example / "audit.jsonl").exists()  # next to the launch file, not in the cwd
    assert list(elsewhere.iterdir()) == []


def test_an_incompatible_publisher_is_reported(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    if backend != "ros2":
        pytest.skip("ROS 1 has no QoS")
    from cosleec.nodes.qos import Qos

    mapping = vacuum_mapping(tmp_path, namespace)  # CleanRequest reads reliable: a command must not be lost
    diagnostics = Typed(transport, "/diagnostics", "diagnostic_msgs/msg/DiagnosticArray")
    nodes = [manager(), ["listener", str(mapping), "--rules", RULES]]
    with System(backend, namespace, env=graph, nodes=nodes):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        mine = node_name(namespace, "listener")
        # the WARN goes out once: hear the listener's heartbeat diagnostics first, so the test's
        # subscription is known to be matched when it does
        diagnostics.wait(
            lambda got: any(mine in st["name"] for arr in got for st in arr["status"]),
            what="a diagnostic of the listener",
        )
        # a best-effort publisher can never reach a reliable subscription: the listener says so
        transport.publish_typed(
            f"{namespace}/voice/command", "std_msgs/msg/String", {"data": "clean"}, Qos.SENSOR_DATA
        )
        driver.wait(
            lambda: driver.status.get("listener", {}).get("qos_incompatible", 0) >= 1,
            what="the listener's count",
        )

        def warned(got: list[dict[str, Any]]) -> bool:
            return any(
                mine in st["name"] and _level(st["level"]) == 1 and "incompatible QoS" in st["message"]
                for arr in got
                for st in arr["status"]
            )

        diagnostics.wait(warned, what="a WARN diagnostic naming the incompatible QoS")
        assert not any(d["rule"] == "R1" for d in driver.decisions)  # and indeed it was never heard


def test_rostopic_echo_shows_a_decisions_fields(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    if backend != "ros1":
        pytest.skip("the ROS 2 wheels have no `ros2` command line")
    rostopic = Path(sys.executable).parent / "rostopic"  # Debian's, with the venv that sees the types
    with System(backend, namespace, env=graph, nodes=[manager()]):
        driver = Driver(transport, namespace, tasks=())
        driver.ready(layers=False)
        echo = subprocess.Popen(
            [str(rostopic), "echo", "-n", "1", f"{namespace}/decisions"],
            env=graph,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            end = time.monotonic() + 30
            while echo.poll() is None:  # until rostopic has subscribed and heard one
                assert time.monotonic() < end, "rostopic heard nothing"
                driver.event("UserApproaches")
                time.sleep(0.5)
            out, err = echo.communicate(timeout=10)
        finally:
            if echo.poll() is None:
                echo.kill()
                echo.wait()
    assert echo.returncode == 0, err
    assert 'rule: "R3"' in out and 'trigger: "UserApproaches"' in out
    assert 'explanation: "R3: not MoveNearUser within 30 s"' in out
