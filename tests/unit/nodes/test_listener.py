"""The Context Listener's mapping: QoS per topic (defaults, profiles, tables, conflicts), how
events fire (``edge``, ``each``), and errors that name the file, the line and the entry."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from cosleec.nodes import ListenerNode, Mapping, MappingError
from cosleec.nodes.mapping import default_qos
from cosleec.nodes.qos import Qos

ROOT = Path(__file__).resolve().parents[3]


class FakeTransport:
    """Records subscriptions (with their QoS) and publications; delivers synchronously."""

    def __init__(self) -> None:
        self.typed: list[tuple[str, str, Qos | None]] = []
        self.handlers: dict[str, Callable[[dict[str, Any]], None]] = {}
        self.published: list[tuple[str, dict[str, Any]]] = []

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        self.published.append((topic, json.loads(message) if isinstance(message, str) else message))

    def subscribe(self, topic: str, handler: Any) -> None:
        pass

    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        self.typed.append((topic, type_name, qos))
        self.handlers[topic] = handler

    def advertise(self, topic: str, latched: bool = False) -> None:
        pass

    def close(self) -> None:
        pass

    def send(self, topic: str, **fields: Any) -> None:
        self.handlers[topic](fields)

    def events(self) -> list[str]:
        return [m["event"] for t, m in self.published if t == "/cosleec/events"]

    def context(self) -> list[dict[str, Any]]:
        return [m["values"] for t, m in self.published if t == "/cosleec/context"]


def qos(text: str, topic: str) -> Qos:
    return Mapping.parse(text, "m.yaml").qos_of(topic)


def error(text: str) -> str:
    with pytest.raises(MappingError) as info:
        Mapping.parse(text, "m.yaml")
    return str(info.value)


# ---------------------------------------------------------------------- QoS defaults
def test_a_measure_reads_best_effort_depth_5_by_default() -> None:
    assert qos("measures:\n  lux: {topic: /lux, type: std_msgs/Float64}", "/lux") == Qos(
        "best_effort", "volatile", 5
    )


def test_an_event_reads_reliable_depth_10_by_default() -> None:
    text = "events:\n  Clean: {topic: /cmd, type: std_msgs/msg/String, equals: clean}"
    assert qos(text, "/cmd") == Qos("reliable", "volatile", 10)


@pytest.mark.parametrize(
    ("type_name", "expected"),
    [
        ("sensor_msgs/msg/BatteryState", Qos.SENSOR_DATA),
        ("sensor_msgs/BatteryState", Qos.SENSOR_DATA),
        ("my_sensor_msgs/msg/Range", Qos.RELIABLE),  # only the package sensor_msgs itself
        ("std_msgs/msg/sensor_msgs", Qos.RELIABLE),
        ("std_msgs/Float64", Qos.RELIABLE),
    ],
)
def test_an_event_of_a_sensor_msgs_type_reads_best_effort(type_name: str, expected: Qos) -> None:
    field = "" if type_name == "std_msgs/Float64" else "field: percentage, "  # Float64 has only `data`
    text = f"events:\n  Low: {{topic: /battery, type: {type_name}, {field}below: 0.2}}"
    assert qos(text, "/battery") == expected
    assert default_qos("event", type_name) == expected


@pytest.mark.parametrize(
    ("entries", "expected"),
    [
        # a measure shares the topic: best effort, or the measure would not hear a sensor driver
        (["measures:", "  m: {topic: /t, type: std_msgs/Bool}", "events:", "  E: {topic: /t, type: std_msgs/Bool, equals: true}"], Qos.SENSOR_DATA),
        (["events:", "  E: {topic: /t, type: std_msgs/Bool, equals: true}", "  F: {topic: /t, type: std_msgs/Bool, equals: false}"], Qos.RELIABLE),
        # a stated QoS is the topic's, whatever the others' defaults
        (["measures:", "  m: {topic: /t, type: std_msgs/Bool}", "events:", "  E: {topic: /t, type: std_msgs/Bool, equals: true, qos: reliable}"], Qos.RELIABLE),
        (["events:", "  E: {topic: /t, type: std_msgs/Bool, equals: true}", "  F: {topic: /t, type: std_msgs/Bool, equals: false, qos: sensor_data}"], Qos.SENSOR_DATA),
    ],
)  # fmt: skip
def test_entries_on_one_topic_share_one_qos(entries: list[str], expected: Qos) -> None:
    assert qos("\n".join(entries), "/t") == expected


def test_one_topic_is_subscribed_once_with_its_qos() -> None:
    text = """
