"""Each check of ``cosleec analyse`` on small files whose answer is known, both ways.

The boundary cases are chosen so that a one-character change in the encoding (an open
window instead of a closed one, ``<`` for ``<=``, an ``otherwise`` started at the trigger, a
trigger that fulfils its own response, integers for reals) changes the answer.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest

from cosleec.analysis import BOUNDED, PROVED, Coverage, FileReport, Finding, Settings, analyse_file
from cosleec.cli.main import main
from cosleec.lang import Severity

from .support import cli_json, of, run, sleec, subjects, values, write

# ---------------------------------------------------------------------------- vacuous conflict


def test_an_obligation_and_a_longer_prohibition_conflict_both_ways(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A then not B within 10 seconds",
        checks="vacuous-conflict",
    )
    found = of(r, "vacuous-conflict")
    assert set(found) == {"R1", "R2"}
    for f in found.values():
        assert f.rules == ("R1", "R2")
        assert f.status == PROVED and f.bound is None
        assert f.severity == Severity.ERROR
    assert found["R1"].span.line == 3 and found["R2"].span.line == 4
    assert "because of R2" in found["R1"].message and "because of R1" in found["R2"].message


@pytest.mark.parametrize(
    ("owed", "forbidden", "conflict"),
    [
        ("B within 5 seconds", "not B within 10 seconds", True),
        ("B within 5 seconds", "not B within 5 seconds", True),  # closed windows: B at 5 is forbidden
        ("B within 5 seconds", "not B within 4 seconds", False),  # B at 4.5
        ("B within [6 seconds, 7 seconds]", "not B within 5 seconds", False),
        ("B within [5 seconds, 5 seconds]", "not B within 5 seconds", True),  # lower bound closed too
        ("B within [5 seconds, 5 seconds]", "not B within 4 seconds", False),
        ("B within [2 seconds, 9 seconds]", "not B within 10 seconds", True),
        ("B within 0 seconds", "not B", True),  # untimed `not B`: the trigger's instant
        ("B within 5 seconds", "not B", False),
        ("B within 1 seconds", "not B", False),  # B at 0.5: untimed `not B` is one instant
        ("B within 1 minutes", "not B within 60 seconds", True),  # units
        ("B within 1 minutes", "not B within 59 seconds", False),
        ("B eventually", "not B eventually", True),
        ("B eventually", "not B within 100 seconds", False),
        ("B", "not B within 100 seconds", False),  # untimed: must happen some time, so later
    ],
)
def test_vacuous_conflict_windows(tmp_path: Path, owed: str, forbidden: str, conflict: bool) -> None:
    r = run(tmp_path, f"R1 when A then {owed}\nR2 when A then {forbidden}", checks="vacuous-conflict")
    assert subjects(r, "vacuous-conflict") == ({"R1", "R2"} if conflict else set())


def test_untimed_zero_reads_an_untimed_obligation_as_the_same_instant(tmp_path: Path) -> None:
    rules = "R1 when A then B\nR2 when A then not B within 5 seconds"
    assert subjects(run(tmp_path, rules, checks="vacuous-conflict"), "vacuous-conflict") == set()
    r = run(tmp_path, rules, checks="vacuous-conflict", untimed=0.0)
    assert subjects(r, "vacuous-conflict") == {"R1", "R2"}
    # a positive untimed deadline moves B past the prohibition only when it is longer
    assert subjects(run(tmp_path, rules, checks="vacuous-conflict", untimed=5.0), "vacuous-conflict") == {
        "R1",
        "R2",
    }
    assert subjects(run(tmp_path, rules, checks="vacuous-conflict", untimed=5.5), "vacuous-conflict") == set()


NO_B = "relation_start\nmeasure invariant {m}\nforbid B {m}\nrelation_end"  # B never occurs


@pytest.mark.parametrize(("forbid_c", "conflict"), [(6, False), (7, True)])
def test_otherwise_starts_at_the_deadline(tmp_path: Path, forbid_c: int, conflict: bool) -> None:
    """B cannot occur (the relations), so the fallback C is owed in [5, 7]: a prohibition of
    C for 6 s leaves room (C at 6.5), one for 7 s does not. An otherwise started at the
    trigger ([0, 2]) would conflict with both, one started after the window never."""
    r = run(
        tmp_path,
        f"R1 when A then B within 5 seconds otherwise C within 2 seconds\nR3 when A then not C within {forbid_c} seconds",
        NO_B,
        checks="vacuous-conflict",
    )
    found = of(r, "vacuous-conflict")
    if conflict:
        assert set(found) == {"R1", "R3"}
        assert all(f.rules == ("R1", "R3", "relation 1", "relation 2") for f in found.values())
    else:
        assert found == {}


def test_an_otherwise_is_owed_only_when_its_obligation_is_missed(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds otherwise C within 2 seconds\nR3 when A then not C within 7 seconds",
        checks="vacuous-conflict",
    )
    assert r.findings == []  # B on time: no C owed


OTHERWISE_REFUSED = (
    "R1 when A then B within 5 seconds otherwise C within 2 seconds\n"
    "R2 when A then not B within 10 seconds\nR3 when A then not C within 6 seconds"
)


def test_the_reference_refuses_at_once_an_obligation_whose_window_is_forbidden(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ground truth for the xfail below: R2 forbids B for R1's whole window, so the
    reference semantics refuses B at 0 and starts the otherwise then: C owed in [0, 2], which
    R3 forbids. No trace with an A conforms."""
    rules = write(tmp_path, OTHERWISE_REFUSED)
    for c_at in (1, 3, 5.5, 6.5, 8):
        trace = tmp_path / "t.jsonl"
        trace.write_text(f'{{"t": 0, "event": "A"}}\n{{"t": {c_at}, "event": "C"}}\n{{"t": 30}}\n')
        assert main(["conforms", str(rules), str(trace)]) == 1, c_at
    assert "R1 (default, otherwise) at 0 s: C in [0, 2]" in capsys.readouterr().out


