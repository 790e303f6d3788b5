"""The mapping schema alone (:mod:`cosleec.nodes.mapping`): every check of an entry, with
the whole message and its ``file:line:col``, the order the checks run in (an entry with
two mistakes reports the first), and the names offered on from the listener module.

No node and no rule file: the rules' measures and events are given as they are.
"""

from __future__ import annotations

import pytest

import cosleec.nodes
import cosleec.nodes.guard_node
import cosleec.nodes.listener
from cosleec.nodes.mapping import Entry, Mapping, MappingError, read_yaml
from cosleec.runtime import MeasureSpec

MEASURES = {
    "dark": MeasureSpec("dark", "boolean"),
    "lux": MeasureSpec("lux", "numeric"),
    "mood": MeasureSpec("mood", "scale", ("low", "mid", "high")),
}
EVENTS = frozenset({"Clean", "Stop"})


def error(text: str, *, rules: bool = True) -> str:
    """The MappingError ``text`` is, read as ``m.yaml`` (against the rules above, if ``rules``)."""
    with pytest.raises(MappingError) as info:
        if rules:
            Mapping.parse(text, "m.yaml", MEASURES, EVENTS)
        else:
            Mapping.parse(text, "m.yaml")
    return str(info.value)


def block(kind: str, name: str, *lines: str) -> str:
    """An entry in block style: its name on line 2 (column 3), its keys from line 3, column 5."""
    return f"{kind}:\n  {name}:\n" + "".join(f"    {line}\n" for line in lines)


TOPIC = ("topic: /t", "type: std_msgs/Float64")


# ---------------------------------------------------------------------- each check, in full
@pytest.mark.parametrize(
    ("text", "message"),
    [
        (block("measures", "lux") + "", "m.yaml:2:3: measures.lux: expected an entry with at least `topic` and `type`"),
        (block("measures", "lux", *TOPIC, "feild: data"), "m.yaml:5:5: measures.lux: unknown key(s) ['feild'] (did you mean 'field'?); allowed: "),
        (block("measures", "lux", "topic: /t"), "m.yaml:2:3: measures.lux: `type` is required and must be a string"),
        (block("measures", "lux", "topic: 3", "type: std_msgs/Float64"), "m.yaml:2:3: measures.lux: `topic` is required and must be a string"),
        (block("measures", "dark", *TOPIC, "above: 1", "bands: [[1, a], [b]]"), "m.yaml:2:3: measures.dark: give at most one of ['above', 'at_least', 'at_most', 'below', 'equals', 'not_equals'] or `bands`"),
        (block("measures", "dark", *TOPIC, "below: .inf"), "m.yaml:5:12: measures.dark: `below` must be a finite number, not infinity: a finite reading"),
        (block("measures", "dark", *TOPIC, "below: 1", "fire: each"), "m.yaml:6:5: measures.dark: `fire` is for events; a measure's value is sent with every message"),
        (block("events", "Clean", *TOPIC, "below: 1", "fire: eahc"), "m.yaml:6:5: events.Clean: `fire` is edge (when the condition becomes true; the default) or each (every message for which it holds), not 'eahc' (did you mean 'each'?)"),
        (block("measures", "lux", *TOPIC, "json: yes please"), "m.yaml:2:3: measures.lux: `json` must be true or false, not 'yes please'"),
        (block("measures", "lux", *TOPIC, "qos: sensor_dta"), "m.yaml:5:5: measures.lux: qos: "),
        (block("events", "Clen", *TOPIC, "below: 1"), "m.yaml:2:3: events.Clen: the rules declare no event 'Clen' (did you mean 'Clean'?)"),
        (block("events", "mood", *TOPIC, "below: 1"), "m.yaml:2:3: events.mood: the rules declare no event 'mood'; it is a measure of the rules: list it under `measures`"),
        (block("events", "Clean", *TOPIC), "m.yaml:2:3: events.Clean: an event needs a condition (e.g. `equals: true`)"),
        (block("measures", "Stop", *TOPIC), "m.yaml:2:3: measures.Stop: the rules declare no measure 'Stop'; it is an event of the rules: list it under `events`"),
        (block("measures", "mood", *TOPIC, "bands: [[1, lwo], [hihg]]"), "m.yaml:2:3: measures.mood: ['lwo', 'hihg'] not in the scale of mood (low, mid, high) (did you mean 'low' for 'lwo', 'high' for 'hihg'?)"),
        (block("measures", "lux", *TOPIC, "bands: [[1, low], [high]]"), "m.yaml:2:3: measures.lux: `bands` give scale literals, but lux is numeric"),
        (block("measures", "lux", *TOPIC, "above: 1"), "m.yaml:2:3: measures.lux: a comparison gives a boolean, but lux is numeric"),
    ],
)  # fmt: skip
def test_each_mistake_of_an_entry_is_said_at_its_place(text: str, message: str) -> None:
    got = error(text)
    assert got.startswith(message), got


