"""Windows at their edges: the runtime and the reference semantics on hand-picked traces.

Each case puts an occurrence exactly at a deadline, exactly at an interval start, or one
instant before, and asserts two things: the Manager on a VirtualClock reaches exactly the
reference verdicts (:func:`both`), and those verdicts are the ones the language reference
(``sleec-language.md`` §6.4-6.7, §10, §13) prescribes. They are the tests that kill the
mutants of ``scripts/mutants``; each names the mutants it is there for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pytest

from cosleec.lang import HedgeSemantics
from cosleec.runtime import Manager, VirtualClock
from cosleec.semantics import Step
from tests.unit.semantics.differential import HEADER, Case, reference, runtime

V0: dict[str, Any] = {"b": False, "n": 2, "s": "low"}  # every measure known from 0

Item = tuple[str, float, str, float | None]  # (item key, start, status, at)


@dataclass
class Seen:
    """What both semantics agreed on: every item's verdict and every conflict."""

    items: list[Item]
    conflicts: list[
        tuple[float, tuple[str, str], str]
    ]  # (time, (obligation's rule, prohibition's rule), resolution)

    def of(self, key: str) -> list[tuple[float, str, float | None]]:
        """(start, status, at) of every item with this key, in creation order."""
        return [(start, status, at) for k, start, status, at in self.items if k == key]


def spec_text(rules: str) -> str:
    return HEADER + "rule_start\n" + rules + "\nrule_end\n"


def both(rules: str, trace: list[Step], **opts: Any) -> Seen:
    """Run ``trace`` through the reference and the runtime; they must agree on everything."""
    case = Case(
        spec_text(rules),
        [Step(0, values=V0), *trace],
        opts.get("semantics", HedgeSemantics.LAST_WINS),
        tuple(opts.get("priorities", ())),
        opts.get("priority_semantics", "cancel"),
        opts.get("lead", 0.0),
    )
    trace = case.trace
    want = reference(case)
    got = runtime(case)
    assert got == want, f"runtime and reference disagree on\n{rules}\n{trace}"
    rule = {id_: rule for id_, rule, *_ in want["verdicts"]}
    return Seen(
        [(key, start, status, at) for _, _, key, start, _, status, at in want["verdicts"]],
        [(t, (rule[o], rule[p]), res) for t, o, p, res in want["conflicts"]],
    )


def ev(t: float, name: str) -> Step:
    return Step(t, event=name)


def tick(t: float) -> Step:
    return Step(t)


def at(t: float, **values: Any) -> Step:
    return Step(t, values=values)


def manager(rules: str, values: dict[str, Any] = V0, **kw: Any) -> tuple[Manager, VirtualClock, list[Any]]:
    """A Manager on a VirtualClock at 0 with ``values`` (every measure by default), and the
    records it emits."""
    clock = VirtualClock(0)
    m = Manager.from_text(spec_text(rules), clock=clock, dispatch=False, **kw)
    records: list[Any] = []
    m.subscribe(records.append)
    m.update(values)
    return m, clock, records


# ---------------------------------------------------------------- prohibitions: `not E within T`
NOT3 = "R1 when T0 then not A within 3 seconds"


def test_a_prohibition_is_violated_by_an_occurrence_exactly_at_its_deadline() -> None:
    """[t, t+T] is closed at both ends (§10). Mutant: prohibition-closes-early-occur."""
    assert both(NOT3, [ev(0, "T0"), ev(3, "A"), tick(9)]).of("R1:0") == [(0, "violated", 3)]
    assert both(NOT3, [ev(0, "T0"), ev(2, "A")]).of("R1:0") == [(0, "violated", 2)]


def test_a_prohibition_is_respected_once_time_passes_its_deadline() -> None:
    assert both(NOT3, [ev(0, "T0"), ev(3.5, "A"), tick(9)]).of("R1:0") == [(0, "respected", 3)]
    assert both(NOT3, [ev(0, "T0"), ev(4, "A")]).of("R1:0") == [(0, "respected", 3)]


