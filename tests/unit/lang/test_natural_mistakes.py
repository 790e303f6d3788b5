"""Issue 33, item 3: a newcomer's natural first guesses get a message about what they meant.

Each case pins the message's phrase (the shared spec, /tmp/briefs/phrases.md: the tutorial's
tests rely on the same words), the code, the line and column, and the fix in the hint.
"""

from __future__ import annotations

import pytest

from cosleec.lang import analyse

DEFS = (
    "def_start\n  event A\n  event B\n  event C\n  event RecordVideo\n  event RaiseAlarm\n"
    "  measure m: boolean\n  measure n: numeric\n  constant K = 3\ndef_end\n"
)


def rules(*lines: str) -> str:
    """A file of DEFS and ``lines`` as its rule block: the first rule is on line 12."""
    return DEFS + "rule_start\n" + "".join(f"  {x}\n" for x in lines) + "rule_end\n"


@pytest.mark.parametrize(
    ("rule", "code", "col", "phrase", "fix"),
    [
        (
            "R1 when A then not RecordVideo for 10 minutes",
            "for-duration",
            34,
            "durations are written `within 10 minutes`",
            "write `not RecordVideo within 10 minutes`",
        ),
        (
            "R1 when A then B for 2 hours",
            "for-duration",
            20,
            "durations are written `within 2 hours`",
            "write `B within 2 hours`",
        ),
        (
            "R1 when A and m == false then B",
            "double-equals",
            19,
            "`=` compares",
            "write `m = false`, or `not m`",
        ),
        ("R1 when A and n == 3 then B", "double-equals", 19, "`=` compares", "write `n = 3`"),
        ("R1 when A and {m} == true then B", "double-equals", 21, "`=` compares", "write `{m} = true`"),
        ("R1: when A then B", "rule-colon", 5, "a rule's name is followed by `when`", "write `R1 when"),
        ("R1 when A and n != 3 then B", "not-equals", 19, "`<>` means not equal", "`a <> b`"),
        ("R1 when A and m && n > 1 then B", "operator-and", 19, "write `and`", "`and` for `&&`"),
        ("R1 when {m} then B", "trigger-condition", 11, "a rule is triggered by one event", "when Event and"),
        ("R1 when (A or C) then B", "trigger-condition", 11, "a rule is triggered by one event", "one rule"),
        ("R1 when A and {{m} or {m}} then B", "braces-group", 17, "braces mark one measure", "parentheses"),
        (
            "R1 when A then B immediately unless m",
            "stray-word",
            20,
            "is read as the name of a new rule",
            "remove",
        ),
    ],
)
def test_a_natural_mistake_is_named_where_it_is(
    rule: str, code: str, col: int, phrase: str, fix: str
) -> None:
    result = analyse(rules(rule), "r.sleec")
    first = result.errors[0]
    assert (first.code, first.span.line, first.span.col) == (code, 12, col), result.render()
    assert phrase in first.message and first.hint is not None and fix in first.hint
    assert first.render(result.source).startswith(f"r.sleec:12:{col}: error: ")


def test_a_constant_without_value_and_a_deadline_without_unit_say_so() -> None:
    defs = DEFS.replace("  constant K = 3\n", "  constant K\n  constant L = 2\n")
    (err,) = analyse(defs + "rule_start\n  R1 when A then B\nrule_end\n").errors
    assert (err.code, err.span.line, err.span.col) == ("constant-value", 9, 12)
    assert err.hint == "give it one: `constant K = 5`"
    text = rules("R1 when A then B within K", "R2 when A then C")
    (err,) = analyse(text).errors
    assert (err.code, err.span.line, err.span.col) == ("missing-unit", 12, 20)
    assert "`within K` has no time unit" in err.message and "`R2`" in err.message


def test_a_rule_name_at_the_start_of_its_line_keeps_the_plain_message() -> None:
    # `R2 B when` : R2 really is a rule's name; the mistake is the word after it
    (err,) = analyse(rules("R1 when A then B", "R2 wen A then C")).errors
    assert err.code == "syntax" and err.hint == "did you mean `when`?"