def test_an_otherwise_after_a_refusal_starts_at_the_refusal(tmp_path: Path) -> None:
    r = run(tmp_path, OTHERWISE_REFUSED, checks="vacuous-conflict")
    assert subjects(r, "vacuous-conflict") == {"R1", "R2", "R3"}


def test_an_occurrence_counts_only_after_the_trigger_in_causal_order(tmp_path: Path) -> None:
    """A owes B and C at its own instant, C forbids B at its instant: A, B, C in that order
    meets every rule, because the B before C is not after C."""
    r = run(
        tmp_path,
        "R1 when A then B within 0 seconds\nR2 when C then not B within 0 seconds\nR3 when A then C within 0 seconds",
        checks="vacuous-conflict",
    )
    assert subjects(r, "vacuous-conflict") == set()
    # ... but when B must answer C (B after C), C's prohibition bites
    r = run(
        tmp_path,
        "R1 when C then B within 0 seconds\nR2 when C then not B within 0 seconds\nR3 when A then C within 0 seconds",
        checks="vacuous-conflict",
    )
    assert subjects(r, "vacuous-conflict") == {"R1", "R2", "R3"}
    assert of(r, "vacuous-conflict")["R3"].rules == ("R1", "R2", "R3")


def test_a_trigger_never_fulfils_its_own_response(tmp_path: Path) -> None:
    r = run(tmp_path, "R1 when A then A within 5 seconds", checks="vacuous-conflict", bound=3)
    f = of(r, "vacuous-conflict")["R1"]
    assert f.rules == ("R1",) and "its own response" in f.message
    assert f.status == BOUNDED and f.bound == 3  # every A owes a later A: no finite trace ends


def test_a_trigger_condition_is_part_of_the_conflict(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A and x then B within 5 seconds\nR2 when A then not B within 10 seconds",
        checks="vacuous-conflict",
    )
    found = of(r, "vacuous-conflict")
    assert set(found) == {"R1"}  # A without x meets both rules
    assert "with its condition" in found["R1"].message


# ---------------------------------------------------------------------------- situational conflict


def _situational(r: FileReport) -> list[Finding]:
    """The situational conflicts (their subject is the trigger that cannot be answered)."""
    found = [f for f in r.findings if f.code == "situational-conflict"]
    assert found
    return found


def test_situational_conflict_of_two_activations(tmp_path: Path) -> None:
    """A at 0 owes B in [6, 7]; an A at 2 forbids B in [2, 7]: that situation is a conflict,
    although each A alone can be answered (B at 6.5)."""
    r = run(
        tmp_path,
        "R1 when A then B within [6 seconds, 7 seconds]\nR2 when A then not B within 5 seconds",
        checks=["vacuous-conflict", "situational-conflict"],
    )
    assert subjects(r, "vacuous-conflict") == set()
    found = _situational(r)
    assert {f.rules for f in found} == {("R1", "R2")}
    for f in found:
        assert f.status == PROVED and f.subject in ("R1", "R2")
        assert f.situation.count("A at t=") == 2


