"""Node logic on the in-process bus: the Context Listener's mapping, the Manager node's
handling of good and bad messages, the Layer Manager's latched topic, a task node."""

from __future__ import annotations

import json
import time

import pytest

from cosleec.demo.runner import rules_path
from cosleec.nodes import LayersNode, ListenerNode, LocalBus, ManagerNode, Mapping, MappingError, TaskNode
from cosleec.runtime import Manager, RuleSet

from .support import collect

RS = RuleSet.from_file(rules_path())


MAPPING = """
measures:
  userUndressed: {topic: /robot/undressed, type: std_msgs/Bool}
  roomDark: {topic: /robot/lux, type: std_msgs/Float64, below: 10}
  userDistressed: {topic: /robot/distress, type: std_msgs/Float64, bands: [[0.3, low], [0.7, medium], [high]]}
  heartRate: {topic: /robot/vitals, type: std_msgs/String, json: true, field: vitals.hr}
events:
  CurtainOpenRequest: {topic: /robot/voice, type: std_msgs/String, equals: open the curtains}
  UserFallen: {topic: /robot/fall, type: std_msgs/Bool, equals: true}
"""


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("measures: [1, 2]", "`measures` must map names to entries"),
        ("measures:\n  nope: {topic: /a, type: std_msgs/Bool}", "the rules declare no measure 'nope'"),
        ("measures:\n  roomDark: {topic: /a}", "`type` is required"),
        (
            "measures:\n  roomDark: {topic: /a, type: std_msgs/Bool, exec: 'import os'}",
            "unknown key(s) ['exec']",
        ),
        (
            "measures:\n  userDistressed: {topic: /a, type: std_msgs/Float64, bands: [[0.5, calm], [high]]}",
            "['calm'] not in the scale of userDistressed",
        ),
        (
            "measures:\n  heartRate: {topic: /a, type: std_msgs/Float64, above: 3}",
            "a comparison gives a boolean",
        ),
        ("events:\n  UserFallen: {topic: /a, type: std_msgs/Bool}", "an event needs a condition"),
        (
            "events:\n  Nope: {topic: /a, type: std_msgs/Bool, equals: true}",
            "the rules declare no event 'Nope'",
        ),
        ("measures: {roomDark: {topic: /a, type: std_msgs/Bool, above: 1, below: 2}}", "at most one of"),
        ("a: [", "not valid YAML"),
        ("other: 1", "unknown section(s) ['other']"),
    ],
)
def test_mapping_errors_name_the_entry(text: str, message: str) -> None:
    with pytest.raises(MappingError) as info:
        Mapping.parse(text, "mapping.yaml", dict(RS.measures), RS.events)
    assert message in str(info.value) and str(info.value).startswith("mapping.yaml")


def test_listener_maps_messages_to_atomic_updates_and_edge_triggered_events(bus: LocalBus) -> None:
    mapping = Mapping.parse(MAPPING, "m.yaml", dict(RS.measures), RS.events)
    t = bus.transport()
    ListenerNode(t, mapping)
    ctx = collect(bus, "/cosleec/context")
    events = collect(bus, "/cosleec/events")
    rejected = collect(bus, "/cosleec/rejected")
    send = lambda topic, fields: t.publish(topic, json.dumps(fields))  # noqa: E731
    send("/robot/lux", {"data": 3.5})
    send("/robot/distress", {"data": 0.5})
    send("/robot/distress", {"data": 0.95})
    send("/robot/vitals", {"data": json.dumps({"vitals": {"hr": 130}})})
    send("/robot/fall", {"data": True})
    send("/robot/fall", {"data": True})  # still true: no second event
    send("/robot/fall", {"data": False})
    send("/robot/fall", {"data": True})  # rising edge again
    send("/robot/voice", {"data": "open the curtains"})
    send("/robot/lux", {"data": "bright"})  # wrong type: rejected
    send("/robot/vitals", {"data": "not json"})  # rejected too
    bus.wait_idle()
    assert [c["values"] for c in ctx] == [
        {"roomDark": True},
        {"userDistressed": "medium"},
        {"userDistressed": "high"},
        {"heartRate": 130},
    ]
    assert [e["event"] for e in events] == ["UserFallen", "UserFallen", "CurtainOpenRequest"]
    assert len(rejected) == 2 and "not comparable" in rejected[0]["reason"]