def test_a_prohibition_refuses_requests_up_to_its_deadline_included() -> None:
    """Mutant: prohibition-closes-early-forbidding."""
    m, clock, _ = manager(NOT3)
    m.event("T0")
    answers = []
    for t in (0, 1, 2.99, 3, 3.01, 4):
        clock.set(t)
        answers.append(m.request("A").permitted)
    assert answers == [False, False, False, False, True, True]


def test_a_prohibition_that_has_ended_forbids_nothing_more() -> None:
    """Violated once (its verdict is final) or cancelled by a priority, a prohibition no
    longer refuses its event. Mutant: closed-prohibition-still-forbids."""
    m, clock, _ = manager(NOT3)
    m.event("T0")
    clock.set(1)
    m.event("A")  # happened anyway: violated
    assert m.request("A").permitted is True
    rules = "R1 when T1 then B within 5 seconds\nR2 when T0 then not A within 10 seconds"
    m, clock, _ = manager(rules, priorities=["R1 > R2"])
    m.event("T0")
    assert m.request("A").permitted is False
    clock.set(1)
    m.event("T1")  # R2 is cancelled (cancellation-based priority)
    assert m.request("A").permitted is True


INTERVAL_NOT = "R1 when T0 then not A within [2 seconds, 5 seconds]"


def test_a_prohibition_interval_refuses_requests_only_inside_it() -> None:
    """Mutants: prohibition-ignores-start-forbidding, prohibition-start-operands-swapped."""
    m, clock, _ = manager(INTERVAL_NOT)
    clock.set(10)
    m.event("T0")  # the window is [12, 15]
    answers = []
    for t in (10, 11, 11.99, 12, 13, 15, 15.01):
        clock.set(t)
        answers.append(m.request("A").permitted)
    assert answers == [True, True, True, False, False, False, True]


@pytest.mark.parametrize("early", [1, 1.5, 1.99])
def test_an_occurrence_before_a_prohibition_interval_opens_neither_violates_nor_respects(
    early: float,
) -> None:
    """§6.4: `not E within [a, b]` forbids E in [t+a, t+b] only.
    Mutants: prohibition-ignores-start-occur, prohibition-violated-before-start."""
    seen = both(INTERVAL_NOT, [ev(0, "T0"), ev(early, "A"), tick(9)])
    assert seen.of("R1:0") == [(0, "respected", 5)]


def test_an_occurrence_exactly_at_a_prohibition_interval_start_violates_it() -> None:
    assert both(INTERVAL_NOT, [ev(0, "T0"), ev(1, "A"), ev(2, "A"), tick(9)]).of("R1:0") == [
        (0, "violated", 2)
    ]
    assert both(INTERVAL_NOT, [ev(0, "T0"), ev(5, "A")]).of("R1:0") == [(0, "violated", 5)]


def test_untimed_not_forbids_the_trigger_instant_only() -> None:
    """§6.4: untimed `not E` holds at the trigger instant. Mutant: untimed-not-lasts-a-second."""
    rule = "R1 when T0 then not A"
    assert both(rule, [ev(4, "T0"), ev(4, "A"), tick(9)]).of("R1:0") == [(4, "violated", 4)]
    assert both(rule, [ev(4, "T0"), ev(4.5, "A"), tick(9)]).of("R1:0") == [(4, "respected", 4)]
    m, clock, _ = manager(rule)
    m.event("T0")
    assert m.request("A").permitted is False
    clock.set(0.5)
    assert m.request("A").permitted is True


# ---------------------------------------------------------------- prohibitions and `otherwise`
NOT_OTHERWISE = "R1 when T0 then not A within 3 seconds otherwise B within 2 seconds"