def test_situational_conflict_of_one_occurrence_with_a_condition(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless y\nR2 when A and x then not B within 10 seconds",
        checks=["vacuous-conflict", "situational-conflict"],
    )
    assert subjects(r, "vacuous-conflict") == set()  # A with x and y meets both
    (f,) = _situational(r)
    assert f.rules == ("R1", "R2")
    vals = values(f.situation)
    assert vals.get("x") is True and vals.get("y", False) is False
    # when the prohibiting rule conflicts whenever it fires, that is the finding
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A and x then not B within 10 seconds",
        checks=["vacuous-conflict", "situational-conflict"],
    )
    assert subjects(r, "vacuous-conflict") == {"R2"} and subjects(r, "situational-conflict") == set()


def test_a_prohibition_that_covers_the_remaining_window_is_a_situational_conflict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A at 0 owes B in [0, 5]; C at 1, before any B, forbids B in [1, 5]: what remains of
    the window is forbidden (the reference semantics refuses the obligation), although the
    prohibition is shorter than the window."""
    rules = "R1 when A then B within 5 seconds\nR2 when C then not B within 4 seconds"
    r = run(tmp_path, rules, checks=["vacuous-conflict", "situational-conflict", "runtime-conflict"])
    assert subjects(r, "vacuous-conflict") == set()
    assert subjects(r, "runtime-conflict") == {"R1/R2"}
    assert {f.rules for f in _situational(r)} == {("R1", "R2")}
    trace = tmp_path / "t.jsonl"
    trace.write_text('{"t": 0, "event": "A"}\n{"t": 1, "event": "C"}\n{"t": 30}\n')
    assert main(["conforms", str(write(tmp_path, rules)), str(trace)]) == 1
    assert "blocked" in capsys.readouterr().out
    # a priority settles the situational conflict as well as the runtime one
    r = run(
        tmp_path,
        rules,
        checks=["situational-conflict", "runtime-conflict"],
        priorities=frozenset({("R2", "R1")}),
    )
    assert r.findings == []


TWO_TRIGGERS = (
    "def_start event A event B event C def_end\nrule_start\n"
    "R1 when A then B within 5 seconds\nR2 when C then not B within 10 seconds\nrule_end\n"
)


def test_situational_conflict_with_two_trigger_events(tmp_path: Path) -> None:
    """C at 0 forbids B in [0, 10]; A at 1 owes B in [1, 6]: no trace with that situation
    meets both rules (the reference semantics agrees, below).

    Regression: until 92a3e9d the candidate situation was one z3 model, which in a fresh
    process put C at A's instant but causally after A (B then fits between them), and this
    conflict was missed with ``--check situational-conflict`` alone."""
    path = tmp_path / "two.sleec"
    path.write_text(TWO_TRIGGERS)
    (doc,) = cli_json("--check", "situational-conflict", str(path))["files"]
    assert doc["findings"]
    assert {(f["code"], tuple(f["rules"])) for f in doc["findings"]} == {
        ("situational-conflict", ("R1", "R2"))
    }


def test_a_check_answers_the_same_whatever_else_is_checked(tmp_path: Path) -> None:
    """Regression (same cause, until 92a3e9d): the answer depended on which checks ran first."""
    path = tmp_path / "two.sleec"
    path.write_text(TWO_TRIGGERS)

    def situational(checks: str) -> list[object]:
        (doc,) = cli_json("--check", checks, str(path))["files"]
        return [f for f in doc["findings"] if f["code"] == "situational-conflict"]

    assert situational("situational-conflict") == situational("vacuous-conflict,situational-conflict")


ONE_OVERLAPS = "R1 when A then B within [5 seconds, 7 seconds]\nR2 when A then not B within 5 seconds"


def test_situational_conflict_when_one_occurrence_only_overlaps(tmp_path: Path) -> None:
    """Like [6, 7] vs 5 s (found), with [5, 7]: A at 0 owes B in [5, 7], A at 2 forbids [2, 7]."""
    r = run(tmp_path, ONE_OVERLAPS, checks="situational-conflict")
    assert {f.rules for f in r.findings if f.code == "situational-conflict"} == {("R1", "R2")}


def test_the_situation_of_the_overlapping_clauses_is_refused_by_the_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ground truth for the xfail above: after A at 0 and A at 2, no B conforms."""
    rules = write(tmp_path, ONE_OVERLAPS)
    for b_at in (None, 2.5, 5, 6, 7, 8):
        trace = tmp_path / "t.jsonl"
        b = "" if b_at is None else f'{{"t": {b_at}, "event": "B"}}\n'
        trace.write_text(f'{{"t": 0, "event": "A"}}\n{{"t": 2, "event": "A"}}\n{b}{{"t": 30}}\n')
        assert main(["conforms", str(rules), str(trace)]) == 1, b_at
    capsys.readouterr()