measures:
  level: {topic: /battery, type: sensor_msgs/msg/BatteryState, field: percentage}
  low:   {topic: /battery, type: sensor_msgs/msg/BatteryState, field: percentage, below: 0.2}
events:
  Clean: {topic: /cmd, type: std_msgs/msg/String, equals: clean}
  Latch: {topic: /map_ready, type: std_msgs/Bool, equals: true, qos: latched}
"""
    t = FakeTransport()
    ListenerNode(t, Mapping.parse(text, "m.yaml"))
    assert sorted(t.typed) == [
        ("/battery", "sensor_msgs/msg/BatteryState", Qos.SENSOR_DATA),
        ("/cmd", "std_msgs/msg/String", Qos.RELIABLE),
        ("/map_ready", "std_msgs/Bool", Qos.LATCHED),
    ]
    t.send("/battery", percentage=0.15)
    assert t.context() == [{"level": 0.15, "low": True}]  # one message, one atomic update


# ---------------------------------------------------------------------- stated QoS
@pytest.mark.parametrize("kind", ["measures", "events"])
@pytest.mark.parametrize("profile", ["sensor_data", "reliable", "latched"])
def test_a_named_profile_is_taken_as_it_is(kind: str, profile: str) -> None:
    cond = ", equals: true" if kind == "events" else ""
    text = f"{kind}:\n  X: {{topic: /t, type: std_msgs/Bool{cond}, qos: {profile}}}"
    assert qos(text, "/t") == Qos.PROFILES[profile]


@pytest.mark.parametrize(
    ("kind", "table", "expected"),
    [
        # the keys a table leaves out are the entry's default's
        ("measures", "{reliability: reliable}", Qos("reliable", "volatile", 5)),
        ("events", "{depth: 50}", Qos("reliable", "volatile", 50)),
        ("events", "{reliability: best_effort}", Qos("best_effort", "volatile", 10)),
        ("measures", "{durability: transient_local}", Qos("best_effort", "transient_local", 5)),
        ("events", "{reliability: best_effort, durability: transient_local, depth: 3}", Qos("best_effort", "transient_local", 3)),
    ],
)  # fmt: skip
def test_a_qos_table_fills_in_from_the_entrys_default(kind: str, table: str, expected: Qos) -> None:
    cond = ", equals: true" if kind == "events" else ""
    assert qos(f"{kind}:\n  X: {{topic: /t, type: std_msgs/Bool{cond}, qos: {table}}}", "/t") == expected


def test_the_same_qos_stated_twice_on_one_topic_agrees() -> None:
    text = """
events:
  A: {topic: /t, type: std_msgs/Bool, equals: true, qos: reliable}
  B: {topic: /t, type: std_msgs/Bool, equals: false, qos: {reliability: reliable, depth: 10}}
"""
    assert qos(text, "/t") == Qos.RELIABLE


def test_different_qos_stated_on_one_topic_is_an_error_naming_both_entries() -> None:
    text = """events:
  A: {topic: /t, type: std_msgs/Bool, equals: true, qos: reliable}
  B: {topic: /t, type: std_msgs/Bool, equals: false, qos: {depth: 11}}