def test_a_respected_prohibition_starts_no_otherwise() -> None:
    """§6.5: the fallback of a prohibition starts at the first forbidden occurrence, never
    when the window closes respected. Mutant: otherwise-after-respected-prohibition."""
    seen = both(NOT_OTHERWISE, [ev(0, "T0"), tick(10)])
    assert seen.items == [("R1:0", 0, "respected", 3)]
    seen = both(NOT_OTHERWISE, [ev(0, "T0"), ev(3, "B"), tick(10)])
    assert seen.items == [("R1:0", 0, "respected", 3)]


def test_a_violated_prohibition_starts_its_otherwise_at_the_violation() -> None:
    seen = both(NOT_OTHERWISE, [ev(0, "T0"), ev(3, "A"), ev(5, "B"), tick(10)])
    assert seen.items == [("R1:0", 0, "violated", 3), ("R1:0/o:0", 3, "fulfilled", 5)]


def test_a_prohibition_whose_window_closes_before_it_opens_starts_no_otherwise() -> None:
    """A negative deadline from measures: respected at once (§6.4 notes), no fallback.
    Mutant: otherwise-after-respected-at-start."""
    rule = "R1 when T0 then not A within (3 - {n}) seconds otherwise B within 2 seconds"
    seen = both(rule, [at(0, n=4), ev(1, "T0"), ev(1, "A"), tick(10)])
    assert seen.items == [("R1:0", 1, "respected", 1)]


# ---------------------------------------------------------------- obligations: `E within T`, intervals
def test_an_obligation_is_fulfilled_by_an_occurrence_exactly_at_its_deadline() -> None:
    """Mutants: obligation-closes-early, due-at-deadline."""
    rule = "R1 when T0 then A within 3 seconds"
    assert both(rule, [ev(0, "T0"), ev(3, "A"), tick(9)]).of("R1:0") == [(0, "fulfilled", 3)]
    assert both(rule, [ev(0, "T0"), tick(3), ev(3, "A")]).of("R1:0") == [(0, "fulfilled", 3)]
    assert both(rule, [ev(0, "T0"), ev(3.5, "A")]).of("R1:0") == [(0, "violated", 3)]


INTERVAL = "R1 when T0 then A within [2 seconds, 5 seconds]"


def test_an_occurrence_before_an_interval_opens_does_not_fulfil_it() -> None:
    """§6.4: an earlier E neither satisfies nor violates. Mutant: obligation-met-before-start."""
    assert both(INTERVAL, [ev(0, "T0"), ev(1, "A"), tick(9)]).of("R1:0") == [(0, "violated", 5)]
    assert both(INTERVAL, [ev(0, "T0"), ev(1.99, "A"), tick(9)]).of("R1:0") == [(0, "violated", 5)]


def test_an_occurrence_exactly_at_an_interval_start_or_end_fulfils_it() -> None:
    """Mutants: obligation-start-exclusive, obligation-closes-early."""
    assert both(INTERVAL, [ev(0, "T0"), ev(1, "A"), ev(2, "A")]).of("R1:0") == [(0, "fulfilled", 2)]
    assert both(INTERVAL, [ev(0, "T0"), ev(5, "A")]).of("R1:0") == [(0, "fulfilled", 5)]


def test_a_zero_length_interval_is_open_at_its_one_instant() -> None:
    """[a, a] is not a window that closed before it opened. Mutant: empty-window-closed-at-start."""
    rule = "R1 when T0 then A within [2 seconds, ({n} * 1) seconds]"
    assert both(rule, [ev(0, "T0"), ev(2, "A")]).of("R1:0") == [(0, "fulfilled", 2)]
    assert both(rule, [ev(0, "T0"), tick(3)]).of("R1:0") == [(0, "violated", 2)]


def test_a_negative_deadline_violates_at_the_trigger_and_starts_otherwise_then() -> None:
    """§6.4 notes: the window has already closed. Mutant: negative-window-kept-open."""
    rule = "R1 when T0 then A within (3 - {n}) seconds otherwise B within 2 seconds"
    seen = both(rule, [at(0, n=4), ev(5, "T0"), ev(7, "B"), tick(10)])
    assert seen.items == [("R1:0", 5, "violated", 5), ("R1:0/o:0", 5, "fulfilled", 7)]