def test_the_situation_of_the_two_trigger_conflict_is_refused_by_the_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ground truth behind the two-trigger conflict, from the reference semantics."""
    rules = tmp_path / "two.sleec"
    rules.write_text(TWO_TRIGGERS)
    for b_at in (1, 3, 6, 11):  # B can only answer A after A
        trace = tmp_path / f"t{b_at}.jsonl"
        trace.write_text(
            f'{{"t": 0, "event": "C"}}\n{{"t": 1, "event": "A"}}\n{{"t": {b_at}, "event": "B"}}\n{{"t": 30}}\n'
        )
        assert main(["conforms", str(rules), str(trace)]) == 1, b_at
    capsys.readouterr()


# ---------------------------------------------------------------------------- redundancy


@pytest.mark.parametrize(
    ("r1", "r2", "redundant"),
    [
        ("when A then B within 5 seconds", "when A then B within 3 seconds", {"R1": ("R2",)}),
        ("when A then B within 5 seconds", "when A then B within 5 seconds", {"R1": ("R2",), "R2": ("R1",)}),
        ("when A then B within 5 seconds", "when A then B within 6 seconds", {"R2": ("R1",)}),
        ("when A then B within 5 seconds", "when A then B within [1 seconds, 3 seconds]", {"R1": ("R2",)}),
        ("when A then B within [1 seconds, 5 seconds]", "when A then B within 3 seconds", {}),  # B at 0.5
        ("when A and x then B within 5 seconds", "when A then B within 3 seconds", {"R1": ("R2",)}),
        ("when A then B within 5 seconds", "when A and x then B within 3 seconds", {}),
        ("when A then B within 5 seconds unless x", "when A then B within 5 seconds", {"R1": ("R2",)}),
        ("when A then not B within 3 seconds", "when A then not B within 5 seconds", {"R1": ("R2",)}),
        (
            "when A then not B within 5 seconds",
            "when A then not B within 5 seconds",
            {"R1": ("R2",), "R2": ("R1",)},
        ),
        ("when A then B within 5 seconds", "when C then B within 1 seconds", {}),
    ],
)
def test_redundancy(tmp_path: Path, r1: str, r2: str, redundant: dict[str, tuple[str, ...]]) -> None:
    r = run(tmp_path, f"R1 {r1}\nR2 {r2}", checks="redundant")
    found = of(r, "redundant")
    assert {k: f.rules for k, f in found.items()} == redundant
    assert all(f.status == PROVED and f.severity == Severity.WARNING for f in found.values())


def test_redundancy_through_a_chain(tmp_path: Path) -> None:
    """R2 and R3 together imply R1 (B within 2 s of A, then C within 2 s of B); neither alone does."""
    r = run(
        tmp_path,
        "R1 when A then C within 4 seconds\nR2 when A then B within 2 seconds\nR3 when B then C within 2 seconds\n"
        "R4 when A then D within 1 seconds",
        checks="redundant",
    )
    assert {k: f.rules for k, f in of(r, "redundant").items()} == {"R1": ("R2", "R3")}


# ---------------------------------------------------------------------------- concerns and purposes

CONCERN = "concern_start\nc1 when A and {m} then C within 2 seconds\nconcern_end"


@pytest.mark.parametrize(("forbid", "raised"), [(None, True), (1, True), (2, False), (3, False)])
def test_concern_raised_unless_the_rules_forbid_it(tmp_path: Path, forbid: int | None, raised: bool) -> None:
    rules = "R1 when A then B within 5 seconds"
    if forbid is not None:
        rules += f"\nR2 when A and {{m}} then not C within {forbid} seconds"
    r = run(tmp_path, rules, CONCERN, checks="concern-raised")
    found = of(r, "concern-raised")
    assert set(found) == ({"c1"} if raised else set())
    if raised:
        f = found["c1"]
        assert f.status == PROVED and f.witness is not None and f.witness.confirmed
        assert (
            f.span.line
            == sleec(rules, CONCERN).splitlines().index("c1 when A and {m} then C within 2 seconds") + 1
        )
        steps = f.witness.steps
        a = [s for s in steps if s.event == "A"]
        c = [s for s in steps if s.event == "C"]
        assert a and c and any(0 <= sc.t - sa.t <= 2 for sa in a for sc in c)


def test_an_untimed_concern_response_means_the_same_instant(tmp_path: Path) -> None:
    """Situations read untimed responses as LEGOS does, whatever ``--untimed``: C must be at
    A's instant, and a prohibition for 1 s of C forbids that."""
    extra = "concern_start\nc1 when A and {m} then C\nconcern_end"
    r = run(tmp_path, "R1 when A then not C within 1 seconds", extra, checks="concern-raised")
    assert subjects(r, "concern-raised") == set()
    r = run(tmp_path, "R1 when A then not C within 1 seconds unless {m}", extra, checks="concern-raised")
    assert subjects(r, "concern-raised") == {"c1"}


