"""The Manager's options, checked once (runtime/options.py; issue 29, part 2).

Every message is the one ``Manager(...)`` has always raised, written out here as it was
(so a change of wording fails, whoever makes it); the Manager itself is asked too, so the
two cannot part.
"""

from __future__ import annotations

import itertools
import json
import math
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.lang import HedgeSemantics, PrioritySemantics, Reading, Unknowns, Untimed, parse
from cosleec.runtime import MAX_WINDOW_S, ConfigurationError, Manager, VirtualClock, read_audit
from cosleec.runtime.options import Options, UnknownEvents, given_priorities
from cosleec.runtime.runner import deepest

TEXT = (
    "def_start event E event F event G measure a : boolean def_end "
    "rule_start R1 when E then F within 5 seconds R2 when E then not F within 3 seconds rule_end"
)
PRIORITY_BLOCK = TEXT + " priority_start R2 > R1 priority_end"

STACK_HINT = (
    "each level of implementations that trigger rules takes about 16 of "
    f"Python's {sys.getrecursionlimit()} stack frames (sys.getrecursionlimit()); 16 is the default"
)

# each option, a value it refuses, and the Manager's message for it -- in the order it checks them
REFUSED: list[tuple[str, Any, str]] = [
    ("semantics", "nestd", "semantics must be one of 'last-wins', 'nested', not 'nestd'"),
    ("unknown", "maybe", "unknown must be one of 'undetermined', 'false', 'true', not 'maybe'"),
    ("unknown_events", "allow", "unknown_events must be one of 'raise', 'refuse', not 'allow'"),
    (
        "untimed",
        "bogus",
        f"untimed must be 'none', 'immediate' or a number of seconds from 0 to {MAX_WINDOW_S:g}, not 'bogus'",
    ),
    ("history", 0, "history must be a whole number of at least 1, not 0"),
    ("max_depth", 0, f"max_depth must be a whole number from 1 to {deepest()}, not 0"),
    ("priorities", 5, "priorities must be a list of 'H > L' strings or (H, L) pairs, not 5"),
    ("priority_semantics", "cancl", "priority_semantics must be one of cancel, conflict-aware, not 'cancl'"),
    ("priority_lead", -1, "priority_lead must be a number of seconds >= 0, not -1"),
    ("reset_journal", True, "reset_journal must be True or False, and True only with a journal, not True"),
]

MORE_REFUSED: list[tuple[str, Any, str]] = [
    ("semantics", 3, "semantics must be one of 'last-wins', 'nested', not 3"),  # None: the file's
    ("unknown_events", "RAISE", "unknown_events must be one of 'raise', 'refuse', not 'RAISE'"),
    ("untimed", math.nan, "not nan"),
    ("untimed", -1, "not -1"),
    ("untimed", MAX_WINDOW_S * 2, "from 0 to"),
    ("untimed", True, "not True"),
    ("history", True, "history must be a whole number of at least 1, not True"),
    ("history", 1.5, "not 1.5"),
    ("max_depth", deepest() + 1, f"from 1 to {deepest()}, not {deepest() + 1}"),
    ("max_depth", True, "not True"),
    ("max_age", 10.0, "max_age maps each measure to the seconds its value stays fresh, not 10.0"),
    ("priority_semantics", None, "priority_semantics must be one of cancel, conflict-aware, not None"),
    ("priority_lead", math.inf, "priority_lead must be a number of seconds >= 0, not inf"),
    ("priority_lead", math.nan, "not nan"),
    ("priority_lead", False, "not False"),
    ("reset_journal", "yes", "reset_journal must be True or False, and True only with a journal, not 'yes'"),
]