# ---------------------------------------------------------------- deadlines read from measures
def test_a_measure_dependent_deadline_is_read_on_the_trigger_snapshot() -> None:
    """§6.4 notes. Mutant: deadline-without-context."""
    rule = "R1 when T0 then A within ({n} * 2) seconds"
    assert both(rule, [at(0, n=2), ev(0, "T0"), at(1, n=0), ev(4, "A")]).of("R1:0") == [(0, "fulfilled", 4)]
    assert both(rule, [at(0, n=2), ev(0, "T0"), ev(4.5, "A")]).of("R1:0") == [(0, "violated", 4)]
    rule = "R1 when T0 then not A within ({n} * 2) seconds"
    assert both(rule, [at(0, n=1), ev(0, "T0"), ev(3, "A"), tick(9)]).of("R1:0") == [(0, "respected", 2)]


def test_a_measure_dependent_interval_start_is_read_on_the_trigger_snapshot() -> None:
    """Mutant: interval-start-without-context."""
    rule = "R1 when T0 then A within [({n} * 1) seconds, 6 seconds]"
    seen = both(rule, [at(0, n=3), ev(0, "T0"), ev(2, "A"), ev(3, "A")])
    assert seen.of("R1:0") == [(0, "fulfilled", 3)]
    rule = "R1 when T0 then not A within [({n} * 1) seconds, 6 seconds]"
    seen = both(rule, [at(0, n=3), ev(0, "T0"), ev(2, "A"), tick(9)])
    assert seen.of("R1:0") == [(0, "respected", 6)]


def test_an_unknown_deadline_keeps_a_prohibition_in_force_and_makes_an_obligation_due_now() -> None:
    """Runtime policy (fail closed; the reference leaves the firing undetermined).
    Mutant: unknown-deadline-prohibition-instant."""
    rules = "R1 when T0 then not A within ({n} * 2) seconds\nR2 when T0 then B within ({n} * 2) seconds"
    m, clock, _ = manager(rules, values={"b": False})  # n unknown
    m.event("T0")
    clock.set(1000)
    assert m.request("A").permitted is False
    m.tick()
    b = [t for t in m.tracker.closed if t.rule == "R2"]
    assert [(t.status, t.outcome_at) for t in b] == [("violated", 0)]


# ---------------------------------------------------------------- braced inner responses (§6.7)
INNER = (
    "R1 when T0 then A within 2 seconds otherwise {B within 3 seconds unless {b} then not B within 3 seconds}"
)


def test_an_unless_inside_a_braced_otherwise_is_read_when_the_otherwise_starts() -> None:
    """§6.7: the inner defeater is sampled at the primary deadline, not at the trigger.
    Mutant: inner-unless-ignored."""
    seen = both(INNER, [at(0, b=False), ev(0, "T0"), at(1, b=True), tick(9)])
    assert seen.items == [("R1:0", 0, "violated", 2), ("R1:0/o~1:0", 2, "respected", 5)]
    seen = both(INNER, [at(0, b=True), ev(0, "T0"), at(1, b=False), tick(9)])
    assert seen.items == [("R1:0", 0, "violated", 2), ("R1:0/o:0", 2, "violated", 5)]


def test_an_unless_inside_a_braced_then_is_read_at_the_trigger() -> None:
    rule = "R1 when T0 then A within 2 seconds unless {b} then {B within 3 seconds unless ({n} > 2) then not B within 3 seconds}"
    seen = both(rule, [at(0, b=True, n=3), ev(0, "T0"), ev(1, "B"), tick(9)])
    assert seen.items == [("R1.1~1:0", 0, "violated", 1)]
    seen = both(rule, [at(0, b=True, n=1), ev(0, "T0"), ev(1, "B"), tick(9)])
    assert seen.items == [("R1.1:0", 0, "fulfilled", 1)]


