"""The behavioural diff of a patch (cosleec.repair.behaviour): counts checked against cases
whose situations are known by hand, against a brute-force oracle over small traces judged by
the reference semantics, and every scenario's trace judged differently by that oracle."""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterable, Sequence
from typing import Any

import pytest
import z3
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.analysis import Deadline, Settings
from cosleec.analysis.encoding import Encoding
from cosleec.analysis.witness import final_breaches
from cosleec.lang import Reading, Specification, analyse, visit
from cosleec.lang import ast as A
from cosleec.repair.behaviour import BehaviourChange, Region, atoms, behaviour_change
from cosleec.repair.scenario import UNCONFIRMED, duration
from cosleec.repair.sides import merge
from cosleec.semantics import Step, judge
from cosleec.testing import corpus_dir

HEADER = (
    "def_start event A event B event C measure x : boolean measure y : boolean measure m : boolean "
    "measure t : numeric constant N = 5 def_end\n"
)


def checked(rules: str, extra: str = "") -> tuple[Specification, dict[str, int]]:
    r = analyse(f"{HEADER}rule_start\n{rules}\nrule_end\n{extra}", "rules.sleec")
    assert r.ok and r.spec is not None and r.symbols is not None, [d.message for d in r.diagnostics]
    return r.spec, r.symbols.constant_values


def diff(before: str, after: str, regions: Iterable[Region] = (), **kw: Any) -> BehaviourChange:
    (b, cb), (a, ca) = checked(before), checked(after)
    out = behaviour_change(b, a, cb, ca, kw.pop("settings", Settings()), tuple(regions), **kw)
    assert out.computed, out.reason
    return out


# ---------------------------------------------------------------- the reference semantics as oracle


def forbids(spec: Specification, trace: Sequence[Step]) -> bool:
    """The reference semantics holds something against a complete trace: a breach nothing
    makes up for, or an obligation still pending at its end."""
    j = judge(spec, trace, Reading())
    return bool(final_breaches(spec, j)) or any(not v.negated for v in j.pending)


def differently(before: Specification, after: Specification, trace: Sequence[Step]) -> bool:
    return forbids(before, trace) != forbids(after, trace)


LATER = [(0.5, "B"), (3.0, "B"), (10.0, "B"), (0.5, "C"), (3.0, "C"), (10.0, "C")]


def brute_force(before: Specification, after: Specification, names: Sequence[str]) -> set[tuple[Any, ...]]:
    """The situations (an ``A`` with the values of ``names``) in which some small trace -- an
    ``A`` at 0 with any values of x, y, m, then at most three of B and C at 0.5, 3 or 10
    seconds -- is judged differently by the reference semantics under the two rule sets."""
    found = set()
    for x, y, m in itertools.product((False, True), repeat=3):
        values = {"x": x, "y": y, "m": m, "t": 0}
        for k in range(4):
            for later in itertools.combinations(LATER, k):
                trace = [Step(0, "A", values), *(Step(t, e, values) for t, e in later), Step(1000)]
                if differently(before, after, trace):
                    found.add(tuple(values[n] for n in names))
    return found


def witnessed(out: BehaviourChange, names: Sequence[str]) -> list[tuple[Any, ...]]:
    """The situation of each scenario's trace: the values of ``names`` at its ``A``."""
    return [tuple(next(s for s in w if s.event == "A").values[n] for n in names) for w in out.witnesses]


def changed_names(before: Specification, after: Specification) -> list[str]:
    """The measures the rules that differ read (the atoms of these tests are bare measures)."""
    b, a = set(before.rules), set(after.rules)
    rules = [r for r in (*before.rules, *after.rules) if (r in b) != (r in a)]
    return sorted({n.name for e in atoms(rules) for n in visit.names(e)})


# ---------------------------------------------------------------- known by hand


def test_identical_rules_change_nothing() -> None:
    rules = "R1 when A and x then B within N seconds\nR2 when B then not C within 3 seconds"
    out = diff(rules, rules)
    assert (out.situations, out.outside, out.exact, out.scenarios) == (0, 0, True, ())


def test_removing_a_rule_the_others_imply_changes_nothing() -> None:
    before = "R1 when A then B within 5 seconds\nR2 when A and x then B within 5 seconds"
    out = diff(before, "R1 when A then B within 5 seconds")
    assert (out.situations, out.exact, out.up_to_bound) == (0, True, None)


