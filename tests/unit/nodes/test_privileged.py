"""Privileged operations stay privileged (issue 28, findings 7 and 14), on a LocalBus.

``~/reload`` reads only what the operator allowed when starting the Manager node -- the
rule file it runs, and with ``reload_dir`` the files under that directory, symlinks and
``..`` resolved first -- and answers any other path with one fixed message, without
touching it; every attempt is a ``reload-attempt`` record in the audit log. ``~/decide``
is off unless the operator chose ``events-only`` or ``all``. And every input the node
rejects before the runtime sees it (it cannot be decoded, a service is off) gets its
``rejected`` record, like the runtime's own rejections -- once, never twice.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from cosleec.errors import ConfigurationError, UserError
from cosleec.nodes import DECIDE, DEFAULT_DECIDE, LocalBus, MessageError
from cosleec.runtime import RuleSet, read_audit

from .test_manager_services import NEW_RULES, RULES, Robot

SECRET = "root:x:0:0:root:/root:/bin/bash"


def audit(path: Path, kind: str) -> list[dict[str, Any]]:
    return [r for r in read_audit(path) if r["kind"] == kind]


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    """The running rule file in ``run/``, an allowed directory ``allowed/``, and things outside both."""
    run, allowed, outside = (tmp_path / d for d in ("run", "allowed", "outside"))
    for d in (run, allowed, outside):
        d.mkdir()
    shutil.copy(RULES, run / "rules.sleec")
    (allowed / "new.sleec").write_text(NEW_RULES, encoding="utf-8")
    (outside / "new.sleec").write_text(NEW_RULES, encoding="utf-8")  # good rules, in the wrong place
    (outside / "passwd").write_text(SECRET + "\n", encoding="utf-8")
    (tmp_path / "allowed-too").mkdir()  # shares the allowed directory's name as a prefix
    (tmp_path / "allowed-too" / "new.sleec").write_text(NEW_RULES, encoding="utf-8")
    return {"run": run / "rules.sleec", "allowed": allowed, "outside": outside, "root": tmp_path}


@pytest.fixture
def plain(bus: LocalBus, files: dict[str, Path]) -> Iterator[Robot]:
    """A Manager node started as an operator starts it by default: no reload directory, no decide."""
    r = Robot(bus, files["run"], audit=str(files["root"] / "audit.jsonl"))
    yield r
    r.node.close()


@pytest.fixture
def with_dir(bus: LocalBus, files: dict[str, Path]) -> Iterator[Robot]:
    r = Robot(bus, files["run"], audit=str(files["root"] / "audit.jsonl"), reload_dir=str(files["allowed"]))
    yield r
    r.node.close()


# ----------------------------------------------------------------------------- ~/reload: what is read


def test_by_default_reload_reads_the_running_file_and_nothing_else(
    plain: Robot, files: dict[str, Path]
) -> None:
    before = plain.node.manager.rules_hash
    assert plain.reload()["success"] is True  # no path: the file it runs
    assert plain.reload(rules=str(files["run"]))["success"] is True  # that file, named
    assert plain.reload(rules=os.path.relpath(files["run"]))["success"] is True  # ...relative to the node
    for other in (files["allowed"] / "new.sleec", files["outside"] / "new.sleec"):
        answer = plain.reload(rules=str(other))
        assert answer["success"] is False and answer["message"].startswith("reload refused: ")
        assert answer["previous_hash"] == answer["current_hash"] == before
    assert plain.node.manager.rules_hash == before  # the caller's rules were never put in force
    assert plain.node.counters["reloads_refused"] == 2


@pytest.mark.parametrize("fixture", ["plain", "with_dir"])
def test_a_refused_path_gets_one_fixed_answer_whatever_it_is(
    fixture: str, request: pytest.FixtureRequest, files: dict[str, Path]
) -> None:
    # before: "/etc/passwd:1:1: error: unexpected root ... root:x:0:0:..." -- an existence and content oracle
    robot: Robot = request.getfixturevalue(fixture)
    paths = [
        "/etc/passwd",
        str(files["outside"] / "passwd"),
        str(files["outside"] / "missing.sleec"),
        str(files["outside"]),
        str(files["outside"] / "new.sleec"),
        str(files["allowed"] / ".." / "outside" / "passwd"),
        str(files["root"] / "allowed-too" / "new.sleec"),  # a prefix of the name is not "under"
        "x\0y",
    ]
    answers = {json.dumps(robot.reload(rules=p), sort_keys=True) for p in paths}
    assert len(answers) == 1, answers
    (answer,) = map(json.loads, answers)
    assert answer["success"] is False and answer["message"].startswith("reload refused: ")
    assert SECRET not in answer["message"] and "passwd" not in answer["message"]


@pytest.mark.parametrize("fixture", ["plain", "with_dir"])
def test_a_refused_path_is_not_touched(
    fixture: str, request: pytest.FixtureRequest, files: dict[str, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    plain: Robot = request.getfixturevalue(fixture)
    touched: list[str] = []
    for name in ("stat", "lstat", "open", "readlink", "listdir"):
        real = getattr(os, name)

        def spy(path: Any, *a: Any, _real: Any = real, **k: Any) -> Any:
            if "outside" in str(path):
                touched.append(str(path))
            return _real(path, *a, **k)

        monkeypatch.setattr(os, name, spy)
    loaded: list[str] = []
    plain.node._load = lambda p: (loaded.append(p), RuleSet.from_file(p))[1]
    plain.reload(rules=str(files["outside"] / "passwd"))
    plain.reload(rules=str(files["outside"] / "new.sleec"))
    plain.reload(rules=str(files["allowed"] / ".." / "outside" / "new.sleec"))
    assert touched == [] and loaded == []


def test_with_a_reload_dir_its_files_are_read_and_nothing_outside(
    with_dir: Robot, files: dict[str, Path]
) -> None:
    allowed = files["allowed"]
    ok = with_dir.reload(rules=str(allowed / "new.sleec"))
    assert ok["success"] is True and ok["current_hash"] == RuleSet.from_text(NEW_RULES).digest
    assert with_dir.node.rules_path == str((allowed / "new.sleec").resolve())  # the file it runs now
    assert with_dir.reload()["success"] is True  # and re-reads
    # `..` out of the directory, even through it, is refused
    escape = with_dir.reload(rules=str(allowed / ".." / "outside" / "new.sleec"))
    assert escape["success"] is False and escape["message"].startswith("reload refused")


def test_a_symlink_under_the_reload_dir_counts_where_it_points(
    with_dir: Robot, files: dict[str, Path]
) -> None:
    allowed = files["allowed"]
    (allowed / "out.sleec").symlink_to(files["outside"] / "new.sleec")
    (allowed / "sub").symlink_to(files["outside"], target_is_directory=True)
    (allowed / "in.sleec").symlink_to(allowed / "new.sleec")
    before = with_dir.node.manager.rules_hash
    for path in (allowed / "out.sleec", allowed / "sub" / "new.sleec", allowed / "sub" / "passwd"):
        answer = with_dir.reload(rules=str(path))
        assert answer["success"] is False and answer["message"].startswith("reload refused"), path
    assert with_dir.node.manager.rules_hash == before
    inside = with_dir.reload(rules=str(allowed / "in.sleec"))
    assert inside["success"] is True
    assert with_dir.node.rules_path == str((allowed / "new.sleec").resolve())  # what was read


def test_the_reload_dir_may_be_given_through_a_symlink(bus: LocalBus, files: dict[str, Path]) -> None:
    link = files["root"] / "link-to-allowed"
    link.symlink_to(files["allowed"], target_is_directory=True)
    r = Robot(bus, files["run"], reload_dir=str(link))
    try:
        for path in (link / "new.sleec", files["allowed"] / "new.sleec"):  # either spelling
            assert r.reload(rules=str(path))["success"] is True
    finally:
        r.node.close()


def test_a_reload_dir_that_is_no_directory_is_refused_at_start(bus: LocalBus, files: dict[str, Path]) -> None:
    for bad in (files["outside"] / "passwd", files["root"] / "nope"):
        with pytest.raises(UserError, match="is not a directory"):
            Robot(bus, files["run"], reload_dir=str(bad))


def test_an_allowed_file_that_fails_says_why(with_dir: Robot, files: dict[str, Path]) -> None:
    broken = files["allowed"] / "broken.sleec"
    broken.write_text("def_start\n  event A\n", encoding="utf-8")
    answer = with_dir.reload(rules=str(broken))
    assert answer["success"] is False and "broken.sleec" in answer["message"] and "error" in answer["message"]


# ----------------------------------------------------------------------------- ~/reload: the audit log


def test_every_reload_attempt_is_recorded_with_its_outcome_and_both_hashes(
    with_dir: Robot, files: dict[str, Path]
) -> None:
    before = with_dir.node.manager.rules_hash
    new = files["allowed"] / "new.sleec"
    broken = files["allowed"] / "broken.sleec"
    broken.write_text("def_start\n", encoding="utf-8")
    with_dir.reload(rules="/etc/passwd")
    with_dir.reload(rules=str(broken))
    ok = with_dir.reload(rules=str(new))
    with_dir.node.reload(via="signal")  # SIGHUP, as cosleec.ros.serve does it
    records = audit(files["root"] / "audit.jsonl", "reload-attempt")
    assert [(r["via"], r["outcome"]) for r in records] == [
        ("service", "refused"),
        ("service", "failed"),
        ("service", "reloaded"),
        ("signal", "reloaded"),
    ]
    refused, failed, reloaded, signal = records
    assert refused["path"] == "/etc/passwd" and "file" not in refused  # nothing was read
    assert refused["reason"].startswith("reload refused") and SECRET not in json.dumps(refused)
    assert refused["previous_hash"] == refused["current_hash"] == before
    assert failed["file"] == str(broken.resolve()) and "broken.sleec" in failed["reason"]
    assert failed["previous_hash"] == failed["current_hash"] == before
    assert (reloaded["previous_hash"], reloaded["current_hash"]) == (before, ok["current_hash"])
    assert reloaded["file"] == str(new.resolve()) and "reason" not in reloaded
    assert signal["path"] is None and signal["file"] == str(new.resolve())
    # a local call says no caller: the middleware (ROS 1) gives one, ROS 2 cannot
    assert all(r["caller"] is None for r in records)
    assert [r["seq"] for r in read_audit(files["root"] / "audit.jsonl")] == list(
        range(1, len(read_audit(files["root"] / "audit.jsonl")) + 1)
    )


def test_a_reload_that_fails_on_a_bug_is_recorded_and_raised(plain: Robot, files: dict[str, Path]) -> None:
    def broken(path: str) -> RuleSet:
        raise ZeroDivisionError("a bug")

    plain.node._load = broken
    with pytest.raises(ZeroDivisionError):
        plain.reload()
    (r,) = audit(files["root"] / "audit.jsonl", "reload-attempt")
    assert (r["outcome"], r["reason"]) == ("failed", "ZeroDivisionError: a bug")


def test_the_caller_a_transport_names_is_recorded(with_dir: Robot, files: dict[str, Path]) -> None:
    with_dir.t.call("~/reload", {"rules": "/etc/shadow", "_caller": "/intruder"})
    (r,) = audit(files["root"] / "audit.jsonl", "reload-attempt")
    assert (r["caller"], r["outcome"], r["path"]) == ("/intruder", "refused", "/etc/shadow")


def test_a_long_path_is_cut_in_the_record(plain: Robot, files: dict[str, Path]) -> None:
    plain.reload(rules="/" + "a" * 100_000)
    (r,) = audit(files["root"] / "audit.jsonl", "reload-attempt")
    assert len(r["path"]) < 400 and r["path"].endswith("(99701 more)")


# ----------------------------------------------------------------------------- ~/decide


def test_decide_is_off_by_default(plain: Robot, files: dict[str, Path]) -> None:
    assert DEFAULT_DECIDE == "off" and DECIDE == ("off", "events-only", "all")
    version = plain.node.manager.context.version
    for req in (
        {"values": {"userNearby": False}},
        {"event": "UserApproaches"},
        {"values": {"userNearby": False}, "event": "UserApproaches"},
    ):
        answer = plain.decide(**req)
        assert answer["accepted"] is False and answer["decisions"] == []
        assert answer["error"].startswith("~/decide is off on this Manager")
    assert plain.node.manager.context.version == version and plain.node.manager.stats["events"] == 0
    records = audit(files["root"] / "audit.jsonl", "rejected")
    assert [(r["what"], r["topic"]) for r in records] == [("decide", "~/decide")] * 3
    assert records[0]["reason"].startswith("~/decide is off")
    assert plain.node.counters["rejected"] == 3


def test_decide_events_only_takes_an_event_and_no_values(bus: LocalBus, files: dict[str, Path]) -> None:
    r = Robot(bus, files["run"], decide="events-only")
    try:
        refused = r.decide(values={"userNearby": False}, event="UserApproaches")
        assert refused["accepted"] is False and "events only" in refused["error"]
        assert r.node.manager.stats["events"] == 0 and r.node.manager.values()["userNearby"] is None
        taken = r.decide(event="UserApproaches")
        assert taken["accepted"] is True and [d["rule"] for d in taken["decisions"]] == ["R3"]
    finally:
        r.node.close()


def test_decide_all_takes_values_and_an_event(bus: LocalBus, files: dict[str, Path]) -> None:
    r = Robot(bus, files["run"], decide="all")
    try:
        answer = r.decide(values={"userAsleep": True, "userNearby": False}, event="CleanRequest")
        assert answer["accepted"] is True and answer["decisions"][0]["clause"] == 1
    finally:
        r.node.close()


def test_an_unknown_decide_choice_is_refused(bus: LocalBus, files: dict[str, Path]) -> None:
    with pytest.raises(ConfigurationError, match="decide must be one of off, events-only, all"):
        Robot(bus, files["run"], decide="yes")


# ----------------------------------------------------------------------------- rejections recorded


@pytest.mark.parametrize(
    ("topic", "payload", "reason"),
    [
        ("context", "not json", "Expecting value"),
        ("context", '"a string"', "expected a JSON object"),
        ("context", json.dumps({"values": {}}), "context message needs a non-empty object `values`"),
        ("context", json.dumps({"values": {"batteryLevel": 10**400}}), "too large for a float"),
        ("events", json.dumps({"event": 7}), "event message needs a string `event`"),
        ("request", json.dumps({"id": True, "event": "A"}), "request message needs an `id`"),
        ("clock", json.dumps({"t": "soon"}), "clock message needs a number `t`"),
    ],
)
def test_a_message_the_runtime_never_sees_gets_its_rejected_record(
    plain: Robot, files: dict[str, Path], topic: str, payload: str, reason: str
) -> None:
    # before: counted and published on `rejected`, but the audit log said nothing
    plain.t.publish(f"/cosleec/{topic}", payload)
    plain.idle()
    (r,) = audit(files["root"] / "audit.jsonl", "rejected")
    assert (r["what"], r["topic"]) == (topic, f"/cosleec/{topic}") and reason in r["reason"], r
    assert r["payload"] == payload[:200] or r["payload"].startswith(payload[:20])
    assert plain.node.manager.stats["rejected"] == 1 and plain.node.counters["rejected"] == 1


def test_an_event_while_inactive_gets_its_rejected_record(plain: Robot, files: dict[str, Path]) -> None:
    plain.node.deactivate()
    plain.send("events", {"event": "UserApproaches"})
    (r,) = audit(files["root"] / "audit.jsonl", "rejected")
    assert r["what"] == "events" and "inactive" in r["reason"]


@pytest.mark.parametrize(
    ("topic", "message"),
    [
        ("events", {"event": "NoSuchEvent"}),
        ("context", {"values": {"userAsleep": "yes"}}),
        ("events", {"event": "CleanRequest", "values": {"nope": True}}),
        ("request", {"id": 1, "event": "NoSuchEvent"}),
    ],
)
def test_what_the_runtime_rejects_is_recorded_once(
    plain: Robot, files: dict[str, Path], topic: str, message: dict[str, Any]
) -> None:
    plain.send(topic, message)
    records = audit(files["root"] / "audit.jsonl", "rejected")
    assert len(records) == 1 and "topic" not in records[0], records  # the runtime's own record
    assert plain.node.counters["rejected"] == 1


def test_a_service_request_the_transport_cannot_decode_gets_its_rejected_record(
    plain: Robot, files: dict[str, Path]
) -> None:
    # what a ROS transport does with a Decide whose MeasureValue has an unknown kind (tests/ros)
    plain.t.rejected("~/decide", MessageError("measure 'hot' has kind 9; kinds are ..."), "/intruder")
    plain.idle()
    (r,) = audit(files["root"] / "audit.jsonl", "rejected")
    assert (r["what"], r["topic"], r["caller"]) == ("decide", "~/decide", "/intruder")
    assert "kind 9" in r["reason"]
    assert plain.out["rejected"][-1]["topic"] == "~/decide" and plain.node.counters["rejected"] == 1


def test_a_closed_manager_cannot_record_and_the_node_says_so_without_raising(
    plain: Robot, caplog: pytest.LogCaptureFixture
) -> None:
    plain.node.manager.close()
    plain.t.publish("/cosleec/context", "not json")
    plain.idle()
    assert plain.node.counters["rejected"] == 1
    assert "cannot record rejected" in caplog.text
    assert plain.reload(rules="/etc/passwd")["message"].startswith("reload refused")


# ----------------------------------------------------------------------------- the command line


def test_the_command_line_refuses_a_reload_dir_that_is_no_directory_before_any_middleware(
    files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    from cosleec.cli.main import main

    rc = main(["ros2", "manager", str(files["run"]), "--reload-dir", str(files["root"] / "nope")])
    err = capsys.readouterr().err
    assert rc == 1 and "is not a directory" in err and "Traceback" not in err
    rc = main(["ros2", "manager", str(files["run"]), "--decide", "yes"])
    assert rc == 2 and "invalid choice: 'yes'" in capsys.readouterr().err


def test_reload_dir_and_decide_are_no_ros_parameters() -> None:
    # a ROS 1 node reads a parameter it was not given from the parameter server, which anyone
    # on the graph can write: what the operator allows comes from the command line alone
    from cosleec.cli.ros import PARAMETERS

    assert not {"reload_dir", "decide"} & set(PARAMETERS["manager"])


def test_cosleec_conforms_reads_an_audit_log_with_these_records(
    with_dir: Robot, files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    from cosleec.cli.main import main

    with_dir.send("events", {"event": "UserApproaches"})
    with_dir.reload(rules="/etc/passwd")
    with_dir.t.publish("/cosleec/context", "garbage")
    with_dir.decide(event="UserApproaches")
    with_dir.at(5.0)
    with_dir.reload()
    with_dir.at(40.0)
    with_dir.node.close()
    log = files["root"] / "audit.jsonl"
    assert {"reload-attempt", "rejected"} <= {r["kind"] for r in read_audit(log)}
    rc = main(["conforms", str(files["run"]), str(log)])
    assert rc == 0, capsys.readouterr()


# ----------------------------------------------------------------------------- what cosleec cannot prevent


def test_a_forged_request_reply_is_believed_by_a_task_node(bus: LocalBus) -> None:
    # `request` is readable and `request_reply` writable by anyone on the domain: a participant
    # that answers first is believed (docs/ros.md, "Threat model"; SROS2 permissions close it)
    from cosleec.nodes import TaskNode

    forger = bus.transport()

    def answer(payload: str) -> None:
        asked = json.loads(payload)
        reply = {"id": asked["id"], "event": asked["event"], "allowed": True}
        forger.publish("/cosleec/request_reply", json.dumps(reply))

    forger.subscribe("/cosleec/request", answer)
    task = TaskNode(bus.transport(), RuleSet.from_file(RULES), request_timeout=2.0)
    try:
        assert task.request("MoveNearUser") is True  # no Manager at all, and yet "allowed"
    finally:
        task.close()


def test_every_test_the_threat_model_names_exists() -> None:
    # docs/ros.md names the test behind each claim: a renamed or deleted test must not leave a
    # claim standing on nothing
    import re

    root = Path(__file__).resolve().parents[3]
    text = (root / "docs" / "ros.md").read_text(encoding="utf-8").split("## Threat model", 1)[1]
    named: list[tuple[str, str]] = []
    for cell in re.findall(r"`((?:tests/[\w/]+\.py)?::\w+)`", text):
        path, name = cell.split("::")
        named.append((path or named[-1][0], name))
    assert len(named) >= 20
    for path, name in named:
        assert re.search(rf"^def {name}\(", (root / path).read_text(encoding="utf-8"), re.M), (
            f"{path}::{name}"
        )


def test_the_manager_notes_only_the_two_kinds_a_front_end_may_add(plain: Robot) -> None:
    with pytest.raises(ConfigurationError, match="note records rejected or reload-attempt, not 'decision'"):
        plain.node.manager.note("decision", {"rule": "R1"})