# ---------------------------------------------------------------- `otherwise` and time order (§6.5)
OTHERWISE = "R1 when T0 then A within 2 seconds otherwise B within 3 seconds"


def test_an_otherwise_starts_at_the_deadline_even_when_the_miss_is_noticed_later() -> None:
    """Mutant: otherwise-starts-when-noticed."""
    seen = both(OTHERWISE, [ev(0, "T0"), tick(4), ev(5, "B")])
    assert seen.items == [("R1:0", 0, "violated", 2), ("R1:0/o:0", 2, "fulfilled", 5)]
    seen = both(OTHERWISE, [ev(0, "T0"), tick(4), ev(5.5, "B")])
    assert seen.items == [("R1:0", 0, "violated", 2), ("R1:0/o:0", 2, "violated", 5)]


def test_an_occurrence_counts_for_an_otherwise_that_started_before_it_at_the_same_step() -> None:
    """Time passes before the occurrence: the fallback started at 2 is in force when B
    arrives at 3, with no tick in between. Mutant: occurrence-numbered-before-time-passes."""
    seen = both(OTHERWISE, [ev(0, "T0"), ev(3, "B")])
    assert seen.items == [("R1:0", 0, "violated", 2), ("R1:0/o:0", 2, "fulfilled", 3)]


def test_an_otherwise_started_at_a_deadline_is_in_force_before_a_later_deadline_is_judged() -> None:
    """R1's fallback forbids B from 2 on; R2 owes B until 4: when the fallback starts, R2
    is refused at 2 -- even when both deadlines are judged at one tick, at 5.
    Mutant: deadlines-judged-together."""
    rules = "R1 when T0 then A within 2 seconds otherwise not B within 5 seconds\nR2 when T0 then B within 4 seconds"
    seen = both(rules, [ev(0, "T0"), tick(5)])
    assert seen.items == [
        ("R1:0", 0, "violated", 2),
        ("R2:0", 0, "blocked", 2),
        ("R1:0/o:0", 2, "pending", None),
    ]
    assert seen.conflicts == [(2, ("R2", "R1"), "prohibition-wins")]


def test_a_late_occurrence_is_recorded_once() -> None:
    """§6.5: the first E after the deadline is late, once. Mutant: late-reported-every-time."""
    m, clock, _ = manager("R1 when T0 then A within 2 seconds")
    m.event("T0")
    for t in (3, 4, 5):
        clock.set(t)
        m.event("A")
    [a] = [t for t in m.tracker.closed if t.rule == "R1"]
    assert (a.status, a.outcome_at, a.late) == ("violated", 2, [3])


def test_an_occurrence_at_the_deadline_of_a_window_closed_at_its_start_is_not_late() -> None:
    """`within [3, 1]` (from measures) is violated at once; an E at t+1 is not after the
    deadline, the next one is. Mutant: late-at-deadline."""
    m, clock, _ = manager("R1 when T0 then A within [3 seconds, ({n} * 1) seconds]")
    m.update({"n": 1})
    m.event("T0")
    for t in (1, 2, 3):
        clock.set(t)
        m.event("A")
    [a] = [t for t in m.tracker.closed if t.rule == "R1"]
    assert (a.status, a.outcome_at, a.late) == ("violated", 0, [2])


# ---------------------------------------------------------------- `else` (§6.6)
def test_an_else_alternative_counts_up_to_its_own_deadline_included() -> None:
    """The obligation is judged when the last window closes. Mutants: else-deadline-min,
    else-closes-early."""
    rule = "R1 when T0 then A within 2 seconds else B within 5 seconds"
    assert both(rule, [ev(0, "T0"), ev(4, "B")]).of("R1:0") == [(0, "fulfilled", 4)]
    assert both(rule, [ev(0, "T0"), ev(5, "B")]).of("R1:0") == [(0, "fulfilled", 5)]
    assert both(rule, [ev(0, "T0"), ev(5.5, "B")]).of("R1:0") == [(0, "violated", 5)]


