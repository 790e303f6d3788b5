"""How rules are read (lang/reading.py): one value, checked when built, that *is* the audit
log's ``options`` record (issue 29, part 2)."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.errors import ConfigurationError
from cosleec.lang import (
    CANCEL,
    CONFLICT_AWARE,
    IMMEDIATE_S,
    PRIORITY_SEMANTICS,
    HedgeSemantics,
    PrioritySemantics,
    Reading,
    Unknowns,
    Untimed,
    one_of,
    parse_untimed,
)

NAMES = st.sampled_from(["R1", "R2", "Rule21", "Rule3", "a_b"])
SECONDS = st.one_of(st.integers(0, 10**6), st.floats(0, 1e12, allow_nan=False, allow_infinity=False))


def manager_record(
    semantics: str, unknown: str, untimed: str | float, declared: list[tuple[str, str]], how: str, lead: float
) -> dict[str, Any]:
    """The ``options`` record's data exactly as ``Manager.start`` wrote it before the Reading
    (tracker.untimed, Priorities.declared/semantics/lead), key order included."""
    return {
        "semantics": semantics,
        "unknown": unknown,
        "untimed": untimed,
        "priorities": sorted([h, lo] for h, lo in dict.fromkeys(declared)),
        "priority_semantics": how,
        "priority_lead": float(lead),
    }


@st.composite
def manager_records(draw: st.DrawFn) -> dict[str, Any]:
    untimed = draw(st.one_of(st.sampled_from(["none", "immediate"]), SECONDS.map(float)))
    return manager_record(
        draw(st.sampled_from([str(s) for s in HedgeSemantics])),
        draw(st.sampled_from([str(u) for u in Unknowns])),
        untimed,
        draw(st.lists(st.tuples(NAMES, NAMES).filter(lambda p: p[0] != p[1]), max_size=6)),
        draw(st.sampled_from(list(PRIORITY_SEMANTICS))),
        draw(SECONDS),
    )


@st.composite
def readings(draw: st.DrawFn) -> Reading:
    return Reading(
        semantics=draw(st.sampled_from(list(HedgeSemantics))),
        unknown=draw(st.one_of(st.none(), st.sampled_from(list(Unknowns)))),
        untimed=draw(st.one_of(st.sampled_from(list(Untimed)), SECONDS)),
        priorities=tuple(draw(st.lists(st.tuples(NAMES, NAMES), max_size=6))),
        priority_semantics=draw(st.sampled_from(list(PrioritySemantics))),
        priority_lead=draw(SECONDS),
    )


# ---------------------------------------------------------------- the record, both ways


@given(manager_records())
def test_a_managers_record_reads_back_to_the_same_bytes(record: dict[str, Any]) -> None:
    line = json.dumps(record, separators=(",", ":"))
    reading = Reading.from_json({"seq": 7, "kind": "options", "time": 0.0, **json.loads(line)})
    assert json.dumps(reading.to_json(), separators=(",", ":")) == line


@given(readings())
def test_a_reading_survives_its_record(reading: Reading) -> None:
    assert Reading.from_json(json.loads(json.dumps(reading.to_json()))) == reading


def test_the_record_of_the_defaults_is_the_managers_default_record() -> None:
    assert json.dumps(Reading().to_json()) == json.dumps(
        manager_record("last-wins", "undetermined", "none", [], "cancel", 0.0)
    )
    assert Reading().untimed_seconds is None


def test_unknown_not_said_is_none_and_stays_out_of_the_record() -> None:
    record = Reading(unknown=Unknowns.FALSE).to_json()
    del record["unknown"]
    reading = Reading.from_json(record)
    assert reading.unknown is None
    assert "unknown" not in reading.to_json()
    assert (
        list(Reading.from_json({**record, "unknown": "true"}).to_json())[1] == "unknown"
    )  # second, as written


def test_record_values_take_their_types() -> None:
    r = Reading.from_json(
        {
            "semantics": "nested",
            "untimed": 30,
            "priorities": [["R2", "R1"], ["R1", "R2"], ["R2", "R1"]],
            "priority_semantics": "conflict-aware",
            "priority_lead": 2,
        }
    )
    assert r.semantics is HedgeSemantics.NESTED and r.priority_semantics is PrioritySemantics.CONFLICT_AWARE
    assert r.untimed == 30.0 and isinstance(r.untimed, float)
    assert r.priority_lead == 2.0 and isinstance(r.priority_lead, float)
    assert r.priorities == (("R1", "R2"), ("R2", "R1"))  # sorted, each once


GOOD: dict[str, Any] = {
    "semantics": "last-wins",
    "unknown": "undetermined",
    "untimed": "none",
    "priorities": [],
    "priority_semantics": "cancel",
    "priority_lead": 0.0,
}


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("semantics", "nestd", "the options record's 'semantics' is last-wins or nested: not 'nestd'"),
        ("semantics", None, "the options record's 'semantics' is last-wins or nested: missing"),
        ("semantics", ["nested"], "the options record's 'semantics' is last-wins or nested: not ['nested']"),
        (
            "priorities",
            [["R1"]],
            """the options record's 'priorities' is a list of ["higher", "lower"] rule name pairs: not [['R1']]""",
        ),
        ("priorities", [["R1", ""]], "rule name pairs: not [['R1', '']]"),
        ("priorities", [("R1", "R2")], "rule name pairs: not [('R1', 'R2')]"),
        ("priorities", {"R1": "R2"}, "rule name pairs: not {'R1': 'R2'}"),
        (
            "priority_semantics",
            "cancl",
            "the options record's 'priority_semantics' is cancel or conflict-aware: not 'cancl'",
        ),
        ("priority_lead", -1, "the options record's 'priority_lead' is a number of seconds >= 0: not -1"),
        ("priority_lead", True, "'priority_lead' is a number of seconds >= 0: not True"),
        ("priority_lead", math.inf, "'priority_lead' is a number of seconds >= 0: not inf"),
        ("priority_lead", 10**400, "'priority_lead' is a number of seconds >= 0: not 1000"),
        ("priority_lead", "1", "'priority_lead' is a number of seconds >= 0: not '1'"),
        (
            "untimed",
            "later",
            """the options record's 'untimed' is "none", "immediate" or a number of seconds >= 0: not 'later'""",
        ),
        ("untimed", -0.5, "or a number of seconds >= 0: not -0.5"),
        ("untimed", math.nan, "or a number of seconds >= 0: not nan"),
        ("untimed", None, "or a number of seconds >= 0: missing"),
        ("unknown", "maybe", "the options record's 'unknown' is undetermined or false or true: not 'maybe'"),
        ("unknown", None, "the options record's 'unknown' is undetermined or false or true: not None"),
    ],
)
def test_a_bad_record_names_the_field(key: str, value: Any, message: str) -> None:
    record = dict(GOOD)
    if value is None and key != "unknown":
        del record[key]
    else:
        record[key] = value
    with pytest.raises(ValueError) as e:
        Reading.from_json(record)
    assert message in str(e.value)
    if key != "unknown":
        assert str(e.value).startswith(f"the options record's {key!r} is ")