def test_an_entry_that_is_no_table_is_said_at_its_name() -> None:
    assert (
        error("measures:\n  lux: 3\n")
        == "m.yaml:2:3: measures.lux: expected an entry with at least `topic` and `type`"
    )


def test_without_the_rules_no_name_or_kind_is_checked_but_an_event_still_needs_a_condition() -> None:
    m = Mapping.parse(block("measures", "anything", *TOPIC, "above: 1"), "m.yaml")
    assert m.entries[0].comparison == ("above", 1) and m.entries[0].measure_kind is None
    assert error(block("events", "Anything", *TOPIC), rules=False).startswith(
        "m.yaml:2:3: events.Anything: an event needs a condition"
    )


# ---------------------------------------------------------------------- the order of the checks
#: an entry with the mistake of row i and of every row after it reports the mistake of row i
ORDER = [
    ("feild: data", "unknown key(s) ['feild']"),
    ("type: 3", "`type` is required"),
    ("bands: [[1, low], [high]]", "give at most one of"),
    ("below: .nan", "`below` must be a finite number"),
    ("fire: often", "`fire` is edge"),
    ("json: 2", "`json` must be true or false"),
    ("qos: nope", "qos: "),
]


@pytest.mark.parametrize("first", range(len(ORDER)))
def test_an_entry_with_several_mistakes_reports_the_first_checked(first: int) -> None:
    lines = ["topic: /t", *(line for line, _ in ORDER[first:])]
    if not any(line.startswith("type:") for line in lines):
        lines.append("type: std_msgs/Float64")
    got = error(block("events", "Nope", *lines))
    assert ORDER[first][1] in got, got


def test_the_checks_against_the_rules_come_after_the_entrys_own() -> None:
    # an undeclared event with a bad `fire`: the entry's own mistake is said first
    assert "`fire` is edge" in error(block("events", "Nope", *TOPIC, "below: 1", "fire: often"))
    # a measure of the wrong section with bands outside any scale: the section is said first
    assert "it is an event of the rules" in error(block("measures", "Clean", *TOPIC, "bands: [[1, x], [y]]"))


# ---------------------------------------------------------------------- what a good entry is
def test_a_good_entry_is_read_whole() -> None:
    text = block("events", "Clean", "topic: /voice", "type: std_msgs/String", "equals: clean", "fire: each")
    (e,) = Mapping.parse(text, "m.yaml", MEASURES, EVENTS).entries
    assert e == Entry(
        name="Clean",
        kind="event",
        topic="/voice",
        type="std_msgs/String",
        field=("data",),
        json=False,
        comparison=("equals", "clean"),
        bands=None,
        fire="each",
        where="m.yaml:2:3",
    )


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        ((), ("data",)),
        (("json: true",), ()),
        (("json: true", "field: a.b"), ("a", "b")),
        (("field: x",), ("x",)),
    ],
)
def test_the_field_read_is_data_the_json_root_or_the_dotted_path_given(
    extra: tuple[str, ...], field: tuple[str, ...]
) -> None:
    (e,) = Mapping.parse(block("measures", "lux", *TOPIC, *extra), "m.yaml", MEASURES, EVENTS).entries
    assert e.field == field and e.json == ("json: true" in extra)


def test_a_measure_of_the_rules_takes_its_kind_and_scale() -> None:
    (e,) = Mapping.parse(
        block("measures", "mood", *TOPIC, "bands: [[1, low], [high]]"), "m.yaml", MEASURES
    ).entries
    assert (e.measure_kind, e.literals) == ("scale", ("low", "mid", "high"))


# ---------------------------------------------------------------------- the YAML reader
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a: 1\nb: [\n", "src.yaml:3:1: not valid YAML: "),
        ("a: 1\n  b: 2\n", "src.yaml:2:4: not valid YAML: "),
        ("a: 1\nb: 2\na: 3\n", "src.yaml:3:1: 'a' is given twice (the second would replace the first)"),
        ("x:\n  y: 1\n  y: 2\n", "src.yaml:3:3: 'y' is given twice"),
    ],
)
def test_read_yaml_says_where_the_text_is_wrong(text: str, message: str) -> None:
    with pytest.raises(MappingError) as info:
        read_yaml(text, "src.yaml")
    assert str(info.value).startswith(message), str(info.value)


def test_read_yaml_reads_an_empty_text_as_an_empty_table() -> None:
    assert read_yaml("", "src.yaml") == {} and read_yaml("# nothing\n", "src.yaml") == {}


# ---------------------------------------------------------------------- where the names are
def test_the_mapping_names_are_the_same_objects_from_the_package_and_the_guard() -> None:
    assert cosleec.nodes.Mapping is Mapping and cosleec.nodes.MappingError is MappingError
    # the guard reads its routes with the mapping's read_yaml: the one reader
    assert cosleec.nodes.guard_node.read_yaml is read_yaml
    assert cosleec.nodes.guard_node.MappingError is MappingError
