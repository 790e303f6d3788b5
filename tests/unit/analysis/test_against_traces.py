"""Findings a hand-made trace refutes: for each rule set, a trace that meets every rule (in
the analysis's sense: a missed or refused item made up for by its ``otherwise``) exists, so
no conflict may be reported. Found by a hostile tester; each trace is judged by the
reference semantics here, so the test fails if the trace stops being a counter-example."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.analysis.witness import final_breaches
from cosleec.lang import Reading, load
from cosleec.semantics import Step, judge

from .support import analyse, run, sleec, subjects

CASES = {
    # an obligation with an `else` is never refused: its alternative C meets it
    "else-is-never-refused": (
        "R1 when A then B within 10 seconds otherwise { D within 0 seconds } else C within 10 seconds\n"
        "R2 when A then not B within 10 seconds\n"
        "R3 when A then not D within 20 seconds",
        [Step(0, "A"), Step(1, "C"), Step(100)],
    ),
    # R2's prohibition, broken at 0.5 and made up for by C, refuses nothing after (the other
    # order, A before D, is a real situational conflict: R2 then refuses R1 at once)
    "a-broken-prohibition-refuses-nothing": (
        "R4 when D then A within 5 seconds\n"
        "R2 when D then not B within 100 seconds otherwise C within 50 seconds\n"
        "R1 when A then B within 10 seconds otherwise E within 0 seconds\n"
        "R3 when A then not E within 1000 seconds",
        [Step(0, "D"), Step(0.5, "B"), Step(1, "C"), Step(2, "A"), Step(3, "B"), Step(2000)],
    ),
    # a window that closed at once starts its otherwise at the trigger step: C at the same instant counts
    "otherwise-after-a-negative-deadline": (
        "R1 when A and (t < 0) then B within t seconds otherwise C within 0 seconds",
        [Step(0, "A", {"t": -1}), Step(0, "C"), Step(10)],
    ),
    # a deadline longer than the reference reads (1e10 s) makes the response impose nothing
    "a-deadline-out-of-range": (
        "R1 when A then B within 1 seconds\nR2 when A then not B within 200000 days",
        [Step(0, "A"), Step(0.5, "B"), Step(10)],
    ),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_no_conflict_where_a_trace_meets_every_rule(tmp_path: Path, name: str) -> None:
    rules, trace = CASES[name]
    spec = load(tmp_path.joinpath("x.sleec").write_text(sleec(rules)) and tmp_path / "x.sleec")
    assert not final_breaches(spec, judge(spec, trace, Reading())), "the trace is no counter-example"
    report = run(tmp_path, rules, checks="vacuous-conflict")
    assert subjects(report, "vacuous-conflict") == set()


def test_a_conflict_a_declared_priority_settles_is_settled(tmp_path: Path) -> None:
    """The runtime cancels R2 while R1 is active (cancel semantics): A then B conforms, so no
    conflict or blocked purpose may be shown; the encoding models the cancellation, so that
    is proved, not left to a note."""
    rules = "R1 when A then B within 10 seconds\nR2 when A then not B within 10 seconds"
    purpose = "purpose_start p1 exists A purpose_end"
    report = run(tmp_path, rules, purpose, priorities=frozenset({("R1", "R2")}))
    assert report.findings == []  # the runtime conflict is settled too
    assert report.unknown == []
    spec = load(tmp_path / "rules.sleec")
    trace = [Step(0, "A"), Step(1, "B"), Step(100)]
    j = judge(spec, trace, Reading(priorities=frozenset({("R1", "R2")})))
    assert j.conforms


HEAD = "def_start event A event E event F event G event X measure safe : boolean def_end\n"
REFUSABLE = (
    "R1 when A then E within 10 seconds otherwise F within 2 seconds\n"
    "R2 when X then not E within 100 seconds\n"
    "R3 when A then not F within [5 seconds, 100 seconds]\n"
    "R5 when E then G within 1 seconds\n"
    "R6 when A then not G within 20 seconds"
)
# X, which no rule asks for, lets R2 refuse R1 at once: its fallback F is then owed in [0, 2]
REFUSED_EARLY = [Step(0, "X"), Step(0, "A"), Step(1, "F"), Step(200)]


def _spec(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "rules.sleec"
    path.write_text(text)
    return path


def test_an_occurrence_no_rule_asks_for_can_refuse_early_and_meet_every_rule(tmp_path: Path) -> None:
    """Found by a hostile tester: the unfolding must offer the trigger of a refusing prohibition."""
    path = _spec(
        tmp_path, HEAD + f"rule_start\n{REFUSABLE}\nrule_end\npurpose_start P1 exists A purpose_end\n"
    )
    spec = load(path)
    assert not final_breaches(spec, judge(spec, REFUSED_EARLY, Reading()))
    report = analyse(path, ["vacuous-conflict", "purpose-blocked"])
    assert report.findings == []


def test_a_refusal_can_break_the_rule_the_others_seem_to_imply(tmp_path: Path) -> None:
    rules = (
        "R1 when A then E within 10 seconds otherwise F within 2 seconds\n"
        "R2 when A then F within [11 seconds, 12 seconds]\n"
        "R3 when X then not E within 100 seconds"
    )
    path = _spec(tmp_path, HEAD + f"rule_start\n{rules}\nrule_end\n")
    spec = load(path)
    trace = [Step(0, "X"), Step(0, "A"), Step(11, "F"), Step(200)]
    breached = {v.rule for v in final_breaches(spec, judge(spec, trace, Reading()))}
    assert breached == {"R1"}  # the others are met, R1 is not: R1 is not redundant
    assert "R1" not in subjects(analyse(path, "redundant"), "redundant")


def test_a_for_relation_holds_for_the_values_an_otherwise_reads(tmp_path: Path) -> None:
    """`safe` stays false for 100 s after A, so R1's fallback F is owed: the concern cannot arise."""
    text = HEAD + (
        "rule_start\n"
        "R1 when A then E within 5 seconds otherwise {F within 1 seconds unless {safe}}\n"
        "R5 when E then G within 1 seconds\n"
        "R6 when A then not G within 20 seconds\n"
        "rule_end\n"
        "concern_start c1 when A then not F within 10 seconds concern_end\n"
        "relation_start when A then (not {safe}) for 100 seconds relation_end\n"
    )
    assert subjects(analyse(_spec(tmp_path, text), "concern-raised"), "concern-raised") == set()