def test_removing_a_rule_changes_exactly_where_it_fires_and_nothing_implies_it() -> None:
    """R1 fires where x or y holds (3 of the 4 values) with m either way: 6 situations; where m
    holds its clause asks for C, which R2 asks for anyway: 3 remain. The brute-force oracle
    finds the same 3 (a `not` or `and`/`or` mistake in the trigger, or forgetting R2, would not)."""
    before = "R1 when A and (x or y) then B within 5 seconds unless m then C within 5 seconds\nR2 when A then C within 5 seconds"
    after = "R2 when A then C within 5 seconds"
    out = diff(before, after, scenarios=64)
    (b, _), (a, _) = checked(before), checked(after)
    names = ["m", "x", "y"]
    assert out.situations == 3 and out.exact
    assert (
        set(witnessed(out, names))
        == brute_force(b, a, names)
        == {(False, True, False), (False, False, True), (False, True, True)}
    )
    assert all(differently(b, a, w) for w in out.witnesses)


def test_an_unless_clause_changes_exactly_where_its_condition_holds() -> None:
    before = "R1 when A then B within 10 seconds"
    after = "R1 when A then B within 10 seconds unless x then not B within 10 seconds"
    out = diff(before, after)
    assert (out.situations, out.outside, out.exact) == (1, 1, True)  # no region: every situation is outside
    assert out.scenarios[0].startswith("A with x=true: ")
    assert diff(before, after, [Region("A", A.Name("x"))]).outside == 0
    assert diff(before, after, [Region("A", A.Not(A.Name("x")))]).outside == 1
    assert diff(before, after, [Region("A", A.Name("y"))]).outside == 1  # y does not cover x
    assert diff(before, after, [Region("B", None)]).outside == 1
    assert diff(before, after, [Region("A", None)]).outside == 0


def test_the_regions_of_two_situations() -> None:
    """Two situations (x with m, x without): a region on m leaves the one without m outside."""
    before = "R1 when A and x then B within 10 seconds unless m then C within 10 seconds\nR2 when B then C"
    out = diff(before, "R2 when B then C", [Region("A", A.Name("m"))])
    assert (out.situations, out.outside) == (2, 1)


def test_a_strict_comparison_made_weak_changes_the_boundary() -> None:
    out = diff(
        "R1 when A and (t < 5) then B within 5 seconds", "R1 when A and (t <= 5) then B within 5 seconds"
    )
    assert (out.situations, out.exact) == (1, True)
    assert (
        out.scenarios[0]
        == "A with t=5: before, going without B within 5 seconds was allowed; after, it is required (R1)"
    )
    reverse = diff(
        "R1 when A and (t <= 5) then B within 5 seconds", "R1 when A and (t < 5) then B within 5 seconds"
    )
    assert (
        reverse.scenarios[0]
        == "A with t=5: before, B within 5 seconds was required (R1); after, going without it is allowed"
    )
    assert (
        diff(
            "R1 when A and (t > N) then B within 5 seconds", "R1 when A and (t > 5) then B within 5 seconds"
        ).situations
        == 0
    )


def test_a_shorter_deadline_newly_forbids() -> None:
    before, after = "R1 when A then B within 5 minutes", "R1 when A then B within 3 minutes"
    out = diff(before, after)
    assert (out.situations, out.exact) == (1, True)
    assert out.scenarios == (
        "A: before, going without B within 3 minutes was allowed; after, it is required (R1)",
    )
    (b, _), (a, _) = checked(before), checked(after)
    assert not forbids(b, out.witnesses[0]) and forbids(a, out.witnesses[0])
    back = diff(after, before)  # the longer deadline newly allows
    assert back.scenarios == (
        "A: before, B within 3 minutes was required (R1); after, going without it is allowed",
    )


def test_a_changed_constant_changes_the_rules_that_read_it() -> None:
    rules = "R1 when A then B within N seconds\nR2 when B then C within 5 seconds"
    b, cb = checked(rules)
    r = analyse(f"{HEADER.replace('N = 5', 'N = 3')}rule_start\n{rules}\nrule_end\n", "rules.sleec")
    assert r.spec is not None and r.symbols is not None and r.spec.rules == b.rules
    out = behaviour_change(b, r.spec, cb, r.symbols.constant_values, Settings(), ())
    assert (out.situations, out.computed) == (1, True)
    assert out.scenarios == (
        "A: before, going without B within 3 seconds was allowed; after, it is required (R1)",
    )


