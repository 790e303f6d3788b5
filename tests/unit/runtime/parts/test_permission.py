"""Permission alone: may an event happen now, and if not why -- one phrase per rule."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.errors import clip
from cosleec.records import Kind
from cosleec.runtime import UnknownEvents
from cosleec.runtime.errors import ContextError
from cosleec.runtime.journal import JournalError
from cosleec.runtime.permission import Answers, Permission, undeclared

from .build import Parts, journaled, parts

RULES = (
    "R1 when E then not Rec within 10 seconds "
    "R2 when G then not Rec within 5 seconds "
    "R3 when F then not Rec eventually"
)


def ask(p: Parts, event: str, t: float, source: str = "") -> Permission:
    p.clock.set(t)
    with p.core.steps.step() as step:
        return p.answers.ask(event, source, step)


def forbidding(p: Parts, event: str = "Rec") -> Permission:
    return p.answers.given(event, p.core.tracker.forbidding(event, p.clock.now()))


def test_a_permitted_event_is_answered_once_and_recorded_never() -> None:
    p = parts(RULES)
    first = ask(p, "Rec", 0.0)
    assert first == Permission("Rec", True, (), "Rec is permitted: no prohibition in force forbids it now")
    assert first and ask(p, "Rec", 1.0) is first
    assert p.heard == [] and p.core.stats.refused == 0


def test_a_rule_forbidding_with_several_activations_is_named_once_until_the_last_end() -> None:
    p = parts(RULES)
    p.fire("E")
    p.clock.set(2.0)
    p.fire("E")
    answer = forbidding(p)
    assert not answer and answer.rules == ("R1",)
    # how long it still holds, never a reading of the clock (the last activation ends at 12)
    assert answer.reason == "Rec is forbidden by R1 for another 10 s (R1: not Rec within 10 s)"
    # for people: the longest wait, and each decision's sentence once
    assert answer.for_people == "I can't rec for another 10 seconds."  # not "I will not rec for 10 s"


def test_the_rules_are_named_in_turn_and_one_with_no_end_says_so() -> None:
    p = parts(RULES)
    p.fire("E")
    p.fire("F")
    p.clock.set(2.0)
    p.fire("G")
    p.fire("F")  # an activation with no end is not replaced by a later one
    answer = forbidding(p)
    assert answer.rules == ("R1", "R3", "R2")
    assert answer.reason == (
        "Rec is forbidden by R1 for another 8 s (R1: not Rec within 10 s) and "
        "by R3 with no end (R3: not Rec eventually) and "
        "by R2 for another 5 s (R2: not Rec within 5 s)"
    )
    assert answer.for_people == "I can't rec now."  # R3 has no end


@pytest.mark.parametrize("endless", [0, 1])
def test_an_activation_with_no_end_outlasts_one_with_an_end_of_the_same_rule(endless: int) -> None:
    p = parts(RULES)
    p.fire("E")
    p.clock.set(1.0)
    p.fire("E")
    p.core.tracker.active[endless].hi = None  # as if that activation's window had no end
    assert forbidding(p).reason.startswith("Rec is forbidden by R1 with no end (")


def test_of_two_activations_with_no_end_the_first_speaks() -> None:
    p = parts(RULES)
    p.fire("F")
    p.clock.set(2.0)
    p.fire("F")
    p.core.decisions.clear()
    assert (
        forbidding(p).reason
        == "Rec is forbidden by R3 with no end (R3: not Rec eventually, in force for 2 s)"
    )
    assert forbidding(p).for_people == "I can't rec now."


def test_when_the_decision_is_no_longer_kept_the_prohibition_says_when_it_began() -> None:
    p = parts(RULES)
    p.clock.set(2.0)
    p.fire("E")
    p.core.decisions.clear()
    p.clock.set(5.0)
    assert forbidding(p).reason == (
        "Rec is forbidden by R1 for another 7 s (R1: not Rec within 10 s, in force for 3 s)"
    )
    assert forbidding(p).for_people == "I can't rec for another 7 seconds."


def test_why_finds_the_decision_by_its_id_among_those_kept() -> None:
    p = parts(RULES)
    for event in ["E", "G", "F"]:
        p.fire(event)
    answers = Answers(p.core)
    tracked = sorted(p.core.tracker.active, key=lambda t: t.decision_id)
    assert [answers.why(t) for t in tracked] == [
        "R1: not Rec within 10 s",
        "R2: not Rec within 5 s",
        "R3: not Rec eventually",
    ]
    p.core.decisions.popleft()
    assert answers.why(tracked[0]) is None and answers.why(tracked[1]) == "R2: not Rec within 5 s"


def test_a_refusal_is_counted_once_recorded_and_charged_to_each_prohibition() -> None:
    p = parts(RULES)
    p.fire("E")
    p.fire("G")
    del p.heard[:]
    source = "operator " * 40
    answer = ask(p, "Rec", 5.0, source=source)
    assert not answer
    assert p.core.stats.refused == 1
    assert sorted(t.refused for t in p.core.tracker.active) == [1, 1]
    (refused,) = p.of(Kind.REFUSED)
    assert refused["by"] == ["R1", "R2"] and refused["obligations"] == [1, 2]
    assert refused["reason"] == answer.reason
    assert refused["source"] == clip(source, 200) != source
    ask(p, "Rec", 5.0)
    assert "source" not in p.of(Kind.REFUSED)[-1]


def test_a_prohibition_forbids_to_its_last_instant_included() -> None:
    p = parts(RULES)
    p.fire("E")
    assert not ask(p, "Rec", 10.0)
    assert ask(p, "Rec", 10.5)


def test_the_refusal_count_of_a_prohibition_is_kept_in_the_journal(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    p.fire("E")
    with p.core.steps.step() as step:
        p.answers.ask("Rec", "", step)
        assert step.change.obligations[1] is not None
        assert step.change.obligations[1]["refused"] == 1


def test_a_long_event_name_is_clipped_in_the_reason() -> None:
    p = parts(RULES)
    p.fire("E")
    name = "x" * 500
    answer = p.answers.given(name, p.core.tracker.forbidding("Rec", 0.0))
    assert answer.event == name
    assert answer.reason.startswith(f"{clip(name, 80)} is forbidden by R1")


@pytest.mark.parametrize(
    ("broken", "reason"),
    [
        (
            JournalError("disk full"),
            "Rec is not permitted: the Manager can no longer keep its state (disk full), so it permits nothing",
        ),
        (None, "Rec is not permitted: the Manager is closed"),
    ],
)
def test_a_stopped_runtime_permits_nothing(broken: Exception | None, reason: str) -> None:
    answer = Answers.stopped("Rec", broken)
    assert answer == Permission("Rec", False, (), reason)


def test_a_stopped_runtime_shows_a_name_that_is_no_string() -> None:
    assert Answers.stopped(42, None).reason == "42 is not permitted: the Manager is closed"  # type: ignore[arg-type]


# ---------------------------------------------------------------------------- unknown events


def test_a_declared_event_is_no_concern_of_the_policy() -> None:
    p = parts(RULES)
    with p.core.steps.step() as step:
        assert undeclared(p.core, "Rec", "request", step, UnknownEvents.RAISE) is None
    assert p.core.stats.rejected == 0 and p.heard == []


def test_an_undeclared_event_raises_with_the_closest_names() -> None:
    p = parts(RULES)
    with pytest.raises(ContextError, match="unknown event 'Reec'") as e, p.core.steps.step() as step:
        undeclared(p.core, "Reec", "event", step, UnknownEvents.RAISE)
    assert e.value.hint == "did you mean Rec?"
    assert p.of(Kind.REJECTED) == [
        {"reason": "unknown event 'Reec'", "what": "event", "hint": "did you mean Rec?"}
    ]
    assert p.core.stats.rejected == 1


def test_an_undeclared_event_is_refused_with_a_reason_under_refuse() -> None:
    p = parts(RULES)
    with p.core.steps.step() as step:
        why = undeclared(p.core, "Typo" * 100, "request", step, UnknownEvents.REFUSE)
    assert why is not None
    assert why.startswith("Typo") and why.endswith(
        "is not an event the rules declare (declare it in the rules' def block)"
    )
    assert p.of(Kind.REJECTED)[0]["what"] == "request"


def test_an_event_named_by_no_string_is_rejected_whatever_the_policy() -> None:
    p = parts(RULES)
    with (
        pytest.raises(ContextError, match="an event is named by a string, not int"),
        p.core.steps.step() as step,
    ):
        undeclared(p.core, 7, "event", step, UnknownEvents.REFUSE)  # type: ignore[arg-type]
    assert p.of(Kind.REJECTED) == [{"reason": "an event is named by a string, not int"}]
