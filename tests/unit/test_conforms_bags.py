"""``cosleec conforms RULES BAG --mapping M``: field bags of the robot's own topics, written here
by rosbags' own writers (rosbag2 MCAP, rosbag2 SQLite 3, ROS 1 .bag), replayed through the
Context Listener's mapping code and judged by the reference semantics."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("rosbags")

from cosleec.cli.main import main
from cosleec.nodes.fieldbag import replay
from cosleec.nodes.mapping import Mapping
from tests.bagwriter import FORMATS, T0, Message, write_bag

RULES = """\
def_start
    event UserFallen
    event CallSupport
    event RecordVideo
    event LowBattery
    event Dock
    measure userConsent : boolean
    measure batteryLevel : numeric
def_end
rule_start
    R1 when UserFallen then CallSupport within 30 seconds
    R2 when UserFallen then not RecordVideo within 60 seconds unless userConsent
    R3 when LowBattery then Dock within 2 minutes
rule_end
"""

MAPPING = """\
measures:
  userConsent:  {topic: /consent, type: std_msgs/Bool}
  batteryLevel: {topic: /battery, type: sensor_msgs/msg/BatteryState, field: percentage}
events:
  UserFallen:   {topic: /fall, type: std_msgs/Bool, equals: true}
  CallSupport:  {topic: /support, type: std_msgs/String, equals: calling, fire: each}
  RecordVideo:  {topic: /camera/recording, type: std_msgs/Bool, equals: true}
  LowBattery:   {topic: /battery, type: sensor_msgs/msg/BatteryState, field: percentage, below: 0.2}
  Dock:         {topic: /dock, type: std_msgs/Float64, above: 0.5}
"""

BOOL, STRING, FLOAT, BATTERY = (
    "std_msgs/msg/Bool",
    "std_msgs/msg/String",
    "std_msgs/msg/Float64",
    ("sensor_msgs/msg/BatteryState"),
)

# A run that obeys the rules. /fall stays true from 10 s to 50 s: one fall (an edge), not two --
# a second UserFallen at 50 s would owe a CallSupport by 80 s that never comes.
COMPLIANT: list[Message] = [
    (0.0, "/consent", BOOL, {"data": False}),
    (0.0, "/battery", BATTERY, {"percentage": 0.5}),
    (0.0, "/fall", BOOL, {"data": False}),
    (0.0, "/camera/recording", BOOL, {"data": False}),
    (10.0, "/fall", BOOL, {"data": True}),
    (20.0, "/support", STRING, {"data": "calling"}),
    (30.0, "/battery", BATTERY, {"percentage": 0.15}),
    (50.0, "/fall", BOOL, {"data": True}),
    (60.0, "/dock", FLOAT, {"data": 1.0}),
    (100.0, "/fall", BOOL, {"data": False}),
]
# ... and one that films the fallen user without consent, 30.25 s after the fall
VIOLATING: list[Message] = [*COMPLIANT, (40.25, "/camera/recording", BOOL, {"data": True})]


@pytest.fixture
def files(tmp_path: Path) -> tuple[str, str]:
    (tmp_path / "rules.sleec").write_text(RULES)
    (tmp_path / "mapping.yaml").write_text(MAPPING)
    return str(tmp_path / "rules.sleec"), str(tmp_path / "mapping.yaml")


def conforms(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    rc = main(["conforms", *args])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, " ".join(out.split()), err  # rich wraps long lines: judge the words


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_compliant_field_bag_conforms(
    fmt: str, files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files
    bag = write_bag(tmp_path / "run", fmt, COMPLIANT)
    rc, out, err = conforms(capsys, rules, str(bag), "--mapping", mapping)
    assert rc == 0, out + err
    assert "10 messages on 6 mapped topics, 100 s from 2024-06-10 06:40:00 UTC" in out
    assert "0 violations, 0 pending, 0 conflicts (trace up to 100 s)" in out
    assert "gap" not in out


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_violation_names_the_messages_behind_it(
    fmt: str, files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files
    bag = write_bag(tmp_path / "run", fmt, VIOLATING)
    rc, out, _ = conforms(capsys, rules, str(bag), "--mapping", mapping)
    assert rc == 1
    fall, video = f"{T0 // 10**9 + 10}.000000000", f"{T0 // 10**9 + 40}.250000000"
    assert (
        "violated R2 (default) at 40.25 s: not RecordVideo in [10, 70] -- RecordVideo happened at 40.25 s "
        f"from trigger UserFallen: /fall at 10 s (bag time {fall}); "
        f"RecordVideo: /camera/recording at 40.25 s (bag time {video})"
    ) in out
    assert "1 violation, 0 pending" in out


def test_the_json_document_names_each_verdicts_messages(
    files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files
    bag = write_bag(tmp_path / "run", "mcap", VIOLATING)
    assert main(["conforms", rules, str(bag), "--mapping", mapping, "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["conforms"] is False and doc["bag"]["complete"] is True and doc["bag"]["gaps"] == []
    # edges: one UserFallen although /fall said true twice; fire: each: CallSupport on its one message
    assert [f["event"] for f in doc["firings"] if f["rule"] == "R1"] == ["UserFallen"]
    [violated] = [v for v in doc["verdicts"] if v["status"] == "violated"]
    behind = doc["bag"]["behind"][str(violated["id"])]
    assert behind == [
        {"what": "trigger UserFallen", "topic": "/fall", "stamp_ns": T0 + 10 * 10**9, "t": 10.0},
        {"what": "RecordVideo", "topic": "/camera/recording", "stamp_ns": T0 + 40_250_000_000, "t": 40.25},
    ]


def test_fire_each_and_edges_come_from_the_listener(tmp_path: Path) -> None:
    """The replay is the listener's code: an edge event fires once while its condition holds,
    a ``fire: each`` event on every message, and the measures read by the message come first."""
    m = Mapping.parse(
        "events:\n"
        "  Edge: {topic: /x, type: std_msgs/Bool, equals: true}\n"
        "  Each: {topic: /x, type: std_msgs/Bool, equals: true, fire: each}\n"
        "measures:\n  lit: {topic: /x, type: std_msgs/Bool}\n"
    )
    bag = write_bag(
        tmp_path / "x",
        "mcap",
        [(t, "/x", BOOL, {"data": d}) for t, d in [(0, True), (1, True), (2, False), (3, True)]],
    )
    steps = [(s.t, s.event, dict(s.values)) for s in replay(bag, m).steps]
    assert steps == [
        (0.0, None, {"lit": True}), (0.0, "Edge", {}), (0.0, "Each", {}),
        (1.0, None, {"lit": True}), (1.0, "Each", {}),
        (2.0, None, {"lit": False}),
        (3.0, None, {"lit": True}), (3.0, "Edge", {}), (3.0, "Each", {}),
        (3.0, None, {}),
    ]  # fmt: skip


@pytest.mark.parametrize("fmt", ["sqlite3", "ros1"])
def test_a_bag_that_only_partly_covers_the_mapping_fails_closed(
    fmt: str, files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No /consent topic, and /dock recorded as a String: userConsent stays unknown (R2's
    firing is undecided, not a pass), Dock never happens -- and the run exits 1 with notes."""
    rules, mapping = files
    partial = [m for m in COMPLIANT if m[1] != "/consent" and m[1] != "/dock"]
    partial.append((60.0, "/dock", STRING, {"data": "docked"}))
    bag = write_bag(tmp_path / "run", fmt, partial)
    rc, out, _ = conforms(capsys, rules, str(bag), "--mapping", mapping)
    assert rc == 1
    assert "gap topic /consent is not in the bag: measure userConsent stays unknown gap" in out
    assert (
        "gap topic /dock is std_msgs/msg/String in the bag, the mapping reads std_msgs/Float64: event Dock never happens"
    ) in out
    assert "undecided R2 at 10 s: UserFallen -- no value for userConsent from /fall at 10 s" in out
    assert "violated R3 (default) at 150 s" not in out  # the trace ends at 100 s: R3 still pending
    assert "NOT judged whole: the bag does not cover the mapping (2 gaps above)" in out


