"""CO-SLEEC over real ROS 2 / ROS 1, every node in its own process (COSLEEC_ROS_BACKEND)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from cosleec.demo import first_difference, summary
from cosleec.demo import outcomes as normalised
from cosleec.demo.assistive_care.scenario import EXPECTED, STEPS, outcomes
from cosleec.demo.runner import run as run_embedded
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver
from cosleec.ros.launch import stop

ROOT = Path(__file__).resolve().parents[2]


def env_with_tests(graph: dict[str, str]) -> dict[str, str]:
    return {**graph, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), graph.get("PYTHONPATH", "")]))}


def test_assistive_care_scenario_end_to_end(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    audit = tmp_path / "audit.jsonl"
    with System(backend, namespace, env=graph, audit=str(audit)) as system:
        driver = Driver(transport, namespace)
        driver.ready()
        driver.run(STEPS)
        assert system.codes() == [None, None, None]  # every node still running
    assert outcomes(driver.decisions) == EXPECTED
    manager = driver.status["manager"]
    assert manager["stats"]["refused"] == 1 and manager["counters"]["rejected"] == 0
    # one outcome, whatever the transport: the Manager's audit log, normalised, equals the
    # embedded run of the same day record by record -- decisions, obligations, outcomes
    # and violations, at the same times on the virtual clock
    embedded = run_embedded()
    want = normalised(embedded.records())
    got = normalised(system.records())
    difference = first_difference(want, got)
    assert difference is None, difference
    assert summary(got) == summary(want) == {"decisions": 32, "violations": 2, "late": 1, "refused": 1}
    assert manager["stats"]["violations"] == embedded.manager.stats["violations"] == 2
    # the violations topic also carries the late report of a violation: not a second violation
    assert len({v["id"] for v in driver.violations if v["status"] == "violated"}) == 2


def test_ros_demo_command_checks_the_outcome_against_the_embedded_run(
    backend: str, graph: dict[str, str], namespace: str
) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", backend, "demo", "--namespace", namespace],
        env=graph,  # ROS 1: the command starts a master of its own
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-3000:]
    summary_line = " ".join(done.stdout.split())  # rich wraps the line
    assert (
        f"32 decisions over {backend}, 2 violations, 1 refused actions (embedded: 32, 2, 1)" in summary_line
    )
    assert "outcomes identical to the embedded run" in summary_line


def test_bad_messages_are_rejected_counted_and_the_nodes_keep_running(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, json_wire: str
) -> None:
    with System(backend, namespace, env=graph, wire=json_wire) as system:
        driver = Driver(transport, namespace)
        driver.ready()
        bad = [
            ("context", "this is not json"),
            ("context", json.dumps([1, 2])),
            ("context", json.dumps({"values": {"nope": True}})),
            ("context", json.dumps({"values": {"userUndressed": "yes"}})),
            ("context", json.dumps({"values": {"userDistressed": "extreme"}})),
            ("events", json.dumps({"event": 5})),
            ("events", json.dumps({"event": "NoSuchEvent"})),
            ("clock", json.dumps({"t": "soon"})),
        ]
        for t, payload in bad:
            driver.raw(t, payload)
        driver.quiet()
        driver.wait(
            lambda: len([r for r in driver.rejected if r["node"] == "manager"]) == len(bad), what="rejections"
        )
        # `rejected` and `status` are separate topics, with no order between them: wait for both
        driver.wait(lambda: driver.status["manager"]["counters"]["rejected"] == len(bad), what="the count")
        reasons = [r["reason"] for r in driver.rejected if r["node"] == "manager"]
        assert any("unknown measure 'nope'" in r for r in reasons)
        assert any("not in the scale of userDistressed" in r for r in reasons)
        assert any("unknown event 'NoSuchEvent'" in r for r in reasons)
        # ...and the system still decides
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.event("CurtainOpenRequest")
        assert (driver.decisions[-1]["rule"], driver.decisions[-1]["clause"]) == ("R1", 1)
        assert system.codes() == [None, None, None]


@pytest.mark.parametrize("module", ["tests.ros.hanging_tasks", "tests.ros.crashing_tasks"])
def test_a_hanging_or_crashing_task_node_yields_violations_and_otherwise(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, module: str
) -> None:
    with System(backend, namespace, env=env_with_tests(graph), task_module=module) as system:
        driver = Driver(transport, namespace)
        driver.ready()
        driver.set({"userAssent": True, "userUndressed": False, "userDistressed": "low"})
        driver.sent += 1
        transport.publish(f"{namespace}/events", json.dumps({"event": "DressingAbandoned"}))
        driver.wait(lambda: driver.status["manager"]["stats"]["decisions"] >= 1, what="the decision")
        driver.sent += 1
        transport.publish(f"{namespace}/clock", json.dumps({"t": 121}))
        driver.wait(lambda: any(v["event"] == "RetryAgreed" for v in driver.violations), what="the violation")
        driver.wait(lambda: any(d["event"] == "otherwise" for d in driver.decisions), what="the fallback")
        fallback = next(d for d in driver.decisions if d["event"] == "otherwise")
        assert [o["event"] for o in fallback["obligations"]] == ["SupportCalled"]
        # the Manager is not stuck: it still answers and decides
        assert driver.request("RecordVideo", settle=False) is True
        driver.sent += 1
        transport.publish(f"{namespace}/events", json.dumps({"event": "CurtainOpenRequest"}))
        driver.wait(lambda: any(d["rule"] == "R1" for d in driver.decisions), what="a later decision")
        assert system.codes()[0] is None


def test_no_stale_dispatch_when_updates_race_triggers_across_processes(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    rules = tmp_path / "race.sleec"
    rules.write_text(
        "def_start event E event Same event ABigger event BBigger measure a : numeric measure b : numeric def_end\n"
        "rule_start R when E then Same within 5 seconds unless a > b then ABigger within 5 seconds\n"
        "  unless a < b then BBigger within 5 seconds rule_end\n"
    )
    nodes = [
        ["manager", str(rules), "--sim-time", "--status-each"],
        ["task", str(rules), "--module", "tests.ros.race_tasks", "--status-each"],
    ]
    with System(backend, namespace, env=env_with_tests(graph), rules=str(rules), nodes=nodes) as system:
        driver = Driver(transport, namespace)
        driver.ready(layers=False)
        driver.set({"a": 0, "b": 0})
        # triggers come from another process, as fast as it can send them
        trigger = subprocess.Popen(
            [sys.executable, "-c", TRIGGER.format(backend=backend, topic=f"{namespace}/events", n=300)],
            env=env_with_tests(graph),
        )
        try:
            for i in range(300):  # meanwhile, updates that always change which is bigger, atomically
                a, b = (i, i + 1) if i % 3 == 0 else (i + 1, i) if i % 3 == 1 else (i, i)
                driver.sent += 1
                transport.publish(f"{namespace}/context", json.dumps({"values": {"a": a, "b": b}}))
                time.sleep(0.001)
            assert trigger.wait(60) == 0
        finally:
            stop(trigger)
        driver.wait(lambda: driver.status["manager"]["stats"]["decisions"] >= 300, what="300 decisions")
        driver.wait(lambda: driver.status["manager"]["stats"]["events"] >= 600, what="every report")
        driver.sent += 1
        transport.publish(f"{namespace}/clock", json.dumps({"t": 10}))  # close every window
        driver.wait(lambda: driver.status["manager"]["time"] >= 10, what="the clock")
        decisions = [d for d in driver.decisions if d["rule"] == "R"]
        assert len(decisions) >= 300
        for d in decisions:
            a, b = d["values"]["a"], d["values"]["b"]
            assert d["clause"] == (1 if a > b else 2 if a < b else 0), d
        # the task node ran exactly the variant of each decision: nothing was violated
        assert not [v for v in driver.violations if v["status"] == "violated"]
        assert system.codes() == [None, None]


TRIGGER = """
import json, time
from cosleec.ros.run import transport
t = transport("{backend}", "cosleec_race_trigger")
t.advertise("{topic}")
while t.subscribers("{topic}") < 1:
    time.sleep(0.01)