PURPOSE = "purpose_start\np1 exists A and {m} while B\npurpose_end"


def test_purpose_blocked_names_exactly_the_blocking_rule(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A and {m} then not C within 10 seconds\n"
        "R3 when A then not B within 1 seconds\nR4 when A then D within 2 seconds",
        PURPOSE,
        checks="purpose-blocked",
    )
    f = of(r, "purpose-blocked")["p1"]
    assert f.rules == ("R3",)
    assert f.status == PROVED and f.severity == Severity.ERROR
    assert "blocked by R3" in f.message


def test_purpose_blocked_by_two_rules_together(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when B then D within 0 seconds\nR2 when A then not D within 1 seconds\nR3 when A then E within 5 seconds",
        PURPOSE,
        checks="purpose-blocked",
    )
    assert of(r, "purpose-blocked")["p1"].rules == ("R1", "R2")


@pytest.mark.parametrize(
    "rules",
    [
        "R1 when A then B within 5 seconds",
        "R3 when A then not B within 1 seconds unless {m}",  # the purpose's m exempts it
        "R3 when A and {m} then not B within 0 seconds otherwise C",  # B is allowed, with a fallback
        "R3 when A then not C within 1 seconds",
    ],
)
def test_purpose_not_blocked(tmp_path: Path, rules: str) -> None:
    assert subjects(run(tmp_path, rules, PURPOSE, checks="purpose-blocked"), "purpose-blocked") == set()


def test_purpose_blocked_by_a_relation(tmp_path: Path) -> None:
    extra = (
        "purpose_start\np1 exists A while B\npurpose_end\nrelation_start\nmutualExclusive A B\nrelation_end"
    )
    r = run(tmp_path, "R1 when A then C within 5 seconds", extra, checks="purpose-blocked")
    assert of(r, "purpose-blocked")["p1"].rules == ("relation 1",)


# ---------------------------------------------------------------------------- clauses

# (defeaters as written, the same conditions over x, y) for the brute-force oracle below
CONDS = {
    "x": lambda x, y: x,
    "y": lambda x, y: y,
    "(x and y)": lambda x, y: x and y,
    "(not x)": lambda x, y: not x,
    "(x or y)": lambda x, y: x or y,
}


def _chosen(conds: list[bool], nested: bool) -> int:
    """The clause a trigger selects (0: the default), straight from the language reference §7."""
    if nested:
        k = 0
        while k < len(conds) and conds[k]:
            k += 1
        return k
    return max((i + 1 for i, c in enumerate(conds) if c), default=0)


DEFEATERS = [
    ["x", "(x and y)"],
    ["(x and y)", "x"],
    ["x", "(not x)"],
    ["x", "y"],
    ["(x or y)", "x", "(x and y)"],
    ["(x and y)", "(x or y)", "x"],
    ["x", "(not x)", "y"],
    ["y", "(x and y)", "(not x)"],
]