def test_a_bad_record_names_the_first_bad_field_in_the_records_order() -> None:
    order = ["semantics", "priorities", "priority_semantics", "priority_lead", "untimed", "unknown"]
    record: dict[str, Any] = {key: object() for key in order}
    for key in order:
        with pytest.raises(ValueError, match=f"'{key}'"):
            Reading.from_json(record)
        record[key] = GOOD[key]
    Reading.from_json(record)


# ---------------------------------------------------------------- the options, as typed


def test_the_choices_are_taken_as_strings_and_become_members() -> None:
    r = Reading(
        semantics="nested",  # type: ignore[arg-type]
        unknown="false",  # type: ignore[arg-type]
        untimed="immediate",
        priority_semantics="conflict-aware",  # type: ignore[arg-type]
    )
    assert r.semantics is HedgeSemantics.NESTED
    assert r.unknown is Unknowns.FALSE
    assert r.untimed is Untimed.IMMEDIATE
    assert r.priority_semantics is PrioritySemantics.CONFLICT_AWARE
    assert r == Reading(
        semantics=HedgeSemantics.NESTED,
        unknown=Unknowns.FALSE,
        untimed=Untimed.IMMEDIATE,
        priority_semantics=PrioritySemantics.CONFLICT_AWARE,
    )


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"semantics": "nestd"}, "semantics must be one of 'last-wins', 'nested', not 'nestd'"),
        ({"semantics": "NESTED"}, "semantics must be one of 'last-wins', 'nested', not 'NESTED'"),
        ({"unknown": "maybe"}, "unknown must be one of 'undetermined', 'false', 'true', not 'maybe'"),
        ({"unknown": False}, "unknown must be one of 'undetermined', 'false', 'true', not False"),
        ({"priority_semantics": 1}, "priority_semantics must be one of 'cancel', 'conflict-aware', not 1"),
        (
            {"untimed": "later"},
            "untimed must be 'none', 'immediate' or a finite number of seconds >= 0, not 'later'",
        ),
        (
            {"untimed": None},
            "untimed must be 'none', 'immediate' or a finite number of seconds >= 0, not None",
        ),
        ({"untimed": -1}, "not -1"),
        ({"untimed": math.inf}, "not inf"),
        ({"untimed": True}, "not True"),
        ({"priority_lead": -0.5}, "priority_lead must be a number of seconds >= 0, not -0.5"),
        ({"priority_lead": math.nan}, "priority_lead must be a number of seconds >= 0, not nan"),
        ({"priority_lead": False}, "priority_lead must be a number of seconds >= 0, not False"),
        ({"priorities": [("R1",)]}, "priorities must be (higher, lower) pairs of rule names, not ('R1',)"),
        (
            {"priorities": [("R1", 2)]},
            "priorities must be (higher, lower) pairs of rule names, not ('R1', 2)",
        ),
        ({"priorities": [("", "R2")]}, "not ('', 'R2')"),
        ({"priorities": ["R1 > R2"]}, "not 'R1 > R2'"),
        ({"priorities": 5}, "priorities must be (higher, lower) pairs of rule names, not 5"),
    ],
)
def test_a_value_that_is_no_choice_is_refused_with_the_choices(options: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigurationError) as e:
        Reading(**options)
    assert message in str(e.value)


