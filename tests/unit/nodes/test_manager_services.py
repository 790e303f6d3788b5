"""The Manager node's services (``~/request``, ``~/decide``, ``~/reload``) and lifecycle
(``activate``/``deactivate``), on a LocalBus transport that also records the services it is
asked to serve, so the test calls their handlers. The rules are the vacuum example's (R3
forbids MoveNearUser for 30 s after UserApproaches), in simulated time from ``clock``."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from cosleec.nodes import LocalBus, LocalTransport, ManagerNode
from cosleec.nodes.manager_node import MAX_NAME
from cosleec.runtime import RuleSet

from .support import collect
from .test_conflicts import CURTAINS

RULES = Path(__file__).resolve().parents[3] / "examples" / "ros" / "vacuum" / "rules.sleec"
INACTIVE = "the Manager is inactive (lifecycle): it refuses every request until it is activated"
PERMITTED_REASON = "MoveNearUser is permitted: no prohibition in force forbids it now"
R3_REASON = "MoveNearUser is forbidden by R3 for another 30 s (R3: not MoveNearUser within 30 s)"

Service = Callable[[dict[str, Any]], dict[str, Any]]


class Served(LocalTransport):
    """A LocalBus transport that also offers services: it records each handler for the test."""

    def __init__(self, bus: LocalBus) -> None:
        super().__init__(bus)
        self.services: dict[str, tuple[str, Service]] = {}

    def serve(self, name: str, kind: str, handler: Service, rejected: Any = None) -> None:
        assert name not in self.services, f"{name} served twice"
        self.services[name] = (kind, handler)
        self.rejected = rejected  # the node's: what a transport calls with a request it cannot decode

    def call(self, name: str, request: dict[str, Any]) -> dict[str, Any]:
        return self.services[name][1](request)


class Robot:
    """A Manager node on the bus, with what it publishes collected."""

    def __init__(self, bus: LocalBus, rules_path: Path | None, text: str | None = None, **kw: Any) -> None:
        self.bus = bus
        self.t = Served(bus)
        self.out = {
            name: collect(bus, f"/cosleec/{name}")
            for name in ("refusals", "conflicts", "rejected", "decisions", "status", "request_reply")
        }
        rules = RuleSet.from_text(text) if text is not None else RuleSet.from_file(rules_path)  # type: ignore[arg-type]
        self.node = ManagerNode(
            self.t,
            rules,
            sim_time=True,
            rules_path=str(rules_path) if rules_path is not None else None,
            **kw,
        )

    def request(self, event: Any, source: Any = None) -> dict[str, Any]:
        req: dict[str, Any] = {"event": event}
        if source is not None:
            req["source"] = source
        return self.t.call("~/request", req)

    def decide(self, **req: Any) -> dict[str, Any]:
        return self.t.call("~/decide", req)

    def reload(self, **req: Any) -> dict[str, Any]:
        return self.t.call("~/reload", req)

    def send(self, name: str, message: dict[str, Any]) -> None:
        self.t.publish(f"/cosleec/{name}", json.dumps(message))
        assert self.bus.wait_idle()

    def at(self, t: float) -> None:
        self.send("clock", {"t": t})

    def idle(self) -> None:
        assert self.bus.wait_idle()


@pytest.fixture
def rules_file(tmp_path: Path) -> Path:
    p = tmp_path / "rules.sleec"
    shutil.copy(RULES, p)
    return p


@pytest.fixture
def robot(bus: LocalBus, rules_file: Path) -> Iterator[Robot]:
    """A Manager node whose operator allowed everything: ~/decide takes values and events, and
    ~/reload reads any file of the test's directory (the defaults are tested on their own)."""
    r = Robot(bus, rules_file, decide="all", reload_dir=str(rules_file.parent))
    yield r
    r.node.close()


# ----------------------------------------------------------------------------- wiring


def test_it_serves_request_decide_and_reload(robot: Robot) -> None:
    assert {n: k for n, (k, _) in robot.t.services.items()} == {
        "~/request": "request",
        "~/decide": "decide",
        "~/reload": "reload",
    }


def test_without_services_it_runs_on_topics_alone(bus: LocalBus) -> None:
    node = ManagerNode(bus.transport(), RuleSet.from_file(RULES), sim_time=True)
    node.close()


# ----------------------------------------------------------------------------- ~/request


def test_request_permitted(robot: Robot) -> None:
    assert robot.request("MoveNearUser") == {"permitted": True, "rules": [], "reason": PERMITTED_REASON}
    robot.idle()
    assert robot.out["refusals"] == []
    assert robot.node.manager.stats["refused"] == 0