def test_an_else_alternative_ignores_occurrences_before_its_interval() -> None:
    """Mutant: else-ignores-start."""
    rule = "R1 when T0 then A within 2 seconds else B within [3 seconds, 5 seconds]"
    assert both(rule, [ev(0, "T0"), ev(1, "B"), tick(9)]).of("R1:0") == [(0, "violated", 5)]
    assert both(rule, [ev(0, "T0"), ev(1, "B"), ev(3, "B")]).of("R1:0") == [(0, "fulfilled", 3)]


def test_an_else_alternative_needs_every_one_of_its_items() -> None:
    """Mutant: else-one-item-enough."""
    rule = "R1 when T0 then A within 2 seconds else {B within 5 seconds and A within [3 seconds, 6 seconds]}"
    assert both(rule, [ev(0, "T0"), ev(1, "B"), tick(9)]).of("R1:0") == [(0, "violated", 6)]
    assert both(rule, [ev(0, "T0"), ev(1, "B"), ev(4, "A")]).of("R1:0") == [(0, "fulfilled", 4)]


# ---------------------------------------------------------------- conflicts (issue 12, no priority)
def test_a_prohibition_covering_what_is_left_of_an_obligation_refuses_it() -> None:
    """The part of the window already passed does not save the obligation.
    Mutant: conflict-ignores-elapsed-window."""
    rules = "R1 when T0 then A within 5 seconds\nR2 when T1 then not A within 10 seconds"
    seen = both(rules, [ev(0, "T0"), ev(2, "T1"), tick(20)])
    assert seen.items == [("R1:0", 0, "blocked", 2), ("R2:0", 2, "respected", 12)]
    assert seen.conflicts == [(2, ("R1", "R2"), "prohibition-wins")]
    seen = both(rules, [ev(0, "T1"), ev(2, "T0"), tick(20)])  # until 10: R1's window [2, 7] is covered
    assert seen.items == [("R2:0", 0, "respected", 10), ("R1:0", 2, "blocked", 2)]


def test_windows_that_coincide_exactly_conflict() -> None:
    """Same start, same end: every instant is forbidden. Mutants: conflict-end-strict,
    conflict-start-strict."""
    rules = "R1 when T0 then A within 5 seconds\nR2 when T0 then not A within 5 seconds"
    seen = both(rules, [ev(0, "T0"), tick(9)])
    assert seen.items == [("R1:0", 0, "blocked", 0), ("R2:0", 0, "respected", 5)]
    rules = (
        "R1 when T0 then A within [2 seconds, 5 seconds]\nR2 when T0 then not A within [2 seconds, 5 seconds]"
    )
    seen = both(rules, [ev(0, "T0"), tick(9)])
    assert seen.items == [("R1:0", 0, "blocked", 0), ("R2:0", 0, "respected", 5)]
    rules = "R1 when T0 then A within 6 seconds\nR2 when T0 then not A within 5 seconds"
    seen = both(rules, [ev(0, "T0"), ev(6, "A")])  # one instant is allowed: no conflict
    assert seen.items == [("R1:0", 0, "fulfilled", 6), ("R2:0", 0, "respected", 5)] and not seen.conflicts


def test_an_obligation_with_an_else_is_never_refused() -> None:
    """Mutant: conflict-despite-else."""
    rules = (
        "R1 when T0 then A within 5 seconds else B within 5 seconds\nR2 when T0 then not A within 10 seconds"
    )
    seen = both(rules, [ev(0, "T0"), ev(3, "B"), tick(20)])
    assert seen.items == [("R1:0", 0, "fulfilled", 3), ("R2:0", 0, "respected", 10)] and not seen.conflicts


