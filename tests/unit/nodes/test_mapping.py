"""The mapping schema alone (:mod:`cosleec.nodes.mapping`): every check of an entry, with
the whole message and its ``file:line:col``, the order the checks run in (an entry with
two mistakes reports the first), and the names offered on from the listener module.

No node and no rule file: the rules' measures and events are given as they are.
"""

from __future__ import annotations

import math

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

import cosleec.nodes
import cosleec.nodes.guard_node
import cosleec.nodes.listener
from cosleec.nodes.mapping import COMPARISONS, Entry, Mapping, MappingError, read_yaml
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
    # a type whose fields are not known here (std_msgs/Float64 has only `data`: checked below)
    (e,) = Mapping.parse(
        block("measures", "lux", "topic: /t", "type: my_msgs/Reading", *extra), "m.yaml", MEASURES, EVENTS
    ).entries
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


# ---------------------------------------------------------------------- comparison values, typed
STD = {"Bool": ("topic: /t", "type: std_msgs/Bool"), "String": ("topic: /t", "type: std_msgs/msg/String"),
       "Float64": TOPIC, "Int32": ("topic: /t", "type: std_msgs/Int32")}  # fmt: skip


def mistake(text: str, *, rules: bool = True) -> MappingError:
    """The MappingError ``text`` is, its hint included."""
    with pytest.raises(MappingError) as info:
        Mapping.parse(text, "m.yaml", *((MEASURES, EVENTS) if rules else ()))
    return info.value


@pytest.mark.parametrize(
    ("kind", "name", "lines", "message", "hint"),
    [
        # whatever the type: one plain value, never null; orderings compare numbers
        ("events", "Clean", (*STD["String"], "not_equals: null"), "m.yaml:5:17: events.Clean: `not_equals: null` compares with nothing: a message field is never null, so the comparison would hold for every message", "`every_message: true`"),
        ("events", "Clean", ("topic: /t", "type: my_msgs/Cmd", "equals: ~"), "m.yaml:5:13: events.Clean: `equals: null` compares with nothing", "every_message"),
        ("events", "Clean", ("topic: /t", "type: my_msgs/Cmd", "equals: [1, 2]"), "m.yaml:5:13: events.Clean: `equals` compares with one value (a boolean, a number or a text), not [1, 2]", "give one value"),
        ("events", "Clean", ("topic: /t", "type: my_msgs/Cmd", "above: ten"), "m.yaml:5:12: events.Clean: `above` compares numbers, not 'ten' (text)", "`above: 10`"),
        ("measures", "dark", (*STD["Float64"], "below: 1e-3"), "m.yaml:5:12: measures.dark: `below` compares numbers, not '1e-3' (text)", "YAML reads 1e-3 as text: write `below: 0.001`"),
        ("measures", "dark", ("topic: /t", "type: my_msgs/Cmd", "at_most: true"), "m.yaml:5:14: measures.dark: `at_most` compares numbers, not True (boolean)", "give a number"),
        # a std_msgs type: the value is of its data's kind
        ("events", "Clean", (*STD["Bool"], "equals: 1"), "m.yaml:5:13: events.Clean: std_msgs/Bool's data is a boolean, so `equals: 1` (number) never matches it", "`equals: true` or `equals: false`"),
        ("events", "Clean", (*STD["String"], "equals: yes"), "m.yaml:5:13: events.Clean: std_msgs/msg/String's data is a text, so `equals: True` (boolean) (YAML reads yes, no, on, off, true and false as booleans) never matches it", "quote the word"),
        ("events", "Clean", (*STD["String"], "not_equals: 10"), "m.yaml:5:17: events.Clean: std_msgs/msg/String's data is a text, so `not_equals: 10` (number) never matches it", "quote it: `not_equals: '10'`"),
        ("events", "Clean", (*STD["Float64"], "equals: open"), "m.yaml:5:13: events.Clean: std_msgs/Float64's data is a number, so `equals: 'open'` (text) never matches it", "give a number"),
        ("events", "Clean", (*STD["Int32"], "equals: false"), "m.yaml:5:13: events.Clean: std_msgs/Int32's data is a number, so `equals: False` (boolean)", "give a number"),
        ("events", "Clean", (*STD["Bool"], "above: 0.5"), "m.yaml:5:12: events.Clean: `above` compares numbers, but std_msgs/Bool's data is a boolean", "`equals: true`"),
        ("events", "Clean", (*STD["String"], "below: 3"), "m.yaml:5:12: events.Clean: `below` compares numbers, but std_msgs/msg/String's data is a text", "`json: true`"),
        # a std_msgs type has one field, data
        ("measures", "lux", (*STD["Float64"], "field: percentage"), "m.yaml:5:5: measures.lux: std_msgs/Float64 has one field, `data`, not 'percentage'", "leave out `field`"),
        ("measures", "lux", (*STD["Float64"], "json: true"), "m.yaml:5:5: measures.lux: `json: true` reads JSON text, but std_msgs/Float64's data is a number", "leave out `json`"),
        ("measures", "mood", (*STD["String"], "bands: [[1, low], [high]]"), "m.yaml:5:5: measures.mood: `bands` sort numbers, but std_msgs/msg/String's data is a text", "read a number type"),
        ("measures", "mood", (*STD["Float64"], "bands: [[1, 2], [high]]"), "m.yaml:5:17: measures.mood: band 1's literal must be a word of the scale, not 2", "[0.3, low]"),
        ("measures", "mood", (*STD["Float64"], "bands: [[1, low], [yes]]"), "m.yaml:5:24: measures.mood: band 2's literal must be a word of the scale, not True", "[0.3, low]"),
        # the measure's kind: a comparison makes a boolean; a value taken as it is must be the measure's kind
        ("measures", "mood", (*STD["String"], "equals: high"), "m.yaml:2:3: measures.mood: a comparison gives a boolean, but mood is scale", "`bands`"),
        ("measures", "dark", STD["Float64"], "m.yaml:2:3: measures.dark: std_msgs/Float64's data is a number, but dark is boolean: taken as it is, every message would be rejected", "`below: 0.2`"),
        ("measures", "lux", STD["Bool"], "m.yaml:2:3: measures.lux: std_msgs/Bool's data is a boolean, but lux is numeric", "read a number"),
        ("measures", "lux", STD["String"], "m.yaml:2:3: measures.lux: std_msgs/msg/String's data is a text, but lux is numeric", "`json: true`"),
        ("measures", "mood", STD["Float64"], "m.yaml:2:3: measures.mood: std_msgs/Float64's data is a number, but mood is scale", "give `bands`"),
        ("measures", "mood", STD["Bool"], "m.yaml:2:3: measures.mood: std_msgs/Bool's data is a boolean, but mood is scale", "as text"),
    ],
)  # fmt: skip
def test_a_comparison_or_value_of_the_wrong_type_is_refused_at_load_naming_the_fix(
    kind: str, name: str, lines: tuple[str, ...], message: str, hint: str
) -> None:
    e = mistake(block(kind, name, *lines))
    assert e.message.startswith(message), e.message
    assert hint in e.hint, e.hint