@pytest.mark.parametrize("nested", [False, True], ids=["last-wins", "nested"])
@pytest.mark.parametrize("conds", DEFEATERS, ids=[" | ".join(d) for d in DEFEATERS])
def test_unselectable_clauses_and_differences_agree_with_brute_force(
    tmp_path: Path, conds: list[str], nested: bool
) -> None:
    responses = "BCDE"
    rule = "R1 when A then B within 5 seconds " + " ".join(
        f"unless {c} then {responses[i + 1]} within 5 seconds" for i, c in enumerate(conds)
    )
    r = run(tmp_path, rule, checks=["unselectable-clause", "semantics-differ"], nested=nested)
    picks = {
        (xv, yv): (
            _chosen([CONDS[c](xv, yv) for c in conds], False),
            _chosen([CONDS[c](xv, yv) for c in conds], True),
        )
        for xv, yv in itertools.product([False, True], repeat=2)
    }
    selected = {p[1] if nested else p[0] for p in picks.values()}
    expected = {f"R1.{k}" for k in range(len(conds) + 1) if k not in selected}
    assert subjects(r, "unselectable-clause") == expected
    assert all(f.rules == ("R1",) and f.status == PROVED for f in r.findings)
    differ = of(r, "semantics-differ")
    assert set(differ) == ({"R1"} if any(lw != ne for lw, ne in picks.values()) else set())
    if differ:
        vals = values(differ["R1"].situation)
        xv, yv = bool(vals.get("x", False)), bool(vals.get("y", False))
        lw, ne = picks[(xv, yv)]
        assert lw != ne, differ["R1"].situation
        name = lambda k: "the default response of R1" if k == 0 else f"R1.{k}"  # noqa: E731
        assert f"last-wins selects {name(lw)} and nested selects {name(ne)}" in differ["R1"].message


@pytest.mark.parametrize(
    ("defeaters", "last_wins", "nested"),
    [
        # graded the wrong way round: the later, weaker condition always wins
        ("unless (t > 5) then C within 5 seconds unless (t > 3) then D within 5 seconds", {"R1.1"}, {"R1.1"}),
        ("unless (t > 3) then C within 5 seconds unless (t > 5) then D within 5 seconds", set(), set()),
        ("unless (t >= 3) then C within 5 seconds unless (t > 3) then D within 5 seconds", set(), set()),
        (
            "unless (t > 3) then C within 5 seconds unless (t >= 3) then D within 5 seconds",
            {"R1.1"},
            {"R1.1"},
        ),
        # last-wins: the default needs x and not x; nested: clause 2 does
        ("unless x then C within 5 seconds unless (not x) then D within 5 seconds", {"R1.0"}, {"R1.2"}),
    ],
)
def test_unselectable_clauses_over_numbers(
    tmp_path: Path, defeaters: str, last_wins: set[str], nested: set[str]
) -> None:
    rule = f"R1 when A then B within 5 seconds {defeaters}"
    assert subjects(run(tmp_path, rule, checks="unselectable-clause"), "unselectable-clause") == last_wins
    assert (
        subjects(run(tmp_path, rule, checks="unselectable-clause", nested=True), "unselectable-clause")
        == nested
    )


def test_the_trigger_condition_and_relations_restrict_the_clauses(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A and x then B within 5 seconds unless (not x) then C",
        checks="unselectable-clause",
    )
    assert subjects(r, "unselectable-clause") == {"R1.1"}
    extra = "relation_start\nmeasure invariant ({t} < 3)\nrelation_end"
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless ({t} > 5) then C",
        extra,
        checks="unselectable-clause",
    )
    assert subjects(r, "unselectable-clause") == {"R1.1"}
    extra = "relation_start\nmeasure invariant ({t} <= 5)\nrelation_end"
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless ({t} >= 5) then C",
        extra,
        checks="unselectable-clause",
    )
    assert subjects(r, "unselectable-clause") == set()
    # a trigger that can never fire is not reported clause by clause
    r = run(
        tmp_path,
        "R1 when A and x and not x then B within 5 seconds unless y then C",
        checks="unselectable-clause",
    )
    assert subjects(r, "unselectable-clause") == set()


def test_semantics_differ_on_the_firefighter_rule(tmp_path: Path) -> None:
    """Language reference §8, example 1: personNearby false, temperature > 35."""
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless x then C within 5 seconds unless (t > 35)",
        checks="semantics-differ",
    )
    f = of(r, "semantics-differ")["R1"]
    vals = values(f.situation)
    assert vals.get("x", False) is False and float(vals["t"]) > 35  # type: ignore[arg-type]
    assert "last-wins selects R1.2 and nested selects the default response of R1" in f.message
    assert f.severity == Severity.NOTE and f.witness is not None and f.witness.confirmed


