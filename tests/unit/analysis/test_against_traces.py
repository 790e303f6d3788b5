"""Findings a hand-made trace refutes: for each rule set, a trace that meets every rule (in
the analysis's sense: a missed or refused item made up for by its ``otherwise``) exists, so
no conflict may be reported. Found by a hostile tester; each trace is judged by the
reference semantics here, so the test fails if the trace stops being a counter-example."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.analysis.witness import final_breaches
from cosleec.lang import load
from cosleec.semantics import Options, Step, judge

from .support import run, sleec, subjects

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
    assert not final_breaches(spec, judge(spec, trace, Options())), "the trace is no counter-example"
    report = run(tmp_path, rules, checks="vacuous-conflict")
    assert subjects(report, "vacuous-conflict") == set()


def test_a_conflict_a_declared_priority_settles_is_left_to_it(tmp_path: Path) -> None:
    """The runtime cancels R2 while R1 is active (cancel semantics): A then B conforms, so no
    conflict or blocked purpose may be shown as proved; the analysis says it left them."""
    rules = "R1 when A then B within 10 seconds\nR2 when A then not B within 10 seconds"
    purpose = "purpose_start p1 exists A purpose_end"
    report = run(tmp_path, rules, purpose, priorities=frozenset({("R1", "R2")}), allow_unknown=True)
    assert report.findings == []  # the runtime conflict is settled too
    assert any("left to the declared priority R1 > R2" in u for u in report.unknown)
    spec = load(tmp_path / "rules.sleec")
    trace = [Step(0, "A"), Step(1, "B"), Step(100)]
    j = judge(spec, trace, Options(priorities=frozenset({("R1", "R2")})))
    assert j.conforms
