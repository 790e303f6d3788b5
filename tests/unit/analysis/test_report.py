"""The one Finding builder (analysis/report.py), built alone: what it adds to what a check says --
the file, the cause's rules and notes, the proof status of the encoding that decided it."""

from __future__ import annotations

from cosleec.analysis import BOUNDED, PROVED, Finding, Witness
from cosleec.analysis.encoding import Encoding
from cosleec.analysis.report import finding, notes, span_of
from cosleec.lang import Reading, Severity
from cosleec.lang import ast as A

R1, R2, R3 = (A.Span(n, 1, n, 9) for n in (2, 3, 4))
REL1, REL2 = A.Span(8, 1, 8, 20), A.Span(9, 1, 9, 20)
HERE = A.Span(3, 5, 3, 7)


def rule(name: str, trigger: str, owes: str, span: A.Span) -> A.Rule:
    return A.Rule(name, A.Trigger(trigger), A.Response((A.ResponseItem(A.Occurrence(owes)),)), span=span)


SPEC = A.Specification(
    (A.EventDecl("E"), A.EventDecl("F")),
    (rule("R1", "E", "F", R1), rule("R2", "F", "E", R2), rule("R3", "E", "E", R3)),
    relations=(
        A.EventRelation("witness", "E", "F", span=REL1),
        A.EventRelation("equal", "E", "F", span=REL2),
    ),
    path="rules.sleec",
)


def encoding(bound: int) -> Encoding:
    """An encoding of SPEC unfolded from an E at ``bound``: R1 owes F, whose R2 owes E, ... --
    complete only when the bound holds the whole chain of demands (never: it feeds itself)."""
    enc = Encoding(SPEC, {}, Reading(), bound)
    enc.probe("E")
    enc.unfold()
    return enc


def test_what_every_finding_gets_the_same_way() -> None:
    f = finding(
        SPEC, "redundant", "R2", "rule R2 is redundant", span=HERE, hint="remove it", cause=("R1", "R3")
    )
    assert f == Finding(
        code="redundant",
        subject="R2",
        message="rule R2 is redundant",
        path="rules.sleec",
        span=HERE,
        rules=("R1", "R3"),
        related=(("R1 is part of the cause", R1), ("R3 is part of the cause", R3)),
        hint="remove it",
        status=PROVED,
        bound=None,
        severity=Severity.WARNING,
    )
    assert f.extra == {} and f.situation == "" and f.witness is None


def test_the_subject_gets_no_note_when_it_is_part_of_its_own_cause() -> None:
    f = finding(
        SPEC, "vacuous-conflict", "R2", "m", span=R2, hint="h", cause=("R1", "R2", "relation 2"), itself="R2"
    )
    assert f.rules == ("R1", "R2", "relation 2")
    assert f.related == (("R1 is part of the cause", R1), ("relation 2 is part of the cause", REL2))


def test_rules_and_notes_can_be_said_apart_from_the_cause() -> None:
    note = (("R3 forbids `E` here", HERE),)
    f = finding(
        SPEC, "dead-rule", "R1", "m", span=R1, hint="h", cause=("relation 1",), rules=("R1", "relation 1")
    )
    assert f.rules == ("R1", "relation 1") and f.related == (("relation 1 is part of the cause", REL1),)
    g = finding(SPEC, "runtime-conflict", "R1/R3", "m", span=R1, hint="h", cause=("R1", "R3"), related=note)
    assert g.rules == ("R1", "R3") and g.related == note


def test_the_status_is_the_deciding_encodings() -> None:
    small, large = encoding(1), encoding(3)
    assert not small.complete and not large.complete  # R1 and R2 feed each other
    f = finding(SPEC, "redundant", "R1", "m", span=R1, hint="h", decided_by=small)
    assert (f.status, f.bound, f.proof) == (BOUNDED, 1, "up to bound 1")
    assert finding(SPEC, "redundant", "R1", "m", span=R1, hint="h", decided_by=large).bound == 3
    large.complete = True  # the unfolding held every demand: unsat is a proof
    f = finding(SPEC, "redundant", "R1", "m", span=R1, hint="h", decided_by=large)
    assert (f.status, f.bound) == (PROVED, None)


def test_what_a_check_says_besides_is_kept() -> None:
    w = Witness(steps=(), timeline=("t=0: E",), confirmed=True)
    f = finding(
        SPEC,
        "situational-conflict",
        "R1",
        "m",
        span=R1,
        hint="h",
        severity=Severity.ERROR,
        situation="E at t=0",
        witness=w,
        extra={"triggers": ["R1"]},
    )
    assert (f.severity, f.situation, f.witness, f.extra) == (
        Severity.ERROR,
        "E at t=0",
        w,
        {"triggers": ["R1"]},
    )
    g = finding(SPEC, "situational-conflict", "R1", "m", span=R1, hint="h", extra={"triggers": ["R1"]})
    assert g.to_json()["triggers"] == ["R1"]  # the extra fields are the JSON's too


def test_each_finding_has_an_extra_of_its_own() -> None:
    a = finding(SPEC, "redundant", "R1", "m", span=R1, hint="h")
    b = finding(SPEC, "redundant", "R2", "m", span=R2, hint="h")
    a.extra["x"] = 1
    assert b.extra == {}


def test_where_a_rule_or_relation_is() -> None:
    assert [span_of(SPEC, n) for n in ("R1", "R3", "relation 1", "relation 2")] == [R1, R3, REL1, REL2]
    assert span_of(SPEC, "R9") == A.NO_SPAN
    assert notes(SPEC, ("R2", "relation 1"), skip="relation 1") == (("R2 is part of the cause", R2),)
    assert notes(SPEC, ()) == ()