"""
    message = error(text)
    assert message.startswith("m.yaml:3:3: events.B: qos reliable/volatile/depth 11 differs from events.A's")
    assert "reliable/volatile/depth 10 (m.yaml:2:3)" in message and "topic /t" in message


def test_qos_of_a_topic_no_entry_reads_is_an_error() -> None:
    with pytest.raises(MappingError, match="no entry reads topic /nope"):
        qos("events:\n  A: {topic: /t, type: std_msgs/Bool, equals: true}", "/nope")


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("sensor-data", "qos: no QoS profile 'sensor-data'; profiles: sensor_data, reliable, latched (did you mean 'sensor_data'?)"),
        ("5", "qos: qos must be a profile name (sensor_data, reliable, latched) or a table"),
        ("", "qos: qos must be a profile name"),
        ("{reliability: sometimes}", "qos: reliability 'sometimes' is not one of reliable, best_effort"),
        ("{durability: forever}", "qos: durability 'forever' is not one of volatile, transient_local"),
        ("{depth: 0}", "qos: depth must be a whole number from 1 to 100000, not 0"),
        ("{depth: '5'}", "qos: depth must be a whole number from 1 to 100000, not '5'"),
        ("{depth: true}", "qos: depth must be a whole number from 1 to 100000, not True"),
        ("{history: keep_all}", "qos: unknown qos key(s) ['history']; allowed: reliability, durability, depth"),
        ("{1: 2, depth: 3}", "qos keys are reliability, durability and depth, not ['1', 'depth']"),
    ],
)  # fmt: skip
def test_a_bad_qos_is_a_mapping_error_at_its_line(value: str, message: str) -> None:
    text = f"events:\n  Clean:\n    topic: /cmd\n    type: std_msgs/String\n    equals: clean\n    qos: {value}\n"
    got = error(text)
    assert got.startswith(f"m.yaml:6:5: events.Clean: {message}"), got


# ---------------------------------------------------------------------- how events fire
CMD = """
events:
  Clean: {topic: /cmd, type: std_msgs/msg/String, equals: clean, fire: %s}
  Stop:  {topic: /cmd, type: std_msgs/msg/String, equals: stop}
"""


def listener(text: str) -> FakeTransport:
    t = FakeTransport()
    ListenerNode(t, Mapping.parse(text, "m.yaml"))
    return t


def test_fire_each_fires_for_every_message_the_condition_holds_for() -> None:
    t = listener(CMD % "each")
    for word in ("clean", "clean", "clean", "nothing", "clean"):
        t.send("/cmd", data=word)
    assert t.events() == ["Clean"] * 4


def test_fire_edge_fires_once_while_the_condition_holds_and_again_after_it_went_false() -> None:
    t = listener(CMD % "edge")
    for word in ("clean", "clean", "clean"):
        t.send("/cmd", data=word)
    assert t.events() == ["Clean"]
    t.send("/cmd", data="stop")  # Clean's condition goes false; Stop's becomes true
    t.send("/cmd", data="clean")
    assert t.events() == ["Clean", "Stop", "Clean"]


def test_edge_is_the_default_and_each_event_keeps_its_own_edge() -> None:
    text = """
events:
  Clean: {topic: /cmd, type: std_msgs/String, equals: clean}
  Any:   {topic: /cmd, type: std_msgs/String, not_equals: stop, fire: each}
  Busy:  {topic: /cmd, type: std_msgs/String, not_equals: stop}