def test_manager_node_decides_rejects_and_answers_requests(bus: LocalBus) -> None:
    t = bus.transport()
    node = ManagerNode(t, RS, sim_time=True, status_each=True)
    decisions = collect(bus, "/cosleec/decisions")
    obligations = collect(bus, "/cosleec/obligations")
    replies = collect(bus, "/cosleec/request_reply")
    violations = collect(bus, "/cosleec/violations")
    send = lambda topic, msg: t.publish(f"/cosleec/{topic}", msg if isinstance(msg, str) else json.dumps(msg))  # noqa: E731
    send("context", {"values": {"userConsent": False, "userConscious": True}})
    send("events", {"event": "UserFallen"})
    send("request", {"id": 1, "event": "RecordVideo"})
    for bad in ("{", json.dumps({"values": {}}), json.dumps({"event": "Nope"})):
        send("context" if "values" in bad or bad == "{" else "events", bad)
    send("clock", {"t": 120})
    bus.wait_idle()
    assert [d["rule"] for d in decisions] == ["R4", "R6"]  # R5 waits for CallSupport, never reported
    assert [o["rule"] for o in obligations] == ["R4", "R6"]
    # a refusal says which rule forbids it, and why
    assert replies == [
        {
            "id": 1,
            "event": "RecordVideo",
            "allowed": False,
            "rules": ["R6"],
            "reason": "RecordVideo is forbidden by R6 for another 10 min "
            "(R6: not RecordVideo within 600 s [default], because userConsent was false)",
        }
    ]
    assert {v["event"] for v in violations} == {"CallSupport"}  # nobody called support in time
    assert node.counters["rejected"] == 3
    node.close()


def test_layers_node_is_latched_for_late_joiners(bus: LocalBus) -> None:
    t = bus.transport()
    LayersNode(t, RS)
    t.publish("/cosleec/context", json.dumps({"values": {"userUndressed": True, "userDistressed": "low"}}))
    bus.wait_idle()
    late = collect(bus, "/cosleec/layers")  # subscribes after the switch
    assert late and "R1.1" in late[-1]["active"]


def test_layers_node_reports_the_same_switches_as_the_manager(bus: LocalBus) -> None:
    """Both name switches alike, "?" for a rule still undetermined (its measures unknown)."""
    t = bus.transport()
    LayersNode(t, RS)
    out = collect(bus, "/cosleec/layers")
    update = {"userUndressed": True, "userDistressed": "low"}
    t.publish("/cosleec/context", json.dumps({"values": update}))
    bus.wait_idle()
    want = [{"rule": r, "from": a, "to": b} for r, a, b in Manager(RS).update(update)]
    assert {"rule": "R1", "from": "?", "to": "R1.1"} in want
    assert out[-1]["switches"] == want


def test_task_node_dispatches_the_layer_of_each_decision(bus: LocalBus) -> None:
    from cosleec.demo.assistive_care import tasks

    t = bus.transport()
    ManagerNode(t, RS, sim_time=True)
    node = TaskNode(t, RS, name="task")
    robot = tasks.install(node)
    node.start(["R1"])
    t.publish("/cosleec/context", json.dumps({"values": {"userUndressed": True, "userDistressed": "low"}}))
    t.publish("/cosleec/events", json.dumps({"event": "CurtainOpenRequest"}))
    deadline = time.monotonic() + 5
    while len(node.handled) < 1 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert node.handled[0].layer == "R1.1"
    assert robot.log[:2] == ["Refuse", "ExplainWhy"]
    node.close()


def test_the_example_mapping_and_launch_files_are_valid() -> None:
    from pathlib import Path

    from cosleec.ros.launch import load

    here = Path(rules_path()).parent
    mapping = Mapping.load(here / "mapping.yaml", dict(RS.measures), RS.events)
    assert {e.name for e in mapping.entries if e.kind == "measure"} == set(RS.measures)
    for backend in ("ros1", "ros2"):
        cfg = load(str(here / f"{backend}.launch.yaml"))
        assert cfg["backend"] == backend and [n[0] for n in cfg["nodes"]] == [
            "manager",
            "layers",
            "listener",
            "task",
        ]