def test_a_refused_obligation_starts_its_otherwise_at_the_conflict() -> None:
    """Mutant: refused-without-otherwise."""
    rules = "R1 when T0 then A within 5 seconds otherwise B within 2 seconds\nR2 when T1 then not A within 10 seconds"
    seen = both(rules, [ev(0, "T0"), ev(1, "T1"), ev(3, "B")])
    assert seen.items == [
        ("R1:0", 0, "blocked", 1),
        ("R2:0", 1, "pending", None),
        ("R1:0/o:0", 1, "fulfilled", 3),
    ]


def test_a_held_action_is_dispatched_once_the_prohibition_ends() -> None:
    """A prohibition that forbids part of the window is no conflict: the decision waits.
    Mutant: ready-never-holds."""
    m, clock, records = manager("R1 when T0 then A within 10 seconds\nR2 when T1 then not A within 5 seconds")
    m.event("T1")
    clock.set(1)
    m.event("T0")
    held = [r.data for r in records if r.kind == "held"]
    assert [(h["rule"], h["events"], h["by"]) for h in held] == [("R1", ["A"], ["R2"])]
    clock.set(5)
    m.tick()
    assert not [r for r in records if r.kind == "dispatch"]
    clock.set(5.5)
    m.tick()
    assert [r.data["decision"]["rule"] for r in records if r.kind == "dispatch"] == ["R1"]


# ---------------------------------------------------------------- priorities (§13)
@pytest.mark.parametrize("first", ["T0", "T1"])
def test_cancellation_based_priority_cancels_the_lower_rule_whichever_fired_first(first: str) -> None:
    """Mutant: between-lower-wins."""
    rules = "R1 when T0 then A within 5 seconds\nR2 when T1 then B within 5 seconds"
    second = "T1" if first == "T0" else "T0"
    seen = both(rules, [ev(0, first), ev(1, second), tick(9)], priorities=[("R1", "R2")])
    r2 = 1 if first == "T0" else 0
    assert seen.of("R2:0") == [(r2, "cancelled", 1)]
    assert seen.of("R1:0") == [(1 - r2, "violated", 6 - r2)]


def test_a_cancelled_instance_imposes_nothing_and_an_empty_one_cancels_nothing() -> None:
    """A higher instance whose only item closed at once is not active: it cancels nothing.
    Mutant: prioritise-inactive."""
    rules = "R1 when T0 then not A within (3 - {n}) seconds\nR2 when T1 then B within 5 seconds"
    seen = both(rules, [at(0, n=4), ev(0, "T1"), ev(1, "T0"), ev(2, "B")], priorities=[("R1", "R2")])
    assert seen.items == [("R2:0", 0, "fulfilled", 2), ("R1:0", 1, "respected", 1)]


@pytest.mark.parametrize("semantics", ["cancel", "conflict-aware"])
def test_an_undetermined_higher_decision_cancels_nothing(semantics: str) -> None:
    """R1's trigger condition reads b, which has no value: the reference imposes nothing for
    that firing; the runtime holds R1's prohibition fail-closed, but that policy must not
    cancel R2 (R1 may well not apply): R2's obligation is violated at its deadline."""
    rules = "R1 when T0 and {b} then not A within 5 seconds\nR2 when T1 then B within 5 seconds"
    trace = [Step(0, values={"n": 1, "s": "low"}), ev(0, "T1"), ev(1, "T0"), tick(9)]
    case = Case(spec_text(rules), trace, HedgeSemantics.LAST_WINS, (("R1", "R2"),), semantics)
    want = reference(case)
    assert [(key, status, at) for _, _, key, _, _, status, at in want["verdicts"]] == [
        ("R2:0", "violated", 5)
    ]
    got = runtime(case)
    assert [(key, status, at) for _, rule, key, _, _, status, at in got["verdicts"] if rule == "R2"] == [
        ("R2:0", "violated", 5)
    ]