def test_no_semantics_difference_with_one_defeater_or_graded_conditions(tmp_path: Path) -> None:
    for rule in (
        "R1 when A then B within 5 seconds unless x then C within 5 seconds",
        "R1 when A then B within 5 seconds unless (t < 19) then C within 5 seconds unless (t < 17) then D",
    ):
        assert subjects(run(tmp_path, rule, checks="semantics-differ"), "semantics-differ") == set()


def test_semantics_differ_witness_is_confirmed_under_nested(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless x then C within 5 seconds unless (t > 35)",
        checks="semantics-differ",
        nested=True,
    )
    f = of(r, "semantics-differ")["R1"]
    assert f.witness is not None and f.witness.confirmed


# ---------------------------------------------------------------------------- negative deadlines


@pytest.mark.parametrize(
    ("rule", "extra", "negative"),
    [
        ("R1 when A then B within d seconds", "", True),
        ("R1 when A then B within d seconds unless (d < 0) then C", "", False),
        ("R1 when A then B within d seconds unless (d <= 0) then C", "", False),
        ("R1 when A then B within d seconds unless (d < -1) then C", "", True),
        ("R1 when A and (d >= 0) then B within d seconds", "", False),  # 0 is not negative
        ("R1 when A and (d > -1) then B within d seconds", "", True),  # measures are reals: d = -0.5
        ("R1 when A and (d > 0) then B within (10 - d) seconds", "", True),
        ("R1 when A and (d > 0) then B within (10 - d) seconds unless (d > 10) then C", "", False),
        (
            "R1 when A then B within {d} seconds",
            "relation_start\nmeasure invariant ({d} >= 0)\nrelation_end",
            False,
        ),
        (
            "R1 when A then B within {d} seconds",
            "relation_start\nmeasure invariant ({d} > -1)\nrelation_end",
            True,
        ),
        # an otherwise reads the values at its own start, not the trigger's
        ("R1 when A and (d > 0) then B within 5 seconds otherwise C within d seconds", "", True),
        # an interval that ends before it starts
        (
            "R1 when A then B within [{d} seconds, 5 seconds]",
            "relation_start\nmeasure invariant ({d} >= 0)\nrelation_end",
            True,
        ),
        (
            "R1 when A then B within [{d} seconds, 5 seconds]",
            "relation_start\nmeasure invariant (({d} >= 0) and ({d} <= 5))\nrelation_end",
            False,
        ),
        ("R1 when A then B within 5 seconds", "", False),
    ],
)
def test_negative_deadline(tmp_path: Path, rule: str, extra: str, negative: bool) -> None:
    r = run(tmp_path, rule, extra, checks="negative-deadline")
    found = of(r, "negative-deadline")
    assert set(found) == ({"R1"} if negative else set())
    if negative:
        f = found["R1"]
        assert f.rules == ("R1",) and f.status == PROVED and "d" in values(f.situation)


def test_negative_deadline_points_at_the_deadline(tmp_path: Path) -> None:
    path = write(tmp_path, "R1 when A then B within 5 seconds and C within d seconds")
    r = analyse_file(path, Settings(), ["negative-deadline"])
    (f,) = r.findings
    line = path.read_text().splitlines()[f.span.line - 1]
    assert line[f.span.col - 1 :].startswith("d seconds") or line[f.span.col - 1 :].startswith("within d")


# ---------------------------------------------------------------------------- runtime conflicts


def test_runtime_conflict_and_the_priorities_that_settle_it(tmp_path: Path) -> None:
    rules = "R1 when A then B within 5 seconds\nR2 when C then not B within 3 seconds"
    r = run(tmp_path, rules, checks="runtime-conflict")
    f = of(r, "runtime-conflict")["R1/R2"]
    assert f.rules == ("R1", "R2") and f.status == PROVED and f.span.line == 3
    assert f.witness is not None and f.witness.confirmed
    assert [n for n, _ in f.related] == ["R2 forbids `B` here"] and f.related[0][1].line == 4
    # a priority in the file, either way round, settles it
    for block in ("R1 > R2", "R2 > R1"):
        r = run(tmp_path, rules, f"priority_start\n{block}\npriority_end", checks="runtime-conflict")
        assert r.findings == [], block
    # so does one given with the settings (--priority)
    for pair in (("R1", "R2"), ("R2", "R1")):
        r = run(tmp_path, rules, checks="runtime-conflict", priorities=frozenset({pair}))
        assert r.findings == [], pair


