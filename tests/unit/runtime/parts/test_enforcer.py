"""The enforcer alone: obligations begin, meet events, fall due, and meet each other."""

from __future__ import annotations

import pytest

from cosleec.lang import CONFLICT_AWARE
from cosleec.records import Kind
from cosleec.runtime.jobs import Job
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.priorities import forced

from .build import Parts, parts, prioritised

CLASH = "R1 when E then not Rec within 10 seconds R2 when G then Rec within 5 seconds otherwise Help"


def at(p: Parts, t: float) -> list[Job]:
    """The clock moves to ``t`` and what fell due is judged (a step of its own)."""
    p.clock.set(t)
    with p.core.steps.step() as step:
        return p.enforcer.advance(step.now, step)


def items(jobs: list[Job], rule: str) -> list[Tracked]:
    return [t for j in jobs if j.decision.rule == rule and j.decision.event != "otherwise" for t in j.items]


def statuses(p: Parts) -> dict[int, tuple[str, float | None, str | None]]:
    """Every obligation that ended, by id: (status, when, settled by)."""
    return {t.id: (t.status, t.outcome_at, t.by) for t in p.core.tracker.closed}


# ---------------------------------------------------------------------------- conflicts


@pytest.mark.parametrize("prohibition_first", [True, False])
def test_a_prohibition_covering_an_obligations_window_refuses_it_and_starts_its_otherwise(
    prohibition_first: bool,
) -> None:
    p = parts(CLASH)
    p.clock.set(1.0)
    jobs = p.fire("E") + p.fire("G") if prohibition_first else p.fire("G") + p.fire("E")
    (o,) = items(jobs, "R2")
    assert (o.status, o.outcome_at, o.by) == ("blocked", 1.0, "R1")
    (fallback,) = [j for j in jobs if j.decision.event == "otherwise"]
    assert (fallback.decision.time, fallback.decision.violated) == (1.0, o.id)
    assert (fallback.decision.origin, fallback.decision.missed) == ("otherwise", o.obligation)
    assert [t.event for t in fallback.items] == ["Help"]
    (conflict,) = p.of(Kind.CONFLICT)
    assert conflict["between"] == ["R2", "R1"] and conflict["resolution"] == "prohibition-wins"
    assert conflict["winner"] == "R1" and conflict["at"] == 1.0
    assert conflict["explanation"] == (
        "R2 requires Rec within 5 s and R1 forbids Rec for another 10 s: "
        "the prohibition forbids the whole window and wins: the obligation is blocked"
    )
    assert (p.core.stats.conflicts, p.core.stats.violations) == (1, 1)


@pytest.mark.parametrize(
    ("within", "later", "refused"),
    [
        (10.0, 0.0, True),  # the windows end together: the prohibition covers it
        (10.0, 0.5, False),  # it can still be met after the prohibition ends
        (6.0, 4.0, True),  # started later, ends when the prohibition does
        (7.0, 4.0, False),
    ],
)
def test_a_conflict_needs_the_prohibition_to_cover_the_end_of_the_window(
    within: float, later: float, refused: bool
) -> None:
    p = parts(f"R1 when E then not Rec within 10 seconds R2 when G then Rec within {within:g} seconds")
    p.fire("E")
    p.clock.set(later)
    (o,) = items(p.fire("G"), "R2")
    assert (o.status == "blocked") is refused
    assert len(p.of(Kind.CONFLICT)) == int(refused)


@pytest.mark.parametrize(("opens", "refused"), [(2, True), (1, False)])
def test_a_conflict_needs_the_prohibition_to_cover_the_start_of_the_window(opens: int, refused: bool) -> None:
    p = parts(
        "R1 when E then not Rec within [2 seconds, 10 seconds] "
        f"R2 when G then Rec within [{opens} seconds, 5 seconds]"
    )
    p.fire("E")
    (o,) = items(p.fire("G"), "R2")
    assert (o.status == "blocked") is refused


