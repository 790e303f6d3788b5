"""Declared priorities in the encoding, both semantics, against the reference semantics.

With ``H > L`` the runtime cancels L's firing when the two are active together (cancel) or
only when keeping it would make H impossible (conflict-aware). The analysis models that, so a
conflict a priority settles is no finding, one it does not settle still is, and every trace
it shows -- or finds while answering -- is one the reference semantics accepts. The property
test generates small rule sets with priorities (both semantics) and checks them with
:func:`differential.agrees` against :func:`cosleec.semantics.judge`.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.analysis import FileReport, Settings
from cosleec.analysis.witness import final_breaches
from cosleec.lang import PrioritySemantics, Reading, load
from cosleec.semantics import Step, judge

from .differential import agrees
from .support import analyse, of, subjects

SEMANTICS = list(PrioritySemantics)
HEAD = "def_start event A event B event C event D event X event Y def_end\n"
CORPUS = Path(__file__).resolve().parents[4] / "shared" / "sleec-corpus"
TIAGO = CORPUS / "UoY-RoboStar__SLEEC-TK__examples__TIAGo__TIAGo.sleec"

# ---------------------------------------------------------------------- hand-made cases

OWES_FORBIDS = {
    "same trigger": "R1 when A then X within 10 seconds\nR2 when A then not X within 10 seconds",
    "two triggers": "R1 when A then X within 5 seconds\nR2 when C then not X within 10 seconds",
    "prohibition first": "R1 when A then X within 5 seconds\nR2 when C then not X within 3 seconds",
}
CONFLICTS = {"runtime-conflict", "vacuous-conflict", "situational-conflict"}


def run(tmp_path: Path, rules: str, extra: str = "", **kw: object) -> FileReport:
    """Analyse ``rules`` (events A, B, C, X, Y) with ``Settings(**kw)``."""
    path = tmp_path / "rules.sleec"
    path.write_text(HEAD + f"rule_start\n{rules}\nrule_end\n{extra}\n", encoding="utf-8")
    return analyse(path, **kw)  # type: ignore[arg-type]


def _codes(report: object) -> set[str]:
    return {f.code for f in report.findings} & CONFLICTS  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", sorted(OWES_FORBIDS))
def test_a_priority_either_way_settles_an_owes_forbids_conflict(tmp_path: Path, name: str) -> None:
    rules = OWES_FORBIDS[name]
    assert _codes(run(tmp_path, rules)) >= {"runtime-conflict"}  # without it: reported
    for semantics in SEMANTICS:
        for pair in (("R1", "R2"), ("R2", "R1")):
            r = run(tmp_path, rules, priorities=frozenset({pair}), priority_semantics=semantics)
            assert _codes(r) == set(), (semantics, pair, [f.message for f in r.findings])
            assert r.unknown == []  # settled, not left to a note
            block = run(tmp_path, rules, f"priority_start\n{pair[0]} > {pair[1]}\npriority_end")
            assert _codes(block) == set()


def test_a_priority_over_a_third_rule_settles_by_cancelling_only_under_cancel(tmp_path: Path) -> None:
    """R3 > R2, R3 unrelated to X: the runtime conflict R1/R2 stays (no priority orders them).
    Under cancel, B just before A makes R3 active when R2 fires, so R2 is cancelled and A can
    occur (no vacuous conflict); conflict-aware cancels only for a clash, and R3 has none."""
    rules = OWES_FORBIDS["same trigger"] + "\nR3 when B then Y within 1 seconds"
    pair = frozenset({("R3", "R2")})
    cancel = run(tmp_path, rules, priorities=pair, priority_semantics=PrioritySemantics.CANCEL)
    assert _codes(cancel) == {"runtime-conflict"}
    spec = load(tmp_path / "rules.sleec")
    trace = [Step(0, "B"), Step(0.5, "A"), Step(0.6, "Y"), Step(1, "X"), Step(100)]
    assert not final_breaches(spec, judge(spec, trace, Reading(priorities=pair)))
    aware = run(tmp_path, rules, priorities=pair, priority_semantics=PrioritySemantics.CONFLICT_AWARE)
    assert _codes(aware) == {"runtime-conflict", "vacuous-conflict"}
    assert subjects(aware, "vacuous-conflict") == {"R1", "R2"}


def test_cancel_needs_the_higher_firing_still_active(tmp_path: Path) -> None:
    """R1 (higher) owes X within 1 s of B; met at once, it is no longer active when A comes, so
    R2 is not cancelled: A still cannot occur with R3 (cancel semantics; conflict-aware
    never cancels R2 here, R1 and R2 do not clash)."""
    rules = (
        "R1 when B then Y within 1 seconds\n"
        "R2 when A then X within 5 seconds\n"
        "R3 when A then not X within 10 seconds"
    )
    r = run(tmp_path, rules, priorities=frozenset({("R1", "R2")}), checks="vacuous-conflict")
    assert subjects(r, "vacuous-conflict") == set()  # B at 0, A at 0.5 (Y still owed): R2 cancelled
    trace = [Step(0, "B"), Step(0.5, "A"), Step(1, "Y"), Step(100)]
    spec = load(tmp_path / "rules.sleec")
    assert not final_breaches(spec, judge(spec, trace, Reading(priorities=frozenset({("R1", "R2")}))))
    late = [Step(0, "B"), Step(0.5, "Y"), Step(1, "A"), Step(100)]  # R1 no longer active at A
    assert final_breaches(spec, judge(spec, late, Reading(priorities=frozenset({("R1", "R2")}))))


def test_conflict_aware_keeps_the_lower_rule_until_the_deadline(tmp_path: Path) -> None:
    """R1 > R2: R2's prohibition binds until R1's deadline; a purpose that needs X before it
    is blocked under conflict-aware, possible under cancel (R3 keeps A alone: a second A's
    deadline could otherwise end the first A's R2 early)."""
    rules = (
        "R1 when A then X within 5 seconds\nR2 when A then not X within 10 seconds\n"
        "R3 when A then not A within 100 seconds"
    )
    purpose = "purpose_start p1 exists A while X within 2 seconds purpose_end"
    pair = frozenset({("R1", "R2")})
    aware = run(
        tmp_path, rules, purpose, priorities=pair, priority_semantics=PrioritySemantics.CONFLICT_AWARE
    )
    assert subjects(aware, "purpose-blocked") == {"p1"}
    assert of(aware, "purpose-blocked")["p1"].rules == ("R2", "R3")
    assert _codes(aware) == set()
    spec = load(tmp_path / "rules.sleec")
    early, at_deadline = [Step(0, "A"), Step(1, "X"), Step(200)], [Step(0, "A"), Step(5, "X"), Step(200)]
    aware_reading = Reading(priorities=pair, priority_semantics=PrioritySemantics.CONFLICT_AWARE)
    assert final_breaches(spec, judge(spec, early, aware_reading))
    assert not final_breaches(spec, judge(spec, at_deadline, aware_reading))
    assert not final_breaches(spec, judge(spec, early, Reading(priorities=pair)))
    cancel = run(tmp_path, rules, purpose, priorities=pair, priority_semantics=PrioritySemantics.CANCEL)
    assert subjects(cancel, "purpose-blocked") == set()


@pytest.mark.parametrize("semantics", SEMANTICS)
def test_tiago_priority_example(tmp_path: Path, semantics: PrioritySemantics) -> None:
    """SLEEC-TK's TIAGo priority experiment: Rule21 (call support on smoke) > Rule3 (do not call
    support after a fall without assent). Without the priority the two conflict in a situation;
    with it, under either semantics, that conflict is settled and every witness holds."""
    if not TIAGO.exists():
        pytest.skip("the SLEEC corpus is not next to the repository")
    path = tmp_path / "TIAGo.sleec"
    path.write_text(TIAGO.read_text(encoding="utf-8"), encoding="utf-8")
    plain = analyse(path, allow_unknown=True)
    pair = ("Rule21", "Rule3")
    assert any(set(f.rules) >= set(pair) for f in plain.findings if f.code in CONFLICTS)
    r = analyse(path, priorities=frozenset({pair}), priority_semantics=semantics, allow_unknown=True)
    assert not any(set(f.rules) >= set(pair) for f in r.findings if f.code in CONFLICTS)
    assert not any("priority" in u for u in r.unknown)
    for f in r.findings:
        assert f.witness is None or f.witness.confirmed, (f.code, f.subject, f.witness.timeline)


# ---------------------------------------------------------------------- generated rule sets

# no zero-length deadlines: a conflict-aware cancellation forced at the very instant its later
# item was raised is the encoding's known limit (priorities.py)
SECONDS = st.integers(min_value=1, max_value=6)


@st.composite
def _item(draw: st.DrawFn) -> str:
    event = draw(st.sampled_from(["X", "Y"]))
    k = draw(SECONDS)
    # no obligation with an otherwise: its fallback after a refusal counts an occurrence at the
    # refusal's instant that precedes the refusing step (obligations.py, found by this test, with
    # or without priorities; reported, not fixed here)
    kind = draw(st.sampled_from(["owe", "forbid", "between", "forbid-otherwise"]))
    if kind == "between":
        return f"{event} within [{k} seconds, {k + draw(SECONDS)} seconds]"
    if kind == "forbid-otherwise":
        return f"not {event} within {k + 1} seconds otherwise C within {draw(SECONDS)} seconds"
    return f"{'not ' if kind == 'forbid' else ''}{event} within {k + (kind == 'forbid')} seconds"


@st.composite
def _rule_set(draw: st.DrawFn) -> tuple[str, frozenset[tuple[str, str]]]:
    n = draw(st.integers(min_value=2, max_value=3))
    # distinct triggers: firings at one step in file order are the encoding's known limit (priorities.py)
    triggers = draw(st.permutations(["A", "B", "D"]))
    rules = [f"R{i} when {triggers[i - 1]} then {draw(_item())}" for i in range(1, n + 1)]
    order = draw(st.permutations([f"R{i}" for i in range(1, n + 1)]))
    chosen = draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), min_size=1, max_size=2))
    pairs = frozenset((order[min(a, b)], order[max(a, b)]) for a, b in chosen if a != b)
    return "\n".join(rules), pairs or frozenset({(order[0], order[1])})


TRACES = st.lists(
    st.tuples(st.integers(min_value=0, max_value=16).map(lambda t: t / 2), st.sampled_from("ABCDXY")),
    min_size=1,
    max_size=5,
).map(lambda xs: [Step(t, e) for t, e in sorted(xs, key=lambda s: s[0])] + [Step(100)])

SLOW = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@SLOW
@given(rs=_rule_set(), semantics=st.sampled_from(SEMANTICS), traces=st.lists(TRACES, min_size=1, max_size=4))
def test_generated_rule_sets_with_priorities_agree_with_the_reference(
    tmp_path: Path,
    rs: tuple[str, frozenset[tuple[str, str]]],
    semantics: PrioritySemantics,
    traces: list[list[Step]],
) -> None:
    rules, pairs = rs
    path = tmp_path / "rules.sleec"
    path.write_text(HEAD + f"rule_start\n{rules}\nrule_end\n", encoding="utf-8")
    agrees(path, Settings(priorities=pairs, priority_semantics=semantics, timeout=20.0), traces)