def test_priorities_settle_runtime_conflicts_transitively(tmp_path: Path) -> None:
    rules = (
        "R1 when A then B within 5 seconds\nR2 when C then not B within 3 seconds\n"
        "R3 when D then E within 1 seconds\nR4 when E then D within 1 seconds"
    )
    r = run(tmp_path, rules, "priority_start\nR2 > R3\npriority_end", checks="runtime-conflict")
    assert subjects(r, "runtime-conflict") == {"R1/R2"}
    r = run(
        tmp_path,
        rules,
        "priority_start\nR2 > R3\npriority_end",
        checks="runtime-conflict",
        priorities=frozenset({("R3", "R1")}),
    )
    assert r.findings == []
    r = run(tmp_path, rules, checks="runtime-conflict", priorities=frozenset({("R3", "R4")}))
    assert subjects(r, "runtime-conflict") == {"R1/R2"}


def test_runtime_conflict_between_two_activations_of_one_rule(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds unless x then not B within 5 seconds",
        checks="runtime-conflict",
    )
    f = of(r, "runtime-conflict")["R1/R1.1"]
    assert f.rules == ("R1",) and "two activations" in f.message


def test_no_runtime_conflict_without_a_prohibition_of_the_owed_event(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when C then not D within 3 seconds\nR3 when A then not E",
        checks=["runtime-conflict", "situational-conflict"],
    )
    assert r.findings == []


def test_runtime_conflict_rules_are_in_file_order(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when C then not B within 3 seconds\nR2 when A then B within 5 seconds",
        checks="runtime-conflict",
    )
    (f,) = r.findings
    assert f.rules == ("R1", "R2")


# ---------------------------------------------------------------------------- coverage


COVERED = (
    "R1 when A and x then B within 5 seconds unless y then C within 5 seconds\n"
    "R2 when D then B within 5 seconds"
)


def test_unproduced_inputs_from_a_mapping(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, COVERED)
    mapping = tmp_path / "mapping.yaml"
    mapping.write_text(
        "measures:\n  x: {topic: /x, type: std_msgs/Bool}\nevents:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n"
    )
    assert (
        main(["analyse", "--json", "--check", "unproduced-input", "--mapping", str(mapping), str(path)]) == 1
    )
    (doc,) = json.loads(capsys.readouterr().out)["files"]
    got = {(f["subject"], f["line"], tuple(f["rules"])) for f in doc["findings"]}
    assert got == {("y", 3, ("R1",)), ("D", 4, ("R2",))}
    # a mapping that produces everything the rules read: nothing to say
    mapping.write_text(
        "measures:\n  x: {topic: /x, type: std_msgs/Bool}\n  y: {topic: /y, type: std_msgs/Bool}\n"
        "events:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n  D: {topic: /d, type: std_msgs/Bool, equals: true}\n"
    )
    assert main(["analyse", "--check", "unproduced-input", "--mapping", str(mapping), str(path)]) == 0
    capsys.readouterr()


def test_unimplemented_clauses_from_tasks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write(tmp_path, COVERED)
    module = f"analyse_tasks_{tmp_path.name.replace('-', '_')}"
    (tmp_path / f"{module}.py").write_text(
        "from cosleec.runtime import Task\n\n"
        "class T1(Task):\n    rule = 'R1'\n\n    def default(self, decision):\n        self.event('B')\n\n"
        "def install(manager):\n    manager.bind(T1())\n    manager.capability('B')(lambda o, d: None)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["analyse", "--json", "--check", "unimplemented-clause", "--tasks", module, str(path)]) == 1
    (doc,) = json.loads(capsys.readouterr().out)["files"]
    (f,) = doc["findings"]
    assert f["code"] == "unimplemented-clause" and f["subject"] == "R1.1" and f["rules"] == ["R1"]
    assert f["severity"] == "error" and f["line"] == 3
    assert f["col"] == path.read_text().splitlines()[2].index("unless y") + 1


def test_coverage_findings_through_the_api(tmp_path: Path) -> None:
    path = write(tmp_path, COVERED)
    cov = Coverage(
        unimplemented=("R1.1: no implementation",), measures=frozenset({"x", "y"}), events=frozenset({"A"})
    )
    r = analyse_file(path, Settings(), ["unimplemented-clause", "unproduced-input"], coverage=cov)
    assert {(f.code, f.subject) for f in r.findings} == {
        ("unimplemented-clause", "R1.1"),
        ("unproduced-input", "D"),
    }
    # without coverage, the coverage checks have nothing to go on
    assert analyse_file(path, Settings(), ["unimplemented-clause", "unproduced-input"]).findings == []