time.sleep(0.2)
for _ in range({n}):
    t.publish("{topic}", json.dumps({{"event": "E"}}))
    time.sleep(0.002)
time.sleep(0.5)
t.close()
"""


def test_layers_are_latched_for_late_joiners(
    backend: str, graph: dict[str, str], transport: Any, namespace: str
) -> None:
    with System(backend, namespace, env=graph):
        driver = Driver(transport, namespace)
        driver.ready()
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.wait(lambda: "R1.1" in driver.layers_message.get("active", []), what="the layer switch")
        late = subprocess.run(
            [sys.executable, "-c", LATE.format(backend=backend, topic=f"{namespace}/layers")],
            env=graph,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert late.returncode == 0, late.stderr
        assert "R1.1" in json.loads(late.stdout.strip().splitlines()[-1])["active"]


LATE = """
import json, threading
from cosleec.ros.run import transport
t = transport("{backend}", "cosleec_late_joiner")
from cosleec.nodes import record
got = threading.Event(); box = []
def on(payload):
    box.append(record(payload)); got.set()
t.subscribe("{topic}", on)
assert got.wait(20), "no latched layers"
print(json.dumps(box[-1]))
t.close()
"""


def test_context_listener_maps_robot_topics(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    from cosleec.demo.runner import rules_path

    mapping = tmp_path / "mapping.yaml"
    mapping.write_text(f"""
namespace: {namespace}
measures:
  userUndressed: {{topic: {namespace}_robot/undressed, type: std_msgs/Bool}}
  userDistressed:
    topic: {namespace}_robot/distress
    type: std_msgs/Float64
    bands: [[0.3, low], [0.7, medium], [high]]
events:
  CurtainOpenRequest: {{topic: {namespace}_robot/voice, type: std_msgs/String, equals: open the curtains}}
