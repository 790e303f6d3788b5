"""Which reading a recorded run is judged under (semantics/conformance.py), decided without the CLI:
the user's options, else the audit log's, else the defaults; what the user is told about them."""

from __future__ import annotations

import pytest

from cosleec.errors import UserError
from cosleec.lang import HedgeSemantics, PrioritySemantics, Reading, Unknowns, Untimed, parse
from cosleec.semantics import Recording, RunOptions, Step, conformance

RULES = """def_start event A event B event C def_end
rule_start
R1 when A then B within 5 seconds
R2 when A then not B within 10 seconds
R3 when C then B
rule_end
priority_start R3 > R2 priority_end
"""
SPEC = parse(RULES)
STEPS = [Step(0.0, event="A")]
LOGGED = RunOptions(
    semantics=HedgeSemantics.NESTED,
    unknown=Unknowns.UNDETERMINED,
    untimed=Untimed.IMMEDIATE,
    priorities=(("R1", "R2"),),
    priority_semantics=PrioritySemantics.CONFLICT_AWARE,
    priority_lead=2.5,
    line=4,
)


def log(options: RunOptions | None = LOGGED, **more: object) -> Recording:
    return Recording(STEPS, source="audit.jsonl", audit=True, options=options, **more)  # type: ignore[arg-type]


def test_a_written_trace_is_judged_by_the_defaults_and_the_files_priorities() -> None:
    choice = conformance.choose_reading(SPEC, Recording(STEPS, source="t.jsonl"), conformance.Given())
    assert choice.reading == Reading(priorities=(("R3", "R2"),))
    assert (choice.from_audit, choice.notes, choice.warnings) == ([], [], [])


def test_an_audit_log_supplies_every_option_not_given_and_says_which() -> None:
    choice = conformance.choose_reading(SPEC, log(), conformance.Given())
    assert choice.reading == Reading(
        semantics=HedgeSemantics.NESTED,
        untimed=Untimed.IMMEDIATE,
        priorities=(("R1", "R2"), ("R3", "R2")),
        priority_semantics=PrioritySemantics.CONFLICT_AWARE,
        priority_lead=2.5,
    )
    assert choice.from_audit == ["semantics", "priorities", "priority_semantics", "priority_lead", "untimed"]


def test_what_is_given_wins_over_the_log_and_is_not_said_to_come_from_it() -> None:
    given = conformance.Given(
        semantics=HedgeSemantics.LAST_WINS,
        priorities=("R1 > R3",),
        priority_lead=0.0,  # given as 0: not the log's 2.5
        untimed=3.0,
    )
    choice = conformance.choose_reading(SPEC, log(), given)
    assert choice.reading.semantics is HedgeSemantics.LAST_WINS
    assert choice.reading.priorities == (("R1", "R3"), ("R3", "R2"))  # the log's R1 > R2 is not added
    assert (choice.reading.priority_lead, choice.reading.untimed) == (0.0, 3.0)
    assert choice.reading.priority_semantics is PrioritySemantics.CONFLICT_AWARE  # the log's
    assert choice.from_audit == ["priority_semantics"]


def test_a_log_without_options_is_judged_by_the_defaults_and_said() -> None:
    choice = conformance.choose_reading(SPEC, log(None), conformance.Given(untimed=Untimed.IMMEDIATE))
    assert choice.reading == Reading(untimed=Untimed.IMMEDIATE, priorities=(("R3", "R2"),))
    assert choice.from_audit == []
    assert choice.notes == [
        "the audit log records no options (a Manager from before they were recorded): "
        "options not given here are the defaults"
    ]


def test_logged_priorities_over_rules_no_longer_there_are_left_out_and_noted() -> None:
    logged = RunOptions(priorities=(("R1", "R2"), ("R9", "R1"), ("R2", "Gone")), line=4)
    choice = conformance.choose_reading(SPEC, log(logged), conformance.Given())
    assert choice.reading.priorities == (("R1", "R2"), ("R3", "R2"))
    assert (
        choice.notes
        == [
            "priorities of the log over rules not in these rules, ignored: R2 > Gone, R9 > R1"  # sorted, as a record is read
        ]
    )


def test_the_warnings_say_when_the_verdicts_may_not_be_the_runs() -> None:
    logged = RunOptions(unknown=Unknowns.FALSE, line=7)
    recording = log(logged, options_differ=True, decision_semantics={"nested": 2, "last-wins": 1})
    choice = conformance.choose_reading(SPEC, recording, conformance.Given())
    assert choice.warnings == [
        "the log has runs with different options: those of the last (line 7) are used",
        "the run read a condition over a measure with no value as false (unknown=false); "
        "the reference semantics leaves such a firing undetermined, so verdicts may differ",
        "the log's decisions were made with semantics nested (2 decisions); judged with last-wins",
    ]
    given = conformance.Given(semantics=HedgeSemantics.NESTED)
    choice = conformance.choose_reading(SPEC, log(logged, decision_semantics={"last-wins": 1}), given)
    assert choice.warnings[-1] == (
        "the log's decisions were made with semantics last-wins (1 decision); "
        "judged with nested (given on the command line)"
    )


def test_options_that_differ_are_no_warning_when_none_is_taken_from_the_log() -> None:
    given = conformance.Given(
        semantics=HedgeSemantics.NESTED,
        priorities=("R1 > R2",),
        priority_semantics=PrioritySemantics.CANCEL,
        priority_lead=1.0,
        untimed=Untimed.NONE,
    )
    choice = conformance.choose_reading(SPEC, log(options_differ=True), given)
    assert choice.from_audit == [] and choice.warnings == []


@pytest.mark.parametrize(
    ("given", "message", "where", "hint"),
    [
        (["R1 > Rx1"], "no rule named 'Rx1' in <string>", "--priority 'R1 > Rx1'", "did you mean 'R1'?"),
        (
            ["R1 > Zzz"],
            "no rule named 'Zzz' in <string>",
            "--priority 'R1 > Zzz'",
            "the rules are R1, R2, R3",
        ),
        (["R1 >"], "malformed priority `R1 >`", "--priority 'R1 >'", None),
        (
            ["R2 > R2"],
            "rule 'R2' is declared above itself",
            "--priority",
            "a priority orders two different rules",
        ),
        (["R2 > R3"], "the priorities go round in a circle: R3 > R2 > R3", "--priority", "drop one of them"),
    ],
)
def test_given_priorities_that_cannot_hold_are_user_errors(
    given: list[str], message: str, where: str, hint: str | None
) -> None:
    with pytest.raises(UserError) as e:
        conformance.judged_priorities(SPEC, given)
    assert message in str(e.value) and e.value.where == where
    if hint is not None:
        assert hint in e.value.hint


def test_logged_priorities_that_clash_with_the_files_name_the_log_line() -> None:
    logged = RunOptions(priorities=(("R2", "R3"),), line=9)
    with pytest.raises(UserError) as e:
        conformance.choose_reading(SPEC, log(logged), conformance.Given())
    assert e.value.where == "audit.jsonl:9"
    assert (
        e.value.hint
        == "these are the audit log's priorities with the rule file's: choose others with --priority"
    )