def test_a_prohibition_that_opens_later_is_no_conflict_for_an_obligation_started_inside_it() -> None:
    p = parts("R1 when E then not Rec within [2 seconds, 10 seconds] R2 when G then Rec within 5 seconds")
    p.fire("E")
    assert items(p.fire("G"), "R2")[0].status == "pending"  # Rec is allowed until 2
    p.clock.set(2.0)
    assert items(p.fire("G"), "R2")[0].status == "blocked"  # from 2 it is forbidden to its end


def test_an_obligation_with_an_else_is_never_refused() -> None:
    p = parts(
        "R1 when E then not Rec within 10 seconds R2 when G then Rec within 5 seconds else F within 20 seconds"
    )
    p.fire("E")
    assert items(p.fire("G"), "R2")[0].status == "pending"
    assert p.of(Kind.CONFLICT) == []


# ---------------------------------------------------------------------------- time


def test_a_deadline_falls_due_only_once_the_clock_has_passed_it() -> None:
    p = parts("R2 when G then Rec within 5 seconds otherwise Help R1 when E then not F within 5 seconds")
    p.fire("G")
    p.fire("E")
    assert at(p, 5.0) == []
    assert statuses(p) == {}
    (fallback,) = at(p, 5.25)
    assert statuses(p) == {1: ("violated", 5.0, None), 2: ("respected", 5.0, None)}
    assert (fallback.decision.event, fallback.decision.time, fallback.decision.violated) == (
        "otherwise",
        5.0,
        1,
    )
    assert fallback.items[0].start == 5.0
    assert p.core.stats.violations == 1  # a prohibition that held is no violation


def test_a_batch_judges_at_most_its_limit_and_says_more_are_due() -> None:
    p = parts("R1 when E then F within 1 seconds and G within 1 seconds and Help within 1 seconds")
    p.fire("E")
    p.clock.set(2.0)
    with p.core.steps.step() as step:
        p.enforcer.advance(2.0, step, limit=2)
        assert step.more and len(statuses(p)) == 2
    with p.core.steps.step() as step:
        p.enforcer.advance(2.0, step, limit=2)
        assert not step.more and len(statuses(p)) == 3


def test_each_otherwise_is_in_force_before_a_later_deadline_is_judged() -> None:
    p = parts(
        "R1 when E then F within 3 seconds otherwise not G within 10 seconds R2 when E then G within 5 seconds"
    )
    p.fire("E")
    at(p, 6.0)  # both deadlines passed: F's at 3 first, whose otherwise forbids G from 3
    g = next(t for t in p.core.tracker.closed if t.event == "G" and not t.prohibition)
    assert (g.status, g.outcome_at, g.by) == ("blocked", 3.0, "R1")


def test_an_occurrence_counts_only_for_obligations_started_before_it() -> None:
    p = parts("R1 when E then F within 5 seconds")
    with p.core.steps.step() as step:
        p.trigger("E", step)
        seq = p.core.steps.counters["seq"] - 1  # the trigger's own occurrence
        assert p.enforcer.occur("F", 1.0, seq, step) == []
        assert p.core.tracker.active[0].status == "pending"
        p.enforcer.occur("F", 1.0, seq + 1, step)
    assert statuses(p) == {1: ("fulfilled", 1.0, "F")}


def test_an_event_a_prohibition_forbids_violates_it_and_starts_its_otherwise_then() -> None:
    p = parts("R1 when E then not Rec within 10 seconds otherwise Help")
    p.fire("E")
    p.clock.set(3.0)
    (fallback,) = p.fire("Rec")
    assert statuses(p) == {1: ("violated", 3.0, "Rec")}
    assert (fallback.decision.time, [t.event for t in fallback.items]) == (3.0, ["Help"])


def test_a_window_that_closes_before_it_opens_is_judged_at_once() -> None:
    p = parts("R1 when E then F within (n) seconds otherwise Help")
    p.update(n=-1)
    p.clock.set(2.0)
    jobs = p.fire("E")
    assert statuses(p) == {1: ("violated", 2.0, None)}
    assert [j.decision.event for j in jobs] == ["E", "otherwise"]


