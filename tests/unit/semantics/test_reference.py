"""The reference semantics on its own, at the edges the language reference fixes.

The differential test holds the runtime to the reference; these hold the reference to
``sleec-language.md`` (§6.1-6.7, §10), so that the two cannot drift away from the language
together. Each case is written out by hand: an occurrence exactly at a deadline, exactly
at an interval start, one instant before, a snapshot read at the right moment.
"""

from __future__ import annotations

from typing import Any

import pytest

from cosleec.lang import HedgeSemantics, Reading, parse
from cosleec.semantics import Step, judge
from tests.unit.semantics.differential import HEADER

V0: dict[str, Any] = {"b": False, "n": 2, "s": "low"}


def verdicts(rules: str, *trace: Step, **options: Any) -> list[tuple[str, float, str, float | None]]:
    """(item key, start, status, at) of every verdict, for ``trace`` after all measures are set at 0."""
    spec = parse(HEADER + "rule_start\n" + rules + "\nrule_end\n")
    j = judge(spec, [Step(0, values=V0), *trace], Reading(**options))
    return [(v.key, v.start, v.status, v.at) for v in sorted(j.verdicts, key=lambda v: v.id)]


def ev(t: float, name: str) -> Step:
    return Step(t, event=name)


def at(t: float, **values: Any) -> Step:
    return Step(t, values=values)


# ---------------------------------------------------------------- §6.4, §10: windows closed at both ends
@pytest.mark.parametrize(
    ("when", "status", "time"),
    [(0, "pending", None), (0.5, "fulfilled", 0.5), (3, "fulfilled", 3), (3.001, "violated", 3)],
)
def test_within_is_closed_at_both_ends(when: float, status: str, time: float | None) -> None:
    """[t, t+T] (case 0: an A handled just *before* the trigger at the same instant does not
    count, §6.1 causal order)."""
    rule = "R1 when T0 then A within 3 seconds"
    trace = [ev(0, "A"), ev(0, "T0")] if when == 0 else [ev(0, "T0"), ev(when, "A")]
    assert verdicts(rule, *trace) == [("R1:0", 0, status, time)]


def test_an_occurrence_after_its_trigger_at_the_same_instant_counts() -> None:
    assert verdicts("R1 when T0 then A within 3 seconds", ev(0, "T0"), ev(0, "A")) == [
        ("R1:0", 0, "fulfilled", 0)
    ]


def test_a_trigger_never_fulfils_its_own_response() -> None:
    assert verdicts("R1 when A then A within 3 seconds", ev(0, "A"), Step(4)) == [("R1:0", 0, "violated", 3)]


@pytest.mark.parametrize(
    ("when", "status", "time"),
    [
        (1, "respected", 5),
        (1.999, "respected", 5),
        (2, "violated", 2),
        (5, "violated", 5),
        (5.001, "respected", 5),
    ],
)
def test_a_prohibition_interval_is_closed_at_both_ends(when: float, status: str, time: float) -> None:
    rule = "R1 when T0 then not A within [2 seconds, 5 seconds]"
    assert verdicts(rule, ev(0, "T0"), ev(when, "A"), Step(9)) == [("R1:0", 0, status, time)]


@pytest.mark.parametrize(
    ("when", "status", "time"),
    [
        (1, "violated", 5),
        (1.999, "violated", 5),
        (2, "fulfilled", 2),
        (5, "fulfilled", 5),
        (5.001, "violated", 5),
    ],
)
def test_an_obligation_interval_ignores_earlier_occurrences(when: float, status: str, time: float) -> None:
    rule = "R1 when T0 then A within [2 seconds, 5 seconds]"
    assert verdicts(rule, ev(0, "T0"), ev(when, "A"), Step(9)) == [("R1:0", 0, status, time)]


def test_a_window_is_judged_only_once_time_has_passed_its_end() -> None:
    """At t+T itself the obligation can still be met: pending, not violated."""
    assert verdicts("R1 when T0 then A within 3 seconds", ev(0, "T0"), Step(3)) == [
        ("R1:0", 0, "pending", None)
    ]
    assert verdicts("R1 when T0 then not A within 3 seconds", ev(0, "T0"), Step(3)) == [
        ("R1:0", 0, "pending", None)
    ]


def test_untimed_responses() -> None:
    """§6.4, §10: untimed `E` has no deadline; untimed `not E` covers the trigger instant."""
    assert verdicts("R1 when T0 then A", ev(0, "T0"), Step(1000)) == [("R1:0", 0, "pending", None)]
    assert verdicts("R1 when T0 then A", ev(0, "T0"), Step(1000), untimed=5.0) == [("R1:0", 0, "violated", 5)]
    assert verdicts("R1 when T0 then not A", ev(2, "T0"), ev(2, "A")) == [("R1:0", 2, "violated", 2)]
    assert verdicts("R1 when T0 then not A", ev(2, "T0"), ev(2.5, "A")) == [("R1:0", 2, "respected", 2)]


def test_eventually() -> None:
    assert verdicts("R1 when T0 then A eventually", ev(0, "T0"), ev(10**6, "A")) == [
        ("R1:0", 0, "fulfilled", 10**6)
    ]
    assert verdicts("R1 when T0 then not A eventually", ev(0, "T0"), Step(10**6)) == [
        ("R1:0", 0, "pending", None)
    ]


# ---------------------------------------------------------------- §6.4 notes: deadlines from measures
def test_deadlines_are_computed_once_on_the_trigger_snapshot() -> None:
    rule = "R1 when T0 then A within ({n} * 2) seconds"
    assert verdicts(rule, at(0, n=2), ev(0, "T0"), at(1, n=0), ev(4, "A")) == [("R1:0", 0, "fulfilled", 4)]
    rule = "R1 when T0 then A within [({n} * 1) seconds, 6 seconds]"
    assert verdicts(rule, at(0, n=3), ev(0, "T0"), ev(2, "A"), Step(9)) == [("R1:0", 0, "violated", 6)]