@pytest.mark.parametrize(("name", "value", "message"), REFUSED + MORE_REFUSED)
def test_each_option_is_refused_as_the_manager_refuses_it(name: str, value: Any, message: str) -> None:
    with pytest.raises(ConfigurationError) as built:
        Options.build(**{name: value})
    assert message in str(built.value)
    if name in (
        "semantics",
        "unknown",
        "unknown_events",
        "priorities",
        "priority_semantics",
        "reset_journal",
    ):
        assert str(built.value) == message
    with pytest.raises(ConfigurationError) as managed:
        Manager.from_text(TEXT, clock=VirtualClock(), **{name: value})
    assert (str(managed.value), managed.value.hint) == (str(built.value), built.value.hint)


def test_a_max_depth_too_deep_says_why_in_the_hint() -> None:
    with pytest.raises(ConfigurationError) as e:
        Options.build(max_depth=10**9)
    assert e.value.hint == STACK_HINT
    assert Options.build(max_depth=deepest()).max_depth == deepest()  # the deepest one is taken


def test_the_first_wrong_option_in_the_managers_order_is_the_one_named() -> None:
    wrong = {name: value for name, value, _ in REFUSED}
    for name, _, message in REFUSED:
        with pytest.raises(ConfigurationError) as e:
            Options.build(**wrong)
        assert e.value.message == message, name
        del wrong[name]
    Options.build(**wrong)


def test_reset_journal_is_taken_with_a_journal(tmp_path: Path) -> None:
    assert Options.build(reset_journal=True, journal=tmp_path / "j.db").reset_journal is True
    with pytest.raises(ConfigurationError, match="True only with a journal"):
        Options.build(reset_journal=True, journal="")  # no file named: no journal


def test_a_keyword_that_is_no_option_is_a_type_error_as_for_the_constructor() -> None:
    with pytest.raises(TypeError) as e:
        Options.build(semantic="nested", also=1)
    assert str(e.value) == "Manager.__init__() got an unexpected keyword argument 'semantic'"
    with pytest.raises(TypeError, match="'web'"):
        Options().replace(web=8765)


def test_the_defaults_are_the_managers() -> None:
    o = Options.build()
    assert o == Options()
    assert (o.semantics, o.unknown, o.unknown_events, o.untimed) == (
        None,  # the rule file's semantics block, else last-wins
        Unknowns.UNDETERMINED,
        UnknownEvents.RAISE,
        Untimed.NONE,
    )
    assert (o.priorities, o.priority_semantics, o.priority_lead) == ((), PrioritySemantics.CANCEL, 0.0)
    assert (o.history, o.max_depth, o.dispatch, o.reset_journal) == (10_000, 16, True, False)
    assert (o.clock, o.audit, o.journal, o.max_age) == (None, None, None, None)


def test_the_choices_are_taken_as_strings_and_kept_as_enums() -> None:
    o = Options.build(
        semantics="nested",
        unknown="false",
        unknown_events="refuse",
        untimed="immediate",
        priority_semantics="conflict-aware",
        priority_lead=2,
    )
    assert o.semantics is HedgeSemantics.NESTED and o.unknown is Unknowns.FALSE
    assert o.unknown_events is UnknownEvents.REFUSE and o.untimed is Untimed.IMMEDIATE
    assert o.priority_semantics is PrioritySemantics.CONFLICT_AWARE
    assert o.priority_lead == 2.0 and isinstance(o.priority_lead, float)
    assert Options.build(untimed=7).untimed == 7.0 and isinstance(Options.build(untimed=7).untimed, float)
    assert Options.build(untimed=0).untimed == 0.0
    assert Options.build(untimed=MAX_WINDOW_S).untimed == MAX_WINDOW_S


def test_what_is_kept_as_given() -> None:
    clock, ages = VirtualClock(), {"a": 5.0}
    o = Options.build(clock=clock, max_age=ages, dispatch=False, audit="a.jsonl", journal=Path("j.db"))
    assert o.clock is clock and o.max_age is ages and o.dispatch is False
    assert o.audit == "a.jsonl" and o.journal == Path("j.db")