# ---------------------------------------------------------------------------- priorities: cancel


@pytest.mark.parametrize("higher_first", [False, True])
def test_a_cancellation_priority_cancels_the_lower_activation(higher_first: bool) -> None:
    p = parts(
        "R1 when E then F within 10 seconds R2 when G then Help within 10 seconds", priorities=("R1 > R2",)
    )
    jobs = p.fire("E") + p.fire("G") if higher_first else p.fire("G") + p.fire("E")
    (lower,) = items(jobs, "R2")
    (higher,) = items(jobs, "R1")
    assert (lower.status, lower.by, higher.status) == ("cancelled", "R1", "pending")
    (cancelled,) = p.of(Kind.CANCELLED)
    assert cancelled == {
        "instance": lower.instance,
        "rule": "R2",
        "by": "R1",
        "at": 0.0,
        "priority": "cancel",
        "obligations": [lower.id],
    }
    assert p.core.stats.cancelled == 1


def test_a_priority_cancels_only_the_rules_it_orders() -> None:
    p = parts(
        "R1 when E then F within 10 seconds R2 when G then Help within 10 seconds R3 when E then G within 1 seconds",
        priorities=("R1 > R3",),
    )
    p.fire("G")
    p.fire("E")
    assert {t.rule for t in p.core.tracker.active} == {"R1", "R2"}  # R3, lower than R1, is cancelled


def test_a_cancellation_settles_the_conflicts_between_the_two_activations() -> None:
    p = parts(CLASH, priorities=("R1 > R2",))
    p.fire("G")
    p.fire("E")
    (conflict,) = p.of(Kind.CONFLICT)
    assert (conflict["resolution"], conflict["winner"]) == ("cancel", "R1")
    assert conflict["explanation"].endswith("R1 has priority (cancel): the other is cancelled")
    assert statuses(p) == {1: ("cancelled", 0.0, "R1")}  # cancelled, not refused: no otherwise


def test_an_undetermined_decision_is_no_activation_a_priority_cancels_or_keeps() -> None:
    p = parts(
        "R1 when E and a then not F within 10 seconds R2 when G then Help within 10 seconds",
        priorities=("R1 > R2",),
    )
    p.fire("G")
    p.fire("E")  # R1 undetermined: it forbids F, and cancels nothing
    assert p.of(Kind.CANCELLED) == []


def test_an_undetermined_prohibition_wins_a_conflict_whatever_the_priority() -> None:
    p = parts(
        "R1 when E and a then not Rec within 10 seconds R2 when G then Rec within 5 seconds",
        priorities=("R1 > R2",),
    )
    p.fire("E")  # undetermined: no activation a priority acts on, but its prohibition holds
    (o,) = items(p.fire("G"), "R2")
    assert (o.status, o.by) == ("blocked", "R1")
    assert p.of(Kind.CONFLICT)[0]["resolution"] == "prohibition-wins"


def test_an_activation_that_imposes_nothing_cancels_nothing() -> None:
    p = parts(
        "R1 when E then F within 10 seconds unless a R2 when G then Help within 10 seconds",
        priorities=("R1 > R2",),
    )
    p.update(a=True)
    p.fire("G")
    p.fire("E")  # R1's clause requires nothing: it is not active
    assert p.of(Kind.CANCELLED) == [] and [t.rule for t in p.core.tracker.active] == ["R2"]


def test_an_undetermined_decision_meets_no_activation_when_priorities_arrive() -> None:
    p = parts("R1 when E and a then not F within 10 seconds R2 when G then Help within 10 seconds")
    p.fire("E")
    p.fire("G")
    p.core.priorities = prioritised(p.core.ruleset, "R1 > R2")
    p.core.index()
    with p.core.steps.step() as step:
        p.enforcer.meet(p.core.tracker.active, 1.0, step)
    assert p.of(Kind.CANCELLED) == []