@pytest.mark.parametrize(
    ("kind", "name", "lines"),
    [
        ("events", "Clean", (*STD["Bool"], "equals: true")),
        ("events", "Clean", (*STD["String"], "equals: 'yes'")),
        ("events", "Clean", (*STD["String"], "not_equals: ''")),
        ("events", "Clean", (*STD["Int32"], "equals: 3")),
        ("events", "Clean", (*STD["Float64"], "at_least: 0")),
        ("events", "Clean", ("topic: /t", "type: std_msgs/String", "json: true", "field: a.b", "equals: true")),
        ("events", "Clean", ("topic: /t", "type: my_msgs/Cmd", "field: code", "equals: 3")),
        ("events", "Clean", ("topic: /t", "type: my_msgs/Cmd", "field: ok", "equals: false")),
        ("measures", "dark", (*STD["Float64"], "below: 10")),
        ("measures", "dark", STD["Bool"]),
        ("measures", "lux", STD["Int32"]),
        ("measures", "mood", STD["String"]),
        ("measures", "mood", (*STD["Float64"], "bands: [[1, low], [high]]")),
        ("measures", "lux", ("topic: /t", "type: sensor_msgs/msg/BatteryState", "field: percentage")),
    ],
)  # fmt: skip
def test_a_comparison_or_value_of_the_fields_type_is_taken(
    kind: str, name: str, lines: tuple[str, ...]
) -> None:
    assert len(Mapping.parse(block(kind, name, *lines), "m.yaml", MEASURES, EVENTS).entries) == 1


# the oracle: the runtime's own comparison (Entry.value, on an entry built without the load's
# checks) on the values the field can hold. A condition is worth loading when some message makes
# it true and some false, the runtime comparing without an error; and `above`, `below`, `at_least`,
# `at_most` order numbers (documented: no ordering of texts or booleans).
KINDS = {"std_msgs/Bool": "boolean", "std_msgs/String": "text", "std_msgs/Float64": "number", "std_msgs/Int64": "number"}  # fmt: skip
ORDERING = ("above", "below", "at_least", "at_most")


def _held(kind: str, target: object) -> list[object]:
    """Values a field of ``kind`` can hold, around ``target`` when it is of that kind."""
    if kind == "boolean":
        return [True, False]
    if kind == "text":
        return [target, f"{target}x", ""] if isinstance(target, str) else ["", "a"]
    number = isinstance(target, int | float) and not isinstance(target, bool)
    if not number:
        return [0.0, 1.0, -1.5]
    t = float(target)  # type: ignore[arg-type]
    return [target, math.nextafter(t, math.inf), math.nextafter(t, -math.inf)]


def _live(op: str, target: object, kind: str) -> bool:
    """Does ``op: target`` on a field of ``kind`` make a condition some message makes true, some false?"""
    if op in ORDERING and (isinstance(target, bool) or not isinstance(target, int | float)):
        return False
    e = Entry(name="E", kind="event", topic="/t", type="t", field=("data",), json=False,
              comparison=(op, target), bands=None)  # fmt: skip
    seen = set()
    for x in _held(kind, target):
        try:
            seen.add(e.value({"data": x}))
        except Exception:
            return False
    return seen == {True, False}


@given(
    op=st.sampled_from(sorted(COMPARISONS)),
    target=st.one_of(
        st.none(), st.booleans(), st.integers(-10**6, 10**6),
        st.floats(-1e300, 1e300), st.sampled_from([math.nan, math.inf, -math.inf]),
        st.text(alphabet="abc ", max_size=4), st.lists(st.integers(), max_size=2),
    ),
    type_name=st.sampled_from([*sorted(KINDS), "my_msgs/Reading"]),
)  # fmt: skip
@settings(max_examples=300, deadline=None)
def test_a_condition_loads_exactly_when_some_message_makes_it_true_and_some_false(
    op: str, target: object, type_name: str
) -> None:
    text = yaml.safe_dump({"events": {"E": {"topic": "/t", "type": type_name, op: target}}})
    try:
        Mapping.parse(text, "m.yaml")
        loaded = True
    except MappingError:
        loaded = False
    kinds = [KINDS[type_name]] if type_name in KINDS else sorted(set(KINDS.values()))  # unknown: any kind
    assert loaded == any(_live(op, target, kind) for kind in kinds), (text, loaded)