CA_RULES = "R1 when T0 then A within 5 seconds\nR2 when T0 then not A within 10 seconds"
CA = {"priorities": [("R1", "R2")], "priority_semantics": "conflict-aware"}


def test_conflict_aware_priority_keeps_the_lower_rule_until_the_higher_deadline() -> None:
    """§13.3: TK's Rule21 > Rule3 shape. Mutants: conflict-aware-refuses, forced-wrong-victim."""
    seen = both(CA_RULES, [ev(0, "T0"), ev(5, "A")], **CA)
    assert seen.items == [("R1:0", 0, "fulfilled", 5), ("R2:0", 0, "cancelled", 5)]
    assert seen.conflicts == [(0, ("R1", "R2"), "conflict-aware")]
    seen = both(CA_RULES, [ev(0, "T0"), ev(2, "A")], **CA)  # too early: the lower rule still binds
    assert seen.items == [("R1:0", 0, "fulfilled", 2), ("R2:0", 0, "violated", 2)]


def test_a_conflict_aware_cancellation_comes_before_the_deadline_it_is_due_at() -> None:
    """Nothing happens until after 5: the cancellation at 5 comes first, then R1 is judged.
    Mutant: cancellation-after-deadline."""
    seen = both(CA_RULES, [ev(0, "T0"), tick(6)], **CA)
    assert seen.items == [("R1:0", 0, "violated", 5), ("R2:0", 0, "cancelled", 5)]


@pytest.mark.parametrize(
    "prohibition",
    ["not A within 5 seconds", "not A within [5 seconds, 10 seconds]", "not A within [2 seconds, 5 seconds]"],
)
def test_a_prohibition_that_forbids_the_higher_deadline_instant_is_cancelled_then(prohibition: str) -> None:
    """The forcing test is closed at both ends of the prohibition's window.
    Mutants: forced-window-end-strict, forced-window-start-strict."""
    rules = f"R1 when T0 then A within 5 seconds\nR2 when T0 then {prohibition}"
    seen = both(rules, [ev(0, "T0"), ev(5, "A"), tick(12)], **CA)
    assert seen.items == [("R1:0", 0, "fulfilled", 5), ("R2:0", 0, "cancelled", 5)]


def test_the_earliest_conflict_aware_cancellation_is_applied_first() -> None:
    """R2 is forced out by R1 at 3 and would be by R3 at 5: it goes at 3, by R1.
    Mutant: forced-latest-first."""
    rules = (
        "R1 when T0 then A within 3 seconds\n"
        "R2 when T0 then not A within 10 seconds and B within 5 seconds\n"
        "R3 when T0 then not B within 10 seconds"
    )
    seen = both(
        rules,
        [ev(0, "T0"), tick(6)],
        priorities=[("R1", "R2"), ("R3", "R2")],
        priority_semantics="conflict-aware",
    )
    assert seen.of("R2:0") == [(0, "cancelled", 3)] and seen.of("R2:1") == [(0, "cancelled", 3)]
    m, clock, records = manager(rules, priorities=["R1 > R2", "R3 > R2"], priority_semantics="conflict-aware")
    m.event("T0")
    clock.set(6)
    m.tick()
    assert [(r.data["rule"], r.data["by"], r.data["at"]) for r in records if r.kind == "cancelled"] == [
        ("R2", "R1", 3)
    ]


def test_a_priority_lead_cancels_the_lower_rule_that_much_earlier() -> None:
    """Mutant: forced-ignores-lead."""
    seen = both(CA_RULES, [ev(0, "T0"), ev(4, "A")], lead=1.0, **CA)
    assert seen.items == [("R1:0", 0, "fulfilled", 4), ("R2:0", 0, "cancelled", 4)]
    m, clock, _ = manager(
        CA_RULES, priorities=["R1 > R2"], priority_semantics="conflict-aware", priority_lead=1.0
    )
    m.event("T0")
    clock.set(3.5)
    assert m.request("A").permitted is False
    clock.set(4)
    assert m.request("A").permitted is True