def test_activations_in_force_before_a_priority_meet_in_the_order_they_began() -> None:
    p = parts("R1 when E then F within 10 seconds R2 when G then Help within 10 seconds")
    p.fire("G")
    p.fire("E")
    p.core.priorities = prioritised(p.core.ruleset, "R1 > R2")
    p.core.index()
    with p.core.steps.step() as step:
        p.enforcer.meet(p.core.tracker.active, 1.0, step)
    assert statuses(p) == {1: ("cancelled", 1.0, "R1")}


def test_cancelling_an_activation_with_nothing_in_force_records_nothing() -> None:
    p = parts(CLASH, priorities=("R1 > R2",))
    with p.core.steps.step() as step:
        assert not p.enforcer.cancel(99, 0.0, "R1", step, "cancel")
        assert step.events == []


# ---------------------------------------------------------------------------- priorities: conflict-aware


AWARE = "R1 when E then not Rec within 10 seconds R2 when G then Rec within 5 seconds"


@pytest.mark.parametrize(("lead", "cut"), [(0.0, 5.0), (1.5, 3.5)])
def test_conflict_aware_keeps_the_lower_rule_until_the_deadline_that_forces_it(
    lead: float, cut: float
) -> None:
    p = parts(AWARE, priorities=("R1 > R2",), semantics=CONFLICT_AWARE, lead=lead)
    p.fire("G")
    p.fire("E")
    (conflict,) = p.of(Kind.CONFLICT)
    assert (conflict["resolution"], conflict["winner"]) == (CONFLICT_AWARE, "R1")
    assert [t.status for t in p.core.tracker.active] == ["pending", "pending"]
    at(p, cut - 0.25)
    assert p.of(Kind.CANCELLED) == []
    at(p, cut)  # at the forcing deadline itself: cancelled (a deadline is judged only after it)
    (cancelled,) = p.of(Kind.CANCELLED)
    assert (cancelled["rule"], cancelled["at"], cancelled["priority"]) == ("R2", cut, CONFLICT_AWARE)
    assert statuses(p) == {1: ("cancelled", cut, "R1")}


def test_conflict_aware_cancels_a_lower_prohibition_at_the_higher_obligations_deadline() -> None:
    p = parts(
        "R1 when E then Rec within 5 seconds R2 when G then not Rec within 10 seconds",
        priorities=("R1 > R2",),
        semantics=CONFLICT_AWARE,
    )
    p.fire("E")
    p.fire("G")
    at(p, 5.0)
    assert statuses(p) == {2: ("cancelled", 5.0, "R1")}
    assert [t.rule for t in p.core.tracker.active] == ["R1"]


def test_a_deadline_before_the_cut_is_judged_first() -> None:
    p = parts(f"{AWARE} R3 when E then F within 2 seconds", priorities=("R1 > R2",), semantics=CONFLICT_AWARE)
    p.fire("G")
    p.fire("E")
    del p.heard[:]
    at(p, 6.0)
    assert [(str(ev.kind), ev.data.get("status"), ev.data.get("at")) for ev in p.heard] == [
        ("obligation", "violated", 2.0),  # F's deadline, at 2
        ("obligation", "cancelled", 5.0),  # then the cut, at 5
        ("cancelled", None, 5.0),
    ]


def test_the_kept_cut_is_the_one_a_fresh_look_at_everything_finds() -> None:
    p = parts(
        "R1 when E then not Rec within 10 seconds R2 when G then Rec within 5 seconds R3 when F then Rec within 3 seconds",
        priorities=("R1 > R2", "R1 > R3"),
        semantics=CONFLICT_AWARE,
    )
    for event in ["G", "E", "F", "G"]:
        p.fire(event)
        kept = p.enforcer.forced()
        fresh = forced(p.core.tracker, p.core.priorities)
        assert kept == fresh
    assert kept is not None and (kept[0], kept[1].rule) == (3.0, "R3")
    p.enforcer.reset()
    assert p.enforcer.forced() == kept