def test_a_prohibition_removed_newly_allows() -> None:
    out = diff("R1 when A and x then not B within 10 seconds\nR2 when A then C", "R2 when A then C")
    assert out.scenarios == (
        "A with x=true: before, B within 10 seconds was forbidden (R1); after, it is allowed",
    )


def test_an_added_rule_newly_forbids_where_it_fires() -> None:
    out = diff("R1 when A then C", "R1 when A then C\nR2 when A and (not x) then not C within 10 seconds")
    assert out.situations == 1
    assert out.scenarios[0].startswith(
        "A with x=false: before, C within 10 seconds was allowed; after, it is forbidden (R2)"
    )


def test_the_limit_stops_the_count() -> None:
    before = "R1 when A and (x or y or m) then B within 5 seconds\nR2 when A then C"
    out = diff(before, "R2 when A then C", limit=4, scenarios=2)
    assert (out.situations, out.exact, len(out.scenarios), len(out.witnesses)) == (4, False, 2, 2)
    assert diff(before, "R2 when A then C", limit=7).exact  # (x or y or m): 7 situations
    assert not diff(before, "R2 when A then C", limit=6).exact


# ---------------------------------------------------------------- what is not computed


PRIORITY = "priority_start R1 > R2 priority_end"


def test_declaring_a_priority_allows_what_the_lower_rule_forbade() -> None:
    """R1 owes B and R2 forbids it: with R1 > R2 (cancel), R2 is cancelled where R1 fires with
    it (x holds), or fires again while it is active (a later A with x): B is newly allowed in
    both situations of R2's probe -- x and not x -- and the scenarios say so."""
    rules = "R1 when A and x then B within 5 seconds\nR2 when A then not B within 5 seconds"
    (b, cb), (a, ca) = checked(rules), checked(rules, PRIORITY)
    out = behaviour_change(b, a, cb, ca, Settings(), (), scenarios=64)
    assert (out.computed, out.situations, out.exact) == (True, 2, True), out.reason
    assert set(out.scenarios) == {
        f"A with x={v}: before, B within 5 seconds was forbidden (R2); after, it is allowed"
        for v in ("true", "false")
    }
    assert all(differently(b, a, w) for w in out.witnesses)
    back = behaviour_change(a, b, ca, cb, Settings(), ())
    assert "before, B within 5 seconds was allowed; after, it is forbidden (R2)" in back.scenarios[0]


def test_a_priority_given_besides_the_file_counts_for_both_versions() -> None:
    rules = "R1 when A and x then B within 5 seconds\nR2 when A then not B within 5 seconds\nR3 when C then B"
    (b, cb), (a, ca) = (
        checked(rules),
        checked(rules.replace("then B\n", "then C\n").replace("when C then B", "when C then C")),
    )
    given = Settings(priorities=frozenset({("R1", "R2")}))
    assert diff(rules, rules, settings=given).situations == 0
    out = behaviour_change(b, a, cb, ca, given, (), scenarios=64)
    assert out.computed and all(differently(b, a, w) for w in out.witnesses)


def test_a_changed_higher_rule_changes_what_it_cancels() -> None:
    """R1 > R2 in both; R1 now fires only with y: where x holds without y, R2 is no longer
    cancelled, so B is newly forbidden there (R2), and no longer owed (R1)."""
    before = "R1 when A then B within 5 seconds\nR2 when A and x then not B within 5 seconds"
    after = "R1 when A and y then B within 5 seconds\nR2 when A and x then not B within 5 seconds"
    (b, cb), (a, ca) = checked(before, PRIORITY), checked(after, PRIORITY)
    out = behaviour_change(b, a, cb, ca, Settings(), (), scenarios=64)
    assert out.computed, out.reason
    assert all(differently(b, a, w) for w in out.witnesses) and not any(
        s.endswith(UNCONFIRMED) for s in out.scenarios
    )
    assert any("it is forbidden (R2)" in s for s in out.scenarios)