def test_request_refused_with_the_rules_and_why_and_the_refusal_published(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    answer = robot.request("MoveNearUser", "/planner/cmd_vel")
    assert answer == {"permitted": False, "rules": ["R3"], "reason": R3_REASON}
    robot.idle()
    assert len(robot.out["refusals"]) == 1
    r = robot.out["refusals"][0]
    assert r["event"] == "MoveNearUser" and r["by"] == ["R3"] and r["reason"] == R3_REASON
    assert r["source"] == "/planner/cmd_vel"
    assert robot.node.manager.stats["refused"] == 1


def test_request_follows_the_simulated_clock_window_ends_included(robot: Robot) -> None:
    robot.at(10.0)
    robot.send("events", {"event": "UserApproaches"})  # R3: not MoveNearUser until 40 s
    robot.at(39.0)
    assert robot.request("MoveNearUser")["permitted"] is False
    robot.at(40.0)
    assert robot.request("MoveNearUser")["permitted"] is False
    robot.at(40.001)
    assert robot.request("MoveNearUser")["permitted"] is True


def test_request_other_events_are_not_forbidden_by_r3(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    assert robot.request("ReturnToDock")["permitted"] is True


def test_request_source_is_cut_to_max_name_and_optional(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    robot.request("MoveNearUser", "s" * (MAX_NAME + 500))
    robot.request("MoveNearUser")
    robot.request("MoveNearUser", 42)
    robot.idle()
    first, second, third = robot.out["refusals"]
    assert first["source"] == "s" * 200 + f"…({MAX_NAME - 200} more)"  # cut at MAX_NAME, then clipped
    assert "source" not in second  # nobody said who asked
    assert third["source"] == "42"


@pytest.mark.parametrize("name", [None, "", 5, True, ["MoveNearUser"], "x" * (MAX_NAME + 1)])
def test_request_not_an_event_name(robot: Robot, name: Any) -> None:
    answer = robot.request(name)
    assert answer["permitted"] is False and answer["rules"] == []
    assert answer["reason"].startswith("not an event name: ")
    robot.idle()
    assert robot.out["refusals"] == []


def test_request_a_name_of_max_name_characters_is_a_name(bus: LocalBus, rules_file: Path) -> None:
    r = Robot(bus, rules_file, unknown_events="refuse")
    answer = r.request("x" * MAX_NAME)
    assert answer["permitted"] is False
    assert not answer["reason"].startswith("not an event name")
    assert "is not an event the rules declare" in answer["reason"]
    r.node.close()


def test_request_an_undeclared_event_under_refuse(bus: LocalBus, rules_file: Path) -> None:
    r = Robot(bus, rules_file, unknown_events="refuse")
    answer = r.request("MoveNearUsr")
    assert answer["permitted"] is False and answer["rules"] == []
    assert "did you mean MoveNearUser?" in answer["reason"]
    r.node.close()


def test_request_an_undeclared_event_is_refused_with_the_reason(robot: Robot) -> None:
    answer = robot.request("MoveNearUsr")
    assert answer["permitted"] is False and answer["rules"] == []
    assert "unknown event 'MoveNearUsr'" in answer["reason"]


def test_request_while_inactive_is_refused_and_not_recorded(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    robot.node.deactivate()
    for event in ("ReturnToDock", "MoveNearUser"):
        assert robot.request(event) == {"permitted": False, "rules": [], "reason": INACTIVE}
    robot.idle()
    assert robot.out["refusals"] == []  # the Manager was not asked
    assert robot.node.manager.stats["refused"] == 0
    robot.node.activate()
    assert robot.request("ReturnToDock")["permitted"] is True
    assert robot.request("MoveNearUser")["rules"] == ["R3"]


def test_request_topic_refusal_is_published_on_refusals_and_replied(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    robot.send("request", {"id": "a1", "event": "MoveNearUser", "source": "task"})
    assert robot.out["request_reply"] == [
        {"id": "a1", "event": "MoveNearUser", "allowed": False, "rules": ["R3"], "reason": R3_REASON}
    ]
    assert [r["source"] for r in robot.out["refusals"]] == ["task"]


# ----------------------------------------------------------------------------- ~/decide


def test_decide_applies_values_and_returns_the_decisions(robot: Robot) -> None:
    answer = robot.decide(values={"userAsleep": True, "userNearby": False}, event="CleanRequest")
    assert answer["accepted"] is True and answer["error"] == ""
    [d] = answer["decisions"]
    assert d["rule"] == "R1" and d["event"] == "CleanRequest" and d["clause"] == 1  # unless userAsleep
    assert d["values"] == {"userAsleep": True, "userNearby": False}
    json.dumps(answer)  # a wire form
    robot.idle()
    assert [x["id"] for x in robot.out["decisions"]] == [d["id"]]
    assert robot.node.manager.context.values["userAsleep"] is True


def test_decide_values_only_or_event_only(robot: Robot) -> None:
    assert robot.decide(values={"userAsleep": False, "userNearby": False}) == {
        "accepted": True,
        "error": "",
        "decisions": [],
    }
    assert robot.node.manager.context.values["userAsleep"] is False
    answer = robot.decide(event="CleanRequest")
    assert answer["accepted"] is True and [d["clause"] for d in answer["decisions"]] == [0]
    assert robot.decide(event="MoveNearUser") == {"accepted": True, "error": "", "decisions": []}
    assert robot.decide() == {"accepted": True, "error": "", "decisions": []}


def test_decide_an_event_that_starts_a_prohibition(robot: Robot) -> None:
    answer = robot.decide(event="UserApproaches")
    assert [d["rule"] for d in answer["decisions"]] == ["R3"]
    assert robot.request("MoveNearUser")["rules"] == ["R3"]


def test_decide_while_inactive_is_not_accepted_and_changes_nothing(robot: Robot) -> None:
    robot.node.deactivate()
    answer = robot.decide(values={"userAsleep": True}, event="UserApproaches")
    assert answer == {"accepted": False, "error": INACTIVE, "decisions": []}
    assert robot.node.manager.context.values.get("userAsleep") is None
    assert robot.node.manager.stats["decisions"] == 0


@pytest.mark.parametrize(
    ("req", "error"),
    [
        ({"values": {"nope": True}, "event": "CleanRequest"}, "unknown measure 'nope'"),
        ({"values": {"userAsleep": "yes"}}, "userAsleep is boolean; got str 'yes'"),
        ({"event": "Nope"}, "unknown event 'Nope'"),
        ({"values": "userAsleep"}, "context message needs a non-empty object `values`"),
    ],
)
def test_decide_refuses_what_the_rules_do_not_declare(robot: Robot, req: dict[str, Any], error: str) -> None:
    answer = robot.decide(**req)
    said = answer["error"]
    assert {**answer, "error": said.split("\n  hint: ")[0]} == {
        "accepted": False,
        "error": error,
        "decisions": [],
    }
    assert "hint: " in said if error.startswith("unknown measure") else "hint: " not in said  # the fix shows
    assert robot.node.manager.stats["decisions"] == 0


def test_decide_not_accepted_changes_no_context(robot: Robot) -> None:
    answer = robot.decide(values={"userAsleep": True}, event="Nope")
    assert answer["accepted"] is False
    assert robot.node.manager.context.values.get("userAsleep") is None


# ----------------------------------------------------------------------------- ~/reload


NEW_RULES = RULES.read_text(encoding="utf-8").replace(
    "R3 when UserApproaches then not MoveNearUser within 30 seconds",
    "R3 when UserApproaches then not MoveNearUser within 5 seconds\n"
    "    R4 when BatteryLow then not StartCleaning within 60 seconds",
)


def test_reload_without_a_path_reloads_the_rules_file(robot: Robot, rules_file: Path) -> None:
    before = robot.node.manager.rules_hash
    for req in ({}, {"rules": ""}):
        answer = robot.reload(**req)
        assert answer == {
            "success": True,
            "message": f"reloaded {rules_file}: +0 -0 ~0 rules, 0 obligation(s) withdrawn",
            "previous_hash": before,
            "current_hash": before,
        }
    assert robot.node.counters["reloads"] == 2


def test_reload_a_file_that_changed_in_place(robot: Robot, rules_file: Path) -> None:
    before = robot.node.manager.rules_hash
    rules_file.write_text(NEW_RULES, encoding="utf-8")
    answer = robot.reload()
    assert answer["success"] is True
    assert answer["previous_hash"] == before
    assert answer["current_hash"] == RuleSet.from_text(NEW_RULES).digest != before
    assert answer["message"].startswith(f"reloaded {rules_file}: +1 -0 ~1 rules")


def test_reload_a_broken_file_keeps_the_old_rules(robot: Robot, rules_file: Path, tmp_path: Path) -> None:
    before = robot.node.manager.rules_hash
    broken = tmp_path / "broken.sleec"
    broken.write_text("def_start\n  event A\n", encoding="utf-8")
    answer = robot.reload(rules=str(broken))
    assert answer["success"] is False
    assert answer["previous_hash"] == answer["current_hash"] == before
    assert str(broken) in answer["message"] and "error" in answer["message"]
    assert robot.node.manager.rules_hash == before
    assert robot.node.rules_path == str(rules_file)  # the file it runs is still the old one
    assert robot.node.counters.get("reloads_rejected") == 1 and robot.node.counters.get("reloads", 0) == 0
    # the old rules still decide: R3 for 30 s
    robot.send("events", {"event": "UserApproaches"})
    robot.at(20.0)
    assert robot.request("MoveNearUser")["rules"] == ["R3"]


def test_reload_a_missing_file(robot: Robot, tmp_path: Path) -> None:
    before = robot.node.manager.rules_hash
    answer = robot.reload(rules=str(tmp_path / "nope.sleec"))
    assert answer["success"] is False and "cannot read file" in answer["message"]
    assert answer["previous_hash"] == answer["current_hash"] == before


@pytest.mark.parametrize("what", ["directory", "latin1"])
def test_reload_an_unreadable_file(robot: Robot, tmp_path: Path, what: str) -> None:
    before = robot.node.manager.rules_hash
    target = tmp_path / "rules.d"
    target.mkdir()
    if what == "latin1":
        target = tmp_path / "latin1.sleec"
        target.write_bytes(b"\xff\xfe not text")
    answer = robot.reload(rules=str(target))
    assert answer["success"] is False and str(target) in answer["message"]
    assert answer["previous_hash"] == answer["current_hash"] == before


def test_reload_refused_by_the_manager_keeps_the_old_rules(robot: Robot, tmp_path: Path) -> None:
    robot.send("context", {"values": {"batteryLevel": 0.5}})
    changed = tmp_path / "changed.sleec"  # batteryLevel holds a number: it cannot become a boolean
    changed.write_text(
        RULES.read_text(encoding="utf-8").replace("batteryLevel : numeric", "batteryLevel : boolean"),
        encoding="utf-8",
    )
    before = robot.node.manager.rules_hash
    answer = robot.reload(rules=str(changed))
    assert answer["success"] is False and "reload refused" in answer["message"]
    assert answer["previous_hash"] == answer["current_hash"] == before == robot.node.manager.rules_hash


def test_reload_a_good_file_and_the_new_rule_decides(robot: Robot, tmp_path: Path) -> None:
    before = robot.node.manager.rules_hash
    new = tmp_path / "new.sleec"
    new.write_text(NEW_RULES, encoding="utf-8")
    answer = robot.reload(rules=str(new))
    assert answer["success"] is True
    assert answer["previous_hash"] == before != answer["current_hash"]
    assert answer["current_hash"] == robot.node.manager.rules_hash == RuleSet.from_text(NEW_RULES).digest
    assert robot.node.rules_path == str(new)
    robot.idle()
    assert robot.out["status"][-1]["rules_hash"] == answer["current_hash"]
    # R3 now forbids for 5 s, not 30
    robot.send("events", {"event": "UserApproaches"})
    robot.at(4.0)
    assert robot.request("MoveNearUser")["rules"] == ["R3"]
    robot.at(6.0)
    assert robot.request("MoveNearUser")["permitted"] is True
    # R4 is new
    robot.send("events", {"event": "BatteryLow"})
    assert robot.request("StartCleaning")["rules"] == ["R4"]
    # and a reload without a path now reads the new file
    assert robot.reload()["message"].startswith(f"reloaded {new}: +0 -0 ~0")


def test_reload_with_no_file_at_all(bus: LocalBus) -> None:
    r = Robot(bus, None, text=RULES.read_text(encoding="utf-8"))
    h = r.node.manager.rules_hash
    assert r.reload() == {
        "success": False,
        "message": "no rule file to reload: this Manager was started without one",
        "previous_hash": h,
        "current_hash": h,
    }
    r.node.close()


def test_reload_method_is_what_the_service_answers(robot: Robot, rules_file: Path) -> None:
    assert robot.node.reload() == robot.reload()
    assert robot.node.reload(str(rules_file))["success"] is True


# ----------------------------------------------------------------------------- lifecycle


def test_starts_active_by_default_and_inactive_on_request(bus: LocalBus, rules_file: Path) -> None:
    r = Robot(bus, rules_file, active=False)
    assert r.node.active is False
    assert r.request("MoveNearUser")["reason"] == INACTIVE
    r.idle()
    assert r.out["status"][-1]["lifecycle"] == "inactive"
    r.node.activate()
    r.idle()
    assert r.out["status"][-1]["lifecycle"] == "active"
    assert r.request("MoveNearUser")["permitted"] is True
    r.node.close()


def test_events_while_inactive_are_rejected_counted_and_published(robot: Robot) -> None:
    robot.node.deactivate()
    robot.idle()
    assert robot.out["status"][-1]["lifecycle"] == "inactive"
    robot.send("events", {"event": "UserApproaches"})
    assert robot.node.counters["rejected"] == 1
    assert robot.out["rejected"] == [
        {
            "node": "manager",
            "topic": "/cosleec/events",
            "reason": INACTIVE,
            "payload": json.dumps({"event": "UserApproaches"}),
        }
    ]
    assert robot.node.manager.stats["events"] == 0 and robot.out["decisions"] == []
    # the event never happened: nothing is forbidden once active again
    robot.node.activate()
    assert robot.request("MoveNearUser")["permitted"] is True
    robot.send("events", {"event": "UserApproaches"})
    assert robot.node.counters["rejected"] == 1
    assert [d["rule"] for d in robot.out["decisions"]] == ["R3"]


def test_request_topic_while_inactive_replies_not_allowed(robot: Robot) -> None:
    robot.node.deactivate()
    robot.send("request", {"id": 3, "event": "ReturnToDock"})
    assert robot.out["request_reply"] == [
        {"id": 3, "event": "ReturnToDock", "allowed": False, "rules": [], "reason": INACTIVE}
    ]


def test_context_and_clock_are_taken_while_inactive(robot: Robot) -> None:
    robot.node.deactivate()
    robot.send("context", {"values": {"userAsleep": True, "userNearby": False}})
    robot.at(12.5)
    assert robot.node.counters["rejected"] == 0
    assert robot.node.manager.context.values["userAsleep"] is True
    assert robot.node.clock.now() == 12.5
    robot.node.activate()
    answer = robot.decide(event="CleanRequest")
    assert answer["decisions"][0]["clause"] == 1  # under the context given while inactive
    assert answer["decisions"][0]["time"] == 12.5


def test_a_refused_request_while_inactive_after_a_prohibition_does_not_end_it(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches"})
    robot.node.deactivate()
    robot.at(10.0)
    robot.node.activate()
    assert robot.request("MoveNearUser")["rules"] == ["R3"]


# ----------------------------------------------------------------------------- outputs


def test_refused_and_conflict_records_are_published(bus: LocalBus) -> None:
    r = Robot(bus, None, text=CURTAINS.format(window="10 minutes"))
    r.send("context", {"values": {"night": True}})
    r.send("events", {"event": "CurtainOpenRequest"})
    [c] = r.out["conflicts"]
    assert c["event"] == "OpenCurtains" and c["between"] == ["R1", "R2"] and c["winner"] == "R2"
    answer = r.request("OpenCurtains", "/curtains/cmd")
    assert answer["rules"] == ["R2"]
    r.idle()
    [ref] = r.out["refusals"]
    assert ref["event"] == "OpenCurtains" and ref["by"] == ["R2"] and ref["source"] == "/curtains/cmd"
    assert ref["reason"] == answer["reason"]
    r.node.close()


# ----------------------------------------------------------------------------- events with values


def test_an_event_with_values_is_decided_on_them(robot: Robot) -> None:
    robot.send("context", {"values": {"userAsleep": False, "userNearby": False}})
    robot.send("events", {"event": "CleanRequest", "values": {"userAsleep": True}})
    d = robot.out["decisions"][-1]
    assert (d["rule"], d["clause"], d["values"]["userAsleep"]) == ("R1", 1, True)


def test_an_event_with_no_values_is_a_plain_event(robot: Robot) -> None:
    robot.send("events", {"event": "UserApproaches", "values": {}})  # the typed wire's empty list
    assert [d["rule"] for d in robot.out["decisions"]] == ["R3"]


def test_an_unknown_event_with_values_changes_nothing(robot: Robot) -> None:
    robot.send("events", {"event": "Nope", "values": {"userAsleep": True}})
    assert robot.node.manager.values()["userAsleep"] is None and len(robot.out["rejected"]) == 1


@pytest.mark.parametrize("values", [{"userAsleep": "yes"}, {"nope": True}, [1], {"batteryLevel": 10**400}])
def test_an_event_with_bad_values_is_rejected_whole(robot: Robot, values: Any) -> None:
    robot.send("events", {"event": "CleanRequest", "values": values})
    assert robot.out["decisions"] == []  # the event did not happen either
    assert len(robot.out["rejected"]) == 1