"""
    assert [e.fire for e in Mapping.parse(text).entries] == ["edge", "each", "edge"]
    t = listener(text)
    for word in ("clean", "clean", "mop"):
        t.send("/cmd", data=word)
    assert t.events() == ["Clean", "Any", "Busy", "Any", "Any"]


def test_an_unreadable_message_leaves_the_edge_as_it_was() -> None:
    t = listener(CMD % "edge")
    t.send("/cmd", data="clean")
    t.send("/cmd", nodata=1)  # rejected: neither fired nor reset
    t.send("/cmd", data="clean")
    assert t.events() == ["Clean"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (CMD % "always", "m.yaml:3:66: events.Clean: `fire` is edge (when the condition becomes true; the default) or each (every message for which it holds), not 'always'"),
        (CMD % "eahc", "not 'eahc' (did you mean 'each'?)"),
        (CMD % "true", "not True"),
        ("measures:\n  m: {topic: /t, type: std_msgs/Bool, fire: each}", "m.yaml:2:39: measures.m: `fire` is for events"),
    ],
)  # fmt: skip
def test_a_bad_fire_is_a_mapping_error_listing_the_choices(text: str, message: str) -> None:
    got = error(text)
    assert message in got and got.startswith("m.yaml:"), got


# ---------------------------------------------------------------------- errors and positions
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("events:\n  Clean: {topic: /c, type: std_msgs/String, equals: x, fier: each}", "m.yaml:2:56: events.Clean: unknown key(s) ['fier'] (did you mean 'fire'?); allowed: ["),
        ("measures:\n  m: {topic: /c, type: std_msgs/Bool, qso: reliable}", "m.yaml:2:39: measures.m: unknown key(s) ['qso'] (did you mean 'qos'?)"),
        ("measures:\n  m: {topic: /c, type: std_msgs/Bool, feild: data}", "unknown key(s) ['feild'] (did you mean 'field'?)"),
        ("mesures:\n  m: {topic: /c, type: std_msgs/Bool}", "m.yaml:1:1: unknown section(s) ['mesures'] (did you mean 'measures'?)"),
    ],
)  # fmt: skip
def test_an_unknown_key_suggests_the_key_meant(text: str, message: str) -> None:
    got = error(text)
    assert got.startswith(message) if message.startswith("m.yaml") else message in got, got


def test_an_unknown_key_like_no_known_one_suggests_nothing() -> None:
    got = error("measures:\n  m: {topic: /c, type: std_msgs/Bool, exec: 'import os'}")
    assert "unknown key(s) ['exec']; allowed: ['above'," in got and "did you mean" not in got


def test_an_entry_error_names_its_line_and_column() -> None:
    text = "events:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n\n  B: {topic: /b, type: std_msgs/Bool}\n"
    assert (
        error(text).split("\n")[0] == "m.yaml:4:3: events.B: an event needs a condition (e.g. `equals: true`)"
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("events:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n  A: {topic: /b, type: std_msgs/Bool, equals: true}", "m.yaml:3:3: 'A' is given twice"),
        ("measures:\n  m: {topic: /a, type: std_msgs/Bool,\n      topic: /b}", "m.yaml:3:7: 'topic' is given twice"),
    ],
)  # fmt: skip
def test_a_name_or_key_given_twice_is_an_error_not_silently_the_last(text: str, message: str) -> None:
    assert error(text).startswith(message)


def test_yaml_merge_keys_may_override_what_they_merge() -> None:
    text = """
events:
  A: &cmd {topic: /cmd, type: std_msgs/String, equals: a}
  B: {<<: *cmd, equals: b, fire: each}
"""
    a, b = Mapping.parse(text, "m.yaml").entries
    assert (b.topic, b.comparison, b.fire) == ("/cmd", ("equals", "b"), "each")
    assert (a.comparison, a.fire) == (("equals", "a"), "edge")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a: [", r"^m\.yaml:1:5: not valid YAML: "),
        ("namespace: 3", r"^m\.yaml:1:1: `namespace` must be a topic prefix such as /cosleec, not 3"),
        ("events:\n  A: {topic: /t, type: std_msgs/Bool, equals: true}\n  B: {topic: /t, type: std_msgs/String, equals: x}",
         r"^m\.yaml:3:3: events\.B: topic /t is given two types: std_msgs/Bool \(by events\.A\) and std_msgs/String"),
    ],
)  # fmt: skip
def test_other_mapping_errors_say_where(text: str, message: str) -> None:
    assert re.search(message, error(text))


# ---------------------------------------------------------------------- the documented examples
def yaml_blocks(markdown: str) -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", markdown, re.S)


def test_every_yaml_example_of_the_mapping_docs_is_a_valid_mapping() -> None:
    blocks = yaml_blocks((ROOT / "docs" / "mapping.md").read_text(encoding="utf-8"))
    assert len(blocks) >= 4
    for block in blocks:
        if block.startswith("# wrong"):
            with pytest.raises(MappingError):
                Mapping.parse(block, "docs")
        else:
            Mapping.parse(block, "docs")


def test_the_documented_battery_and_command_examples_behave_as_documented() -> None:
    battery, command = (
        b
        for b in yaml_blocks((ROOT / "docs" / "mapping.md").read_text(encoding="utf-8"))
        if "# example:" in b
    )
    t = listener(battery)
    assert t.typed == [("/battery_state", "sensor_msgs/msg/BatteryState", Qos.SENSOR_DATA)]
    t.send("/battery_state", percentage=0.5)
    t.send("/battery_state", percentage=0.1)
    t.send("/battery_state", percentage=float("nan"))  # unmeasured: rejected, not "low"
    assert t.context() == [
        {"batteryLevel": 0.5, "batteryLow": False},
        {"batteryLevel": 0.1, "batteryLow": True},
    ]
    t = listener(command)
    assert t.typed == [("/voice/command", "std_msgs/msg/String", Qos.RELIABLE)]
    for word in ("clean", "clean", "stop"):
        t.send("/voice/command", data=word)
    assert t.events() == ["CleanRequest", "CleanRequest", "StopRequest"]


def test_the_module_docstring_example_is_a_valid_mapping() -> None:
    import cosleec.nodes.mapping as mapping_module

    doc = mapping_module.__doc__ or ""
    example = doc.split("::\n\n", 1)[1].split("\n\n", 1)[0]
    m = Mapping.parse("\n".join(line[4:] for line in example.splitlines()), "docstring")
    assert {e.name for e in m.entries} >= {"batteryLevel", "CleanRequest"}
    assert m.qos_of("/fall_detector") == Qos.RELIABLE and m.qos_of("/battery") == Qos.SENSOR_DATA


def test_an_event_carries_the_values_read_from_its_own_message() -> None:
    # one distance reading gives `near` and fires Approach: the Manager must decide on this
    # reading, whatever order the context and events topics arrive in (ROS 1 reads each on a
    # thread of its own), so the event carries it
    t = listener(
        """