def test_otherwise_after_an_untimed_response_names_the_otherwise() -> None:
    # a SLEEC-TK file (bare measure `m`) whose only LEGOS syntax is the forgotten deadline
    result = analyse(rules("R1 when A and m then B otherwise C"), "r.sleec")
    (err,) = result.errors
    assert (err.code, err.span.line, err.span.col) == ("mixed-dialect", 12, 36)  # at `C`, after `otherwise`
    assert err.message.startswith("`otherwise` needs a deadline")
    assert err.hint == "write `then B within 5 minutes otherwise C`"
    assert "untimed-otherwise" not in [d.code for d in result.diagnostics]  # said once, as the error
    # alone, it is LEGOS's reading (a warning), with the same words and fix
    alone = analyse(rules("R1 when A then B otherwise C"))
    (warn,) = [d for d in alone.diagnostics if d.code == "untimed-otherwise"]
    assert (
        "`otherwise` needs a deadline" in warn.message
        and warn.hint == "write `then B within 5 minutes otherwise C`"
    )
    # with real LEGOS syntax elsewhere, the TK construct is still the one blamed
    legos = analyse(rules("R1 when A and {m} and n > 1 then B otherwise C"))
    assert legos.errors and all(e.code == "mixed-dialect" and e.span.col < 36 for e in legos.errors)


def test_an_untimed_obligation_in_an_otherwise_is_warned_about() -> None:
    result = analyse(rules("R1 when A then B within 5 minutes otherwise RaiseAlarm"), "r.sleec")
    (warn,) = result.diagnostics
    assert (warn.code, warn.severity.value, warn.span.line, warn.span.col) == (
        "untimed-fallback",
        "warning",
        12,
        47,
    )
    assert "can never be violated" in warn.message
    assert warn.hint is not None and warn.hint.startswith("write `otherwise RaiseAlarm within 1 minutes`")
    assert result.ok  # a warning: the file still loads
    for fine in (
        "R1 when A then B within 5 minutes otherwise RaiseAlarm within 1 minutes",
        "R1 when A then B within 5 minutes otherwise not RaiseAlarm",  # a prohibition: another matter
        "R1 when A then B within 5 minutes otherwise RaiseAlarm eventually",
        "R1 when A then B within 5 minutes",
    ):
        assert not analyse(rules(fine)).diagnostics, fine
    # every untimed obligation of the fallback, not only the first
    both = analyse(
        rules("R1 when A then B within 5 minutes otherwise {RaiseAlarm and C within 1 seconds and B}")
    )
    assert [(d.code, d.span.col) for d in both.diagnostics] == [
        ("untimed-fallback", 48),
        ("untimed-fallback", 86),
    ]


@pytest.mark.parametrize(
    ("written", "shown", "fix"),
    [
        ("battery < 20", "`battery < 20`", "when SomeEvent and battery < 20 then"),
        ("battery >= 20", "`battery >= 20`", "when SomeEvent and battery >= 20 then"),
        ("battery == 20", "`battery == ...`", "when SomeEvent and battery = ... then"),
    ],
)
def test_a_condition_where_the_trigger_goes_is_said_so(written: str, shown: str, fix: str) -> None:
    text = (
        "def_start\n  event Dock\n  measure battery: numeric\ndef_end\n"
        f"rule_start\n  R1 when {written} then Dock\nrule_end\n"
    )
    (d,) = analyse(text, "r.sleec").errors
    assert (d.code, d.span.line, d.span.col) == ("trigger-condition", 6, 11)
    assert shown in d.message and "comes after the event" in d.message
    assert d.hint is not None and fix in d.hint


def test_a_duration_after_for_is_named_in_the_paper_notation_too() -> None:
    (d,) = analyse("R2: WHEN EnterRoom THEN not RecordVideo for 10 minutes\n", "p.txt").errors
    assert (d.code, d.span.line, d.span.col) == ("for-duration", 1, 41)
    assert "durations are written `within 10 minutes`" in d.message
    assert (
        d.hint
        == "write `not RecordVideo within 10 minutes` (it must not happen within that time of the trigger)"
    )
    # a rule named `for` in the paper notation is no mistake of this kind
    assert [e.code for e in analyse("R1: WHEN A THEN B\nfor: WHEN C THEN D\n", "p.txt").errors] == []