""")
    rules = rules_path()
    nodes = [
        ["manager", rules, "--sim-time", "--status-each"],
        ["listener", str(mapping), "--rules", rules],
        ["task", rules, "--module", "cosleec.demo.assistive_care.tasks"],
    ]
    with System(backend, namespace, env=graph, nodes=nodes) as system:
        driver = Driver(transport, namespace)
        driver.ready(layers=False)
        topics = {"undressed": "std_msgs/Bool", "distress": "std_msgs/Float64", "voice": "std_msgs/String"}
        for name, type_name in topics.items():  # make each typed publisher and wait for the listener
            transport.publish_typed(
                f"{namespace}_robot/{name}",
                type_name,
                {"data": {"std_msgs/Bool": False, "std_msgs/Float64": 0.1}.get(type_name, "hello")},
            )
            driver.wait(
                lambda n=name, ty=type_name: transport.typed_subscribers(f"{namespace}_robot/{n}", ty) >= 1,
                what=f"listener on {name}",
            )
        time.sleep(0.5)
        transport.publish_typed(f"{namespace}_robot/undressed", "std_msgs/Bool", {"data": True})
        transport.publish_typed(f"{namespace}_robot/distress", "std_msgs/Float64", {"data": 0.9})
        driver.wait(lambda: driver.status["manager"]["active"] == ["R1.2", "R10.2"], what="the layers")
        transport.publish_typed(f"{namespace}_robot/voice", "std_msgs/String", {"data": "open the curtains"})
        driver.wait(lambda: any(d["rule"] == "R1" for d in driver.decisions), what="the trigger")
        d = next(d for d in driver.decisions if d["rule"] == "R1")
        assert (d["clause"], d["values"]) == (2, {"userDistressed": "high", "userUndressed": True})
        assert system.codes() == [None, None, None]


def test_launcher_starts_and_stops_every_node(backend: str, graph: dict[str, str], tmp_path: Path) -> None:
    from cosleec.demo.runner import rules_path

    ns = f"/cosleec_launch_{os.getpid()}"
    launch = tmp_path / "system.yaml"
    launch.write_text(
        f"backend: {backend}\nnamespace: {ns}\nnodes:\n"
        f"  - [manager, {rules_path()}, --sim-time]\n  - [layers, {rules_path()}]\n"
        f"  - [task, {rules_path()}, --module, cosleec.demo.assistive_care.tasks]\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "cosleec.cli.main", backend, "launch", str(launch)],
        env=graph,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        children = wait_children(proc.pid, 3)
        assert proc.stdout is not None
        ready = 0
        while ready < 3:  # every node says when it is up
            line = proc.stdout.readline()
            assert line, "the launcher ended early"
            ready += ": ready" in line
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
        for pid in children:
            assert (
                not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split()[2]
            )
    finally:
        stop(proc)


def wait_children(pid: int, n: int, timeout: float = 30.0) -> list[int]:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        kids = []
        for d in Path("/proc").iterdir():
            if d.name.isdigit():
                try:
                    if int(d.joinpath("stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                        kids.append(int(d.name))
                except (OSError, IndexError, ValueError):
                    continue
        if len(kids) >= n:
            return kids
        time.sleep(0.1)
    raise TimeoutError("the launcher did not start its nodes")


def test_decision_stream_recorded_to_mcap(
    backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    from cosleec.nodes import read_recording as read

    record = tmp_path / "decisions.mcap"
    if backend == "ros1":
        try:
            import mcap  # noqa: F401
        except ImportError:
            pytest.skip("mcap is not installed in the ROS 1 environment")
    with System(backend, namespace, env=graph, manager_args=["--record", str(record)]):
        driver = Driver(transport, namespace)
        driver.ready()
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.event("CurtainOpenRequest")
    messages = read(record)
    topics = {t for t, _ in messages}
    assert "/cosleec/decision" in topics and "/cosleec/obligation" in topics
    decision = next(m for t, m in messages if t == "/cosleec/decision")
    assert (decision["rule"], decision["layer"]) == ("R1", "R1.1")


def test_threads_do_not_leak(backend: str) -> None:
    assert threading.active_count() < 50


@pytest.mark.parametrize("delay", [0.0, 0.3, 1.5])
def test_a_node_stopped_while_starting_exits_cleanly(
    backend: str, graph: dict[str, str], delay: float
) -> None:
    from cosleec.demo.runner import rules_path
    from cosleec.ros.launch import node_command, start

    proc = start(
        node_command(backend, ["manager", rules_path()], f"/cosleec_early_{os.getpid()}"),
        env=graph,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    time.sleep(delay)
    code = stop(proc, grace=20)
    assert code in (0, -signal.SIGTERM), proc.stderr.read() if proc.stderr else ""


def test_ros2_refuses_to_start_without_localhost_discovery(backend: str, graph: dict[str, str]) -> None:
    if backend != "ros2":
        pytest.skip("a ROS 2 (DDS discovery) safeguard")
    from cosleec.demo.runner import rules_path

    env = {
        k: v for k, v in graph.items() if k not in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "COSLEEC_ALLOW_NETWORK")
    }
    done = subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", "ros2", "manager", rules_path()],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode != 0
    assert "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST" in done.stdout + done.stderr