measures:
  near: {topic: /d, type: std_msgs/Float64, below: 1.5}
events:
  Approach: {topic: /d, type: std_msgs/Float64, below: 1.5}
  Ping: {topic: /p, type: std_msgs/String, equals: x}
"""
    )
    t.send("/d", data=1.0)
    t.send("/p", data="x")
    events = [m for topic, m in t.published if topic.endswith("/events")]
    assert [(m["event"], m.get("values")) for m in events] == [("Approach", {"near": True}), ("Ping", None)]
    contexts = [m for topic, m in t.published if topic.endswith("/context")]
    assert [m["values"] for m in contexts] == [{"near": True}]  # still published for everyone else


# ---------------------------------------------------------------------- thresholds must be finite
BIG = "1" + "0" * 400  # an integer no float can hold


def entry_at(line: str) -> str:
    """A measure entry in block style whose last line is ``line`` (written on line 5, from column 5)."""
    return f"measures:\n  m:\n    topic: /t\n    type: std_msgs/Float64\n    {line}\n"


@pytest.mark.parametrize(
    ("line", "column", "shown"),
    [
        ("below: .nan", 12, "NaN"),
        ("above: .inf", 12, "infinity"),
        ("at_least: -.inf", 15, "-infinity"),
        ("at_most: .NaN", 14, "NaN"),
        ("equals: .nan", 13, "NaN"),
        ("not_equals: +.inf", 17, "infinity"),
        (f"below: {BIG}", 12, "an integer of 401 digits"),
    ],
)
def test_a_comparison_with_nan_infinity_or_a_huge_integer_is_refused_at_its_value(
    line: str, column: int, shown: str
) -> None:
    # `below: .nan` would be accepted and never hold: the event could never fire
    got = error(entry_at(line))
    key = line.split(":")[0]
    assert got.startswith(f"m.yaml:5:{column}: measures.m: `{key}` must be a finite number, not {shown}"), got
    assert "give a number such as" in got, got


def test_a_non_finite_event_threshold_in_flow_style_points_at_the_value() -> None:
    text = "events:\n  Near: {topic: /d, type: std_msgs/Float64, below: .nan}\n"
    got = error(text)
    assert got.startswith("m.yaml:2:52: events.Near: `below` must be a finite number, not NaN"), got


@pytest.mark.parametrize(
    ("bands", "column", "message"),
    [
        ("[[.nan, low], [high]]", 14, "band 1's bound must be a finite number, not NaN"),
        ("[[0.3, low], [.inf, mid], [high]]", 26, "band 2's bound must be a finite number, not infinity"),
        ("[[-.inf, low], [high]]", 14, "band 1's bound must be a finite number, not -infinity"),
        (f"[[{BIG}, low], [high]]", 14, "band 1's bound must be a finite number, not an integer of 401 digits"),
        ("[[0.7, low], [0.3, mid], [high]]", 26, "band 2's bound 0.3 must be above band 1's 0.7"),
        ("[[0.5, low], [0.5, mid], [high]]", 26, "band 2's bound 0.5 must be above band 1's 0.5"),
    ],
)  # fmt: skip
def test_a_band_bound_that_no_value_could_reach_is_refused_at_its_value(
    bands: str, column: int, message: str
) -> None:
    got = error(entry_at(f"bands: {bands}"))
    assert got.startswith(f"m.yaml:5:{column}: measures.m: {message}"), got


def test_finite_thresholds_and_rising_bands_are_taken() -> None:
    m = Mapping.parse(entry_at("bands: [[-1, low], [0.5, mid], [1.0e+3, high], [top]]"), "m.yaml")
    assert m.entries[0].bands == ((-1.0, "low"), (0.5, "mid"), (1000.0, "high"), (float("inf"), "top"))
    m = Mapping.parse(entry_at("at_least: -40"), "m.yaml")
    assert m.entries[0].comparison == ("at_least", -40)


# ---------------------------------------------------------------------- an event on every message
EVERY = """
measures:
  m: {topic: /cmd, type: std_msgs/msg/String}