def test_a_field_the_type_has_not_is_a_gap_and_the_listener_rejects_it(
    files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files
    Path(mapping).write_text(MAPPING.replace("field: percentage}", "field: percent}", 1))
    bag = write_bag(tmp_path / "run", "mcap", COMPLIANT)
    rc, out, _ = conforms(capsys, rules, str(bag), "--mapping", mapping, "--json")
    assert rc == 1
    doc = json.loads(out)
    assert doc["conforms"] is False and doc["bag"]["complete"] is False
    [gap] = doc["bag"]["gaps"]
    assert "measures.batteryLevel" in gap and "sensor_msgs/msg/BatteryState has no field 'percent'" in gap
    assert "percentage" in gap  # the fields it has
    assert doc["bag"]["rejections"] == [
        "2 messages on /battery rejected by the listener, the first at 0 s: /battery: message has no field 'percent'"
    ]


def test_bad_bags_and_mappings_are_input_errors(
    files: tuple[str, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, mapping = files
    bag = write_bag(tmp_path / "run", "mcap", COMPLIANT)
    rc, _, err = conforms(capsys, rules, str(bag))
    assert rc == 2 and "looks like a bag" in err and "--mapping MAPPING.yaml" in err
    rc, _, err = conforms(capsys, rules, str(tmp_path / "nope"), "--mapping", mapping)
    assert rc == 2 and "no such bag" in err
    (tmp_path / "lone.mcap").write_bytes(b"\x89MCAP0\r\n")
    rc, _, err = conforms(capsys, rules, str(tmp_path / "lone.mcap"), "--mapping", mapping)
    assert rc == 2 and "a rosbag2 bag is a directory with a metadata.yaml" in err
    (tmp_path / "broken.bag").write_bytes(b"#ROSBAG V2.0\nnot a bag")
    rc, _, err = conforms(capsys, rules, str(tmp_path / "broken.bag"), "--mapping", mapping)
    assert rc == 2 and "rosbags cannot read the bag" in err
    Path(mapping).write_text(MAPPING.replace("UserFallen:", "UserFalen:"))
    rc, _, err = conforms(capsys, rules, str(bag), "--mapping", mapping)
    assert rc == 2 and "the rules declare no event 'UserFalen'" in err and "UserFallen" in err
    # the .mcap inside a rosbag2 directory stands for the directory
    Path(mapping).write_text(MAPPING)
    rc, out, _ = conforms(capsys, rules, str(next(bag.glob("*.mcap"))), "--mapping", mapping)
    assert rc == 0, out