@pytest.mark.parametrize(
    ("priorities", "kept"),
    [
        (None, []),
        ((), []),
        ("R1 > R2", ["R1 > R2"]),
        (["R1 > R2", ("R2", "R3")], ["R1 > R2", ("R2", "R3")]),
        ((p for p in ["A > B"]), ["A > B"]),
    ],
)
def test_priorities_are_kept_as_given(priorities: Any, kept: list[Any]) -> None:
    if isinstance(priorities, Iterator):  # read once: each reader gets its own
        priorities, again = itertools.tee(priorities)
    else:
        again = priorities
    assert given_priorities(priorities) == kept
    assert Options.build(priorities=again).priorities == tuple(kept)


def test_options_are_checked_however_they_are_made() -> None:
    with pytest.raises(ConfigurationError, match="history"):
        Options(history=0)
    o = Options.build(semantics="nested")
    assert o.replace() is o
    assert o.replace(untimed=3).untimed == 3.0 and o.replace(untimed=3).semantics is HedgeSemantics.NESTED
    with pytest.raises(ConfigurationError, match="untimed"):
        o.replace(untimed="later")


def test_all_priorities_put_the_rule_files_first() -> None:
    o = Options.build(priorities=["R1 > R2", ("R1", "R3")])
    assert o.all_priorities(parse(PRIORITY_BLOCK)) == [("R2", "R1"), "R1 > R2", ("R1", "R3")]


# ---------------------------------------------------------------- the options record


def test_the_reading_is_the_managers_options_record(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    given = {
        "semantics": "nested",
        "unknown": "false",
        "untimed": 5,
        "priorities": ["R1 > R2"],
        "priority_semantics": "conflict-aware",
        "priority_lead": 2.5,
    }
    text = TEXT.replace("rule_end", "R3 when G then F rule_end") + " priority_start R3 > R2 priority_end"
    m = Manager.from_text(text, clock=VirtualClock(), audit=log, dispatch=False, **given)
    m.start()
    m.close()
    (record,) = [r for r in read_audit(log) if r["kind"] == "options"]
    expected = Options.build(**given).reading([("R3", "R2"), ("R1", "R2")]).to_json()
    assert [k for k in record if k in expected] == list(expected)  # the same keys, in the same order
    assert json.dumps({k: record[k] for k in expected}) == json.dumps(expected)
    assert Reading.from_json(record) == Options.build(**given).reading([("R1", "R2"), ("R3", "R2")])


OPTIONS = st.fixed_dictionaries(
    {},
    optional={
        "semantics": st.sampled_from([*HedgeSemantics, *(str(s) for s in HedgeSemantics)]),
        "unknown": st.sampled_from([*Unknowns, *(str(u) for u in Unknowns)]),
        "unknown_events": st.sampled_from(["raise", "refuse"]),
        "untimed": st.one_of(
            st.sampled_from(["none", "immediate"]), st.floats(0, MAX_WINDOW_S), st.integers(0, 100)
        ),
        "history": st.integers(1, 10**6),
        "max_depth": st.integers(1, deepest()),
        "priority_semantics": st.sampled_from(["cancel", "conflict-aware"]),
        "priority_lead": st.one_of(st.integers(0, 100), st.floats(0, 1e9)),
    },
)


@given(OPTIONS, st.lists(st.tuples(st.sampled_from("ABC"), st.sampled_from("DEF")), max_size=4))
def test_any_options_read_back_from_their_record(
    options: dict[str, Any], declared: list[tuple[str, str]]
) -> None:
    o = Options.build(**options)
    assert (
        Options(**{name: getattr(o, name) for name in Options.__dataclass_fields__}) == o
    )  # checked again: the same
    reading = o.reading(declared)
    assert Reading.from_json(json.loads(json.dumps(reading.to_json()))) == reading
    assert (reading.semantics, reading.untimed, reading.priority_lead) == (
        o.semantics or HedgeSemantics.LAST_WINS,  # not given: a file without a block reads last-wins
        o.untimed,
        o.priority_lead,
    )
    assert reading.priorities == tuple(sorted(set(declared)))