events:
  Heard: {topic: /cmd, type: std_msgs/msg/String, every_message: true}
  Clean: {topic: /cmd, type: std_msgs/msg/String, equals: clean}
"""


def test_an_every_message_event_fires_on_each_message_of_its_topic_without_a_condition() -> None:
    (_, heard, clean) = Mapping.parse(EVERY, "m.yaml").entries
    assert (heard.every_message, heard.comparison, heard.fire, heard.field) == (True, None, "each", ())
    assert (clean.every_message, clean.fire) == (False, "edge")
    t = listener(EVERY)
    for word in ("clean", "clean", "mop"):
        t.send("/cmd", data=word)
    assert t.events() == ["Heard", "Clean", "Heard", "Heard"]
    t.send("/cmd", other=1)  # it reads no field: a message without `data` is still a message
    assert t.events()[-1] == "Heard"
    # the values read from its own message travel with it, as with any event
    assert [m.get("values") for topic, m in t.published if topic == "/cosleec/events"][:2] == [
        {"m": "clean"}
    ] * 2


@pytest.mark.parametrize(
    ("entry", "message", "hint"),
    [
        # a forgotten condition is still an error; every_message: false is no condition either
        ("{topic: /c, type: std_msgs/String}", "m.yaml:2:3: events.E: an event needs a condition", "`every_message: true`"),
        ("{topic: /c, type: std_msgs/String, every_message: false}", "m.yaml:2:3: events.E: an event needs a condition", "`every_message: true`"),
        ("{topic: /c, type: std_msgs/String, every_message: yes please}", "m.yaml:2:41: events.E: `every_message` is true or false, not 'yes please'", "write `every_message: true`"),
        ("{topic: /c, type: std_msgs/String, every_message: true, equals: x}", "m.yaml:2:62: events.E: an `every_message` event fires on every message without a condition, so `equals` would be ignored", "`fire: each`"),
        ("{topic: /c, type: std_msgs/String, every_message: true, fire: edge}", "m.yaml:2:62: events.E: an `every_message` event fires on every message without a condition, so `fire` would be ignored", "leave out `fire`"),
        ("{topic: /c, type: std_msgs/String, field: x, every_message: true}", "m.yaml:2:41: events.E: an `every_message` event fires on every message without a condition, so `field` would be ignored", "leave out `field`"),
    ],
)  # fmt: skip
def test_every_message_is_said_explicitly_and_alone(entry: str, message: str, hint: str) -> None:
    with pytest.raises(MappingError) as info:
        Mapping.parse(f"events:\n  E: {entry}\n", "m.yaml")
    assert info.value.message.startswith(message), info.value.message
    assert hint in info.value.hint


def test_every_message_on_a_measure_is_an_error() -> None:
    with pytest.raises(MappingError) as info:
        Mapping.parse("measures:\n  m: {topic: /c, type: std_msgs/Bool, every_message: true}\n", "m.yaml")
    assert info.value.message.startswith("m.yaml:2:39: measures.m: `every_message` is for events")