def test_a_value_set_before_the_trigger_at_the_same_instant_is_read() -> None:
    rule = "R1 when T0 then A within ({n} * 2) seconds"
    assert verdicts(rule, at(4, n=1), ev(4, "T0"), Step(9)) == [("R1:0", 4, "violated", 6)]


def test_a_negative_deadline_has_closed_before_it_opened() -> None:
    rule = "R1 when T0 then A within (3 - {n}) seconds otherwise B within 2 seconds"
    assert verdicts(rule, at(0, n=4), ev(5, "T0"), Step(9)) == [
        ("R1:0", 5, "violated", 5),
        ("R1:0/o:0", 5, "violated", 7),
    ]
    rule = "R1 when T0 then not A within (3 - {n}) seconds otherwise B within 2 seconds"
    assert verdicts(rule, at(0, n=4), ev(5, "T0"), ev(5, "A"), Step(9)) == [("R1:0", 5, "respected", 5)]


def test_a_zero_length_interval_has_one_instant() -> None:
    rule = "R1 when T0 then A within [2 seconds, ({n} * 1) seconds]"
    assert verdicts(rule, ev(0, "T0"), ev(2, "A")) == [("R1:0", 0, "fulfilled", 2)]


# ---------------------------------------------------------------- §6.5 `otherwise`
def test_otherwise_starts_at_the_deadline_only_on_a_miss() -> None:
    rule = "R1 when T0 then A within 2 seconds otherwise B within 3 seconds"
    assert verdicts(rule, ev(0, "T0"), ev(2, "A"), Step(9)) == [("R1:0", 0, "fulfilled", 2)]
    assert verdicts(rule, ev(0, "T0"), ev(3, "A"), ev(5, "B")) == [
        ("R1:0", 0, "violated", 2),
        ("R1:0/o:0", 2, "fulfilled", 5),  # the late A does not cancel the fallback
    ]


def test_otherwise_of_a_prohibition_starts_at_the_violation_and_never_on_respect() -> None:
    rule = "R1 when T0 then not A within 3 seconds otherwise B within 2 seconds"
    assert verdicts(rule, ev(0, "T0"), Step(9)) == [("R1:0", 0, "respected", 3)]
    assert verdicts(rule, ev(0, "T0"), ev(3, "A"), Step(9)) == [
        ("R1:0", 0, "violated", 3),
        ("R1:0/o:0", 3, "violated", 5),
    ]


def test_an_early_fallback_event_is_neither_required_nor_a_violation() -> None:
    rule = "R1 when T0 then A within 2 seconds otherwise B within 3 seconds"
    assert verdicts(rule, ev(0, "T0"), ev(1, "B"), Step(9)) == [
        ("R1:0", 0, "violated", 2),
        ("R1:0/o:0", 2, "violated", 5),
    ]


def test_otherwise_after_an_untimed_occurrence_reads_it_as_within_0_seconds() -> None:
    rule = "R1 when T0 then A otherwise B within 3 seconds"
    assert verdicts(rule, ev(0, "T0"), ev(0, "A"), Step(9)) == [("R1:0", 0, "fulfilled", 0)]
    assert verdicts(rule, ev(0, "T0"), ev(1, "A"), Step(9)) == [
        ("R1:0", 0, "violated", 0),
        ("R1:0/o:0", 0, "violated", 3),
    ]


# ---------------------------------------------------------------- §6.6 `else`, §6.7 nesting
def test_else_is_judged_when_the_last_window_closes() -> None:
    rule = "R1 when T0 then A within 2 seconds else B within [3 seconds, 5 seconds]"
    assert verdicts(rule, ev(0, "T0"), ev(5, "B")) == [("R1:0", 0, "fulfilled", 5)]
    assert verdicts(rule, ev(0, "T0"), ev(2.5, "B"), Step(9)) == [("R1:0", 0, "violated", 5)]


def test_defeaters_of_a_braced_otherwise_are_sampled_when_it_starts() -> None:
    """§6.7: SLEEC-TK's Rule4 reads assentToSupportCalls 2 minutes after the trigger."""
    rule = "R1 when T0 then A within 2 seconds otherwise {B within 3 seconds unless {b} then not B within 3 seconds}"
    assert verdicts(rule, at(0, b=False), ev(0, "T0"), at(2, b=True), Step(9)) == [
        ("R1:0", 0, "violated", 2),
        ("R1:0/o~1:0", 2, "respected", 5),
    ]
    assert verdicts(rule, at(0, b=True), ev(0, "T0"), at(3, b=False), Step(9)) == [
        ("R1:0", 0, "violated", 2),
        ("R1:0/o~1:0", 2, "respected", 5),  # a value set after the start is not read
    ]


@pytest.mark.parametrize(
    ("semantics", "key"), [(HedgeSemantics.LAST_WINS, "R1.1~2:0"), (HedgeSemantics.NESTED, "R1.1:0")]
)
def test_inner_defeaters_combine_as_the_outer_ones(semantics: HedgeSemantics, key: str) -> None:
    """§7: last-wins takes the last clause that holds; nested the longest prefix that holds."""
    rule = (
        "R1 when T0 then A within 2 seconds unless {b} then "
        "{B within 3 seconds unless ({n} > 5) then A within 1 seconds unless ({n} > 1) then not B within 3 seconds}"
    )
    [(k, *_)] = verdicts(rule, at(0, b=True, n=2), ev(0, "T0"), Step(9), semantics=semantics)
    assert k == key