def test_the_event_that_ends_an_until_is_offered(tmp_path: Path) -> None:
    """A@0 (p false), C@1 ends the until, B@2 with p fires R1, C@3 meets it."""
    text = (
        "def_start event A event B event C measure p : boolean def_end\n"
        "rule_start R1 when B and {p} then C within 5 seconds rule_end\n"
        "relation_start happenBefore A B\n when A then (not {p}) until C relation_end\n"
    )
    assert analyse(_spec(tmp_path, text), "vacuous-conflict").findings == []


def test_a_prohibition_inside_an_otherwise_that_could_refuse_is_modelled_so_no_note(
    tmp_path: Path,
) -> None:
    """Once the encoding's known limit (a prohibition inside an otherwise did not refuse, and
    the file got a note naming the rule); now modelled (test_fallback_refusals.py), so no note.
    D can be done on time: no conflict either way."""
    rules = (
        "R1 when A then B within 10 seconds otherwise E within 1 seconds\n"
        "R2 when A then D within 5 seconds otherwise { not B within 20 seconds }"
    )
    report = run(tmp_path, rules, checks="vacuous-conflict")
    assert report.unknown == [] and report.findings == []


def test_an_obligation_without_fallback_refused_at_once_is_broken_even_if_its_event_occurs(
    tmp_path: Path,
) -> None:
    """RP forbids B for RY's whole window when X fires: RY is refused at once (a breach); B
    breaking RP, made up for by C, does not undo it. Found by a hostile tester."""
    rules = "RP when A then not B within 100 seconds otherwise C within 5 seconds\nRY when A then B within 5 seconds"
    path = tmp_path / "rules.sleec"
    path.write_text(
        sleec(
            rules,
            "concern_start c1 when A then C within 10 seconds concern_end\npurpose_start p1 exists A purpose_end",
        )
    )
    spec = load(path)
    trace = [Step(0, "A"), Step(1, "B"), Step(2, "C"), Step(200)]
    assert {v.rule for v in final_breaches(spec, judge(spec, trace, Reading()))} == {"RY"}
    report = analyse(path, ["vacuous-conflict", "purpose-blocked", "concern-raised"])
    assert subjects(report, "vacuous-conflict") == {"RP", "RY"}
    assert subjects(report, "purpose-blocked") == {"p1"}
    assert subjects(report, "concern-raised") == set()


def test_an_event_only_forbidden_is_still_an_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from cosleec.cli.main import main

    path = tmp_path / "rules.sleec"
    path.write_text(sleec("R4 when A then not B within 1 seconds\nRH when B then C within 1 seconds"))
    mapping = tmp_path / "m.yaml"
    mapping.write_text("events:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n")
    assert main(["analyse", "--check", "unproduced-input", "--mapping", str(mapping), str(path)]) == 1
    assert "event `B` is read by RH but the mapping never produces it" in capsys.readouterr().out