def test_priorities_are_a_set_of_pairs() -> None:
    a = Reading(priorities=(("R2", "R1"), ("R1", "R3"), ("R2", "R1")))
    b = Reading(priorities=[["R1", "R3"], ["R2", "R1"]])  # type: ignore[arg-type]
    assert a == b and a.priorities == (("R1", "R3"), ("R2", "R1"))
    assert Reading(priorities=frozenset({("R1", "R2")})).priorities == (("R1", "R2"),)  # type: ignore[arg-type]
    assert a.to_json()["priorities"] == [["R1", "R3"], ["R2", "R1"]]


@pytest.mark.parametrize(
    ("untimed", "seconds"),
    [(Untimed.NONE, None), ("none", None), (Untimed.IMMEDIATE, IMMEDIATE_S), (0, 0.0), (2.5, 2.5), (7, 7.0)],
)
def test_the_deadline_of_an_untimed_response(untimed: Any, seconds: float | None) -> None:
    assert Reading(untimed=untimed).untimed_seconds == seconds
    assert IMMEDIATE_S == 1.0  # the Manager's tolerance for "immediate"


def test_a_reading_is_frozen_and_keyword_only() -> None:
    r = Reading()
    with pytest.raises(AttributeError):
        r.semantics = HedgeSemantics.NESTED  # type: ignore[misc]
    with pytest.raises(TypeError):
        Reading(HedgeSemantics.NESTED)  # type: ignore[misc]


# ---------------------------------------------------------------- the enums and parsers


def test_priority_semantics_is_an_enum_whose_members_are_the_old_constants() -> None:
    assert CANCEL is PrioritySemantics.CANCEL and CONFLICT_AWARE is PrioritySemantics.CONFLICT_AWARE
    assert CANCEL == "cancel" and CONFLICT_AWARE == "conflict-aware"
    assert {"conflict-aware": 1}[CONFLICT_AWARE] == 1 and f"{CONFLICT_AWARE}" == "conflict-aware"
    assert json.dumps([CANCEL]) == '["cancel"]'
    assert PRIORITY_SEMANTICS == ("cancel", "conflict-aware")
    assert all(type(s) is str for s in PRIORITY_SEMANTICS)  # messages show them unquoted, as before
    assert PrioritySemantics("conflict-aware") is CONFLICT_AWARE


@pytest.mark.parametrize("kind", [HedgeSemantics, Unknowns, Untimed, PrioritySemantics])
def test_one_of_takes_members_and_their_strings_and_lists_the_choices_otherwise(kind: Any) -> None:
    for member in kind:
        assert one_of(kind, member, "x") is member
        assert one_of(kind, str(member), "x") is member
    choices = ", ".join(repr(str(k)) for k in kind)
    for wrong in ("", "bogus", str(next(iter(kind))).upper(), None, 3):
        with pytest.raises(ConfigurationError) as e:
            one_of(kind, wrong, "the_option")
        assert str(e.value) == f"the_option must be one of {choices}, not {wrong!r}"


@pytest.mark.parametrize(
    ("text", "value"),
    [("none", Untimed.NONE), ("immediate", Untimed.IMMEDIATE), ("0", 0.0), ("2.5", 2.5), ("1e3", 1000.0)],
)
def test_parse_untimed_reads_the_command_line_form(text: str, value: Any) -> None:
    got = parse_untimed(text)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("soon", "'soon' is not none, immediate or a number of seconds"),
        ("None", "'None' is not none, immediate or a number of seconds"),
        ("", "'' is not none, immediate or a number of seconds"),
        ("-1", "'-1' is not a finite, non-negative number of seconds"),
        ("inf", "'inf' is not a finite, non-negative number of seconds"),
        ("nan", "'nan' is not a finite, non-negative number of seconds"),
    ],
)
def test_parse_untimed_refuses_the_rest(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError) as e:
        parse_untimed(text)
    assert str(e.value) == message