def test_a_measure_whose_type_changes_is_not_computed() -> None:
    b, cb = checked("R1 when A then B")
    a = dataclasses.replace(
        b,
        definitions=tuple(
            dataclasses.replace(d, type=A.NumericType())
            if isinstance(d, A.MeasureDecl) and d.name == "x"
            else d
            for d in b.definitions
        ),
        rules=(),
    )
    out = behaviour_change(b, a, cb, cb, Settings(), ())
    assert not out.computed and "measure x" in out.reason


def test_the_solver_giving_up_is_not_a_count(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(Encoding, "check", lambda self, assumptions: z3.unknown)
    b, cb = checked("R1 when A and x then B within 5 seconds")
    a, ca = checked("R1 when A then B within 5 seconds")
    out = behaviour_change(b, a, cb, ca, Settings(), ())
    assert not out.computed and "gave up" in out.reason and out.situations == 0


def test_a_larger_bound_the_solver_gives_up_on_leaves_the_smaller_ones_answer(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """B and C ask for each other: the unfolding never completes, so bound 2 is asked first,
    then 4; at 4 the solver gives up: the count is the one found up to bound 2."""
    real = Encoding.check

    def check(self: Encoding, assumptions: Sequence[Any]) -> z3.CheckSatResult:
        return z3.unknown if self.bound > 2 else real(self, assumptions)

    monkeypatch.setattr(Encoding, "check", check)
    rules = "R1 when B then C within 1 seconds\nR2 when C then B within 1 seconds\n"
    b, cb = checked(rules + "R3 when A and x then B within 5 seconds")
    a, ca = checked(rules + "R3 when A then B within 5 seconds")
    out = behaviour_change(b, a, cb, ca, Settings(), ())
    assert (out.computed, out.situations, out.up_to_bound) == (True, 1, 2)
    monkeypatch.setattr(Encoding, "check", real)
    assert behaviour_change(b, a, cb, ca, Settings(), ()).up_to_bound == 6
    assert behaviour_change(b, a, cb, ca, Settings(bound=3), ()).up_to_bound == 3


def test_a_passed_deadline_is_not_a_count() -> None:
    b, cb = checked("R1 when A and x then B within 5 seconds")
    a, ca = checked("R1 when A then B within 5 seconds")
    out = behaviour_change(b, a, cb, ca, Settings(), (), deadline=Deadline(0.0))
    assert not out.computed and "deadline" in out.reason


# ---------------------------------------------------------------- the parts


def test_the_atoms_are_the_conditions_read_when_the_rule_fires() -> None:
    spec, _ = checked(
        "R1 when A and ((t > 3) and not x) then B within 5 seconds otherwise C within 1 seconds unless m then "
        "{not C within 1 seconds unless y}"
    )
    assert atoms(spec.rules) == (
        A.Compare(">", A.Name("t"), A.IntLit(3)),
        A.Name("x"),
        A.Name("m"),
        A.Name("y"),
    )


def test_the_sides_keep_shared_rules_once() -> None:
    b, cb = checked("R1 when A then B\nR2 when A and x then C")
    a, ca = checked("R1 when A then B\nR2 when A and y then C\nR3 when B then C")
    sides = merge(b, a, cb, ca)
    assert not isinstance(sides, str)
    assert [r.name for r in sides.spec.rules] == ["R1", "R2", "R2'", "R3'"]
    assert (sides.before, sides.after) == (("R1", "R2"), ("R1", "R2'", "R3'"))
    assert [r.name for r in sides.removed] == ["R2"] and sides.events == ("A", "B")


def test_durations_read_as_people_write_them() -> None:
    assert [duration(s) for s in (1, 0.5, 60, 180, 90, 3600, 86400 * 2)] == [
        "1 second",
        "0.5 seconds",
        "1 minute",
        "3 minutes",
        "90 seconds",
        "1 hour",
        "2 days",
    ]


# ---------------------------------------------------------------- random rule sets and edits

CONDITIONS = [None, "x", "y", "not x", "x and y", "x or y"]
RESPONSES = [
    "B within 1 seconds",
    "B within 5 seconds",
    "not B within 5 seconds",
    "C within 5 seconds",
    "not C within 1 seconds",
    "C",
]
Rule = tuple[str | None, str, tuple[tuple[str, str | None], ...]]

rule_parts = st.tuples(
    st.sampled_from(CONDITIONS),
    st.sampled_from(RESPONSES),
    st.lists(st.tuples(st.sampled_from(CONDITIONS[1:]), st.sampled_from([None, *RESPONSES])), max_size=1).map(
        tuple
    ),
)


def render(rules: Sequence[tuple[str, Rule]]) -> str:
    out = []
    for name, (cond, resp, clauses) in rules:
        text = f"{name} when A{f' and ({cond})' if cond else ''} then {resp}"
        for c, r in clauses:
            text += f" unless ({c})" + (f" then {r}" if r else "")
        out.append(text)
    return "\n".join(out)


@st.composite
def rule_sets_and_an_edit(draw: st.DrawFn) -> tuple[str, str]:
    rules = [(f"R{i}", draw(rule_parts)) for i in range(draw(st.integers(1, 3)))]
    i = draw(st.integers(0, len(rules) - 1))
    name, (cond, resp, clauses) = rules[i]
    edit = draw(st.sampled_from(["remove", "add", "trigger", "response", "unless"]))
    edited = list(rules)
    if edit == "remove" and len(rules) > 1:  # a rule block needs a rule
        del edited[i]
    elif edit == "add":
        edited.append(("R9", draw(rule_parts)))
    elif edit == "trigger":
        edited[i] = (name, (draw(st.sampled_from(CONDITIONS)), resp, clauses))
    elif edit in ("response", "remove"):
        edited[i] = (name, (cond, draw(st.sampled_from(RESPONSES)), clauses))
    else:
        extra = (draw(st.sampled_from(CONDITIONS[1:])), draw(st.sampled_from([None, *RESPONSES])))
        edited[i] = (name, (cond, resp, (*clauses, extra)))
    return render(rules), render(edited)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rule_sets_and_an_edit())
def test_every_situation_is_judged_differently_and_none_is_missed(case: tuple[str, str]) -> None:
    """Every scenario's trace is judged differently by the reference semantics (the count is
    not too high), each scenario is a situation of its own, and every situation the brute-force
    oracle finds among small traces is one of them (the count is not too low)."""
    before, after = case
    (b, cb), (a, ca) = checked(before), checked(after)
    out = behaviour_change(b, a, cb, ca, Settings(), (), scenarios=64)
    assert out.computed and out.exact, out.reason
    names = changed_names(b, a)
    seen = witnessed(out, names)
    assert len(seen) == len(set(seen)) == out.situations
    assert all(differently(b, a, w) for w in out.witnesses), out.scenarios
    assert not any(s.endswith(UNCONFIRMED) for s in out.scenarios)
    assert brute_force(b, a, names) <= set(seen)


# ---------------------------------------------------------------- a case study

CORPUS = corpus_dir()
ASPEN = CORPUS / "NickF0211__LEGOS-SLEEC__ASPEN__aspen.sleec"


def aspen() -> tuple[Specification, dict[str, int]]:
    if not ASPEN.is_file():
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    r = analyse(ASPEN.read_text(encoding="utf-8"), str(ASPEN), legos_compat=True)
    assert r.spec is not None and r.symbols is not None
    return r.spec, r.symbols.constant_values


def without(spec: Specification, name: str) -> Specification:
    return dataclasses.replace(spec, rules=tuple(r for r in spec.rules if r.name != name))


def test_aspen_removing_the_redundant_r14_changes_nothing() -> None:
    spec, consts = aspen()
    r14 = spec.rule("R14")
    out = behaviour_change(
        spec,
        without(spec, "R14"),
        consts,
        consts,
        Settings(),
        (Region("DeployDrone", r14.trigger.condition),),
    )
    assert (out.computed, out.situations, out.exact) == (True, 0, True)


def test_aspen_removing_r13_allows_deploying_in_the_seven_situations_where_it_fires() -> None:
    """R13 forbids DeployDrone where battery or store is low or damages holds: 7 of the 8
    values of its three conditions, none of which another rule forbids it for."""
    spec, consts = aspen()
    after = without(spec, "R13")
    out = behaviour_change(
        spec, after, consts, consts, Settings(), (Region("PreparingDrone", A.Name("damages")),), limit=64
    )
    assert (out.computed, out.situations, out.outside, out.exact) == (True, 7, 3, True)
    assert all(s.startswith("PreparingDrone with battery=") for s in out.scenarios)
    assert all(
        s.endswith(": before, DeployDrone at the same moment was forbidden (R13); after, it is allowed")
        for s in out.scenarios
    )
    assert all(differently(spec, after, w) for w in out.witnesses)
