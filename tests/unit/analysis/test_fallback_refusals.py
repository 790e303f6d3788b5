"""Prohibitions inside an ``otherwise`` and inside braced inner clauses refuse obligations, as
the reference semantics (:func:`cosleec.semantics.judge`) says; and a refused obligation's
``otherwise`` counts only what comes after the refusing step.

Two oracles. :func:`accepts` pins the encoding's slots to one given trace (each occurrence a
slot at its time and causal position, every other slot absent, every snapshot the trace's
values) and asks whether every rule holds: that must be exactly when the reference finds no
breach nothing makes up for. And :func:`differential.agrees` has every witness the analysis
shows confirmed, and takes traces the reference accepts as refutations of vacuous conflicts.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import z3
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.analysis import Settings
from cosleec.analysis.checks import Analysis
from cosleec.analysis.witness import final_breaches
from cosleec.lang import PrioritySemantics, Specification, load
from cosleec.semantics import Step, judge

from .differential import agrees
from .support import analyse, subjects

HEAD = "def_start event A event B event D event C event E event X event Y measure c : boolean def_end\n"
END = 200.0  # time goes on past every deadline the generated rules can set
PLAIN = Settings()  # the default reading (no priority), for both oracles


def _file(tmp_path: Path, rules: str) -> Path:
    path = tmp_path / "rules.sleec"
    path.write_text(HEAD + f"rule_start\n{rules}\nrule_end\n", encoding="utf-8")
    return path


def accepts(spec: Specification, trace: Sequence[tuple[float, str]], c: bool, s: Settings = PLAIN) -> bool:
    """The encoding's answer: every rule holds on exactly ``trace`` (measure ``c`` constant)."""
    a = Analysis(spec, {}, s)
    enc = a.new_encoding(2)
    mine = [enc.free(event) for _, event in trace]
    enc.unfold()
    pinned = [z3.Not(s.present) for s in enc.slots if s not in mine]
    for n, (s, (t, _)) in enumerate(zip(mine, trace)):
        pinned += [s.present, s.t == z3.RealVal(t, enc.ctx), s.pos == n]
    for snap in [s.snap for s in enc.slots] + [fb.snap for fb in enc.fallbacks]:
        pinned += [v == c for v in snap.values()]
    answer = enc.check([*enc.rule_lit.values(), *enc.relation_lit, *pinned])
    assert answer != z3.unknown
    return bool(answer == z3.sat)


def reference_accepts(
    spec: Specification, trace: Sequence[tuple[float, str]], c: bool, s: Settings = PLAIN
) -> bool:
    """The reference's answer on the same trace: no breach that nothing makes up for."""
    steps = [Step(0.0, None, {"c": c}), *(Step(t, e) for t, e in trace), Step(END)]
    return not final_breaches(spec, judge(spec, steps, s.reading))


# ---------------------------------------------------------------------- hand-made cases

# R1 is refused at A (R3 forbids X for its whole window); its fallback forbids Y for 10 s,
# which refuses R2 at once; R2's fallback owes C within 1 s, which R4 forbids: R2 is broken
# whenever A occurs. Without the refusal, R2 would be missed at 5 s and C at 5.5 s would do.
REFUSED_BY_A_FALLBACK = (
    "R1 when A then X within 2 seconds otherwise {not Y within 10 seconds}\n"
    "R2 when A then Y within 5 seconds otherwise C within 1 seconds\n"
    "R3 when A then not X within 3 seconds\n"
    "R4 when A then not C within 4 seconds"
)


def test_an_obligation_refused_by_another_rules_otherwise_is_a_vacuous_conflict(tmp_path: Path) -> None:
    path = _file(tmp_path, REFUSED_BY_A_FALLBACK)
    spec = load(path)
    for trace in ([(0, "A")], [(0, "A"), (5.5, "C")], [(0, "A"), (0.5, "C")], [(0, "A"), (1, "Y")]):
        assert not reference_accepts(spec, trace, False)
        assert not accepts(spec, trace, False), trace
    report = analyse(path, "vacuous-conflict", bound=3, allow_unknown=True)
    assert subjects(report, "vacuous-conflict") == {"R1", "R2", "R3", "R4"}
    assert all("prohibition inside an otherwise" not in u for u in report.unknown)


def test_a_shorter_prohibition_in_the_otherwise_refuses_nothing(tmp_path: Path) -> None:
    """``not Y within 4 seconds`` leaves R2's window [0, 5] an instant: Y at 4.5 s meets it."""
    rules = REFUSED_BY_A_FALLBACK.replace("not Y within 10", "not Y within 4")
    path = _file(tmp_path, rules)
    spec = load(path)
    assert reference_accepts(spec, [(0, "A"), (4.5, "Y")], False)
    assert accepts(spec, [(0, "A"), (4.5, "Y")], False)
    assert not reference_accepts(spec, [(0, "A"), (3.5, "Y")], False)  # inside R1's fallback's window
    assert not accepts(spec, [(0, "A"), (3.5, "Y")], False)
    report = analyse(path, "vacuous-conflict", bound=3, allow_unknown=True)
    assert subjects(report, "vacuous-conflict") == set()


def test_a_prohibition_in_a_braced_clause_of_an_otherwise_refuses_when_chosen(tmp_path: Path) -> None:
    """R1's fallback forbids Y only unless {c}; with c, R2 is missed, not refused: E at 6 s does."""
    rules = (
        "R1 when A then X within 2 seconds otherwise {not Y within 10 seconds unless {c} then C within 9 seconds}\n"
        "R2 when A then Y within 5 seconds otherwise E within 1 seconds\n"
        "R3 when A then not X within 3 seconds\n"
        "R4 when A then not E within 4 seconds"
    )
    spec = load(_file(tmp_path, rules))
    for c in (False, True):
        for trace in ([(0, "A"), (5.5, "E")], [(0, "A"), (0.5, "E")], [(0, "A"), (1, "C"), (5.5, "E")]):
            assert accepts(spec, trace, c) == reference_accepts(spec, trace, c), (c, trace)
    assert reference_accepts(spec, [(0, "A"), (1, "C"), (5.5, "E")], True)
    assert not reference_accepts(spec, [(0, "A"), (5.5, "E")], False)


def test_the_otherwise_of_a_refused_obligation_counts_from_the_refusing_step(tmp_path: Path) -> None:
    """R1 owes X at A; B, later at the same instant, forbids X for R1's whole window: R1 is
    refused at B's step, and its fallback owes E after that step. An E between A and B at that
    instant does not count (it did, before: the fallback counted from A's step); an E after B
    does. R3 keeps any later E out, so only the order at the instant decides."""
    rules = (
        "R1 when A then X within 2 seconds otherwise E within 1 seconds\n"
        "R2 when B then not X within 5 seconds\n"
        "R3 when B then not E within [1 seconds, 9 seconds]"
    )
    spec = load(_file(tmp_path, rules))
    before, after = [(0, "A"), (0, "E"), (0, "B")], [(0, "A"), (0, "B"), (0, "E")]
    assert not reference_accepts(spec, before, False) and reference_accepts(spec, after, False)
    assert not accepts(spec, before, False)
    assert accepts(spec, after, False)
    # refused by a prohibition raised first (B before A): the fallback counts from A's step
    first = [(0, "B"), (0, "A"), (0, "E")]
    assert reference_accepts(spec, first, False) and accepts(spec, first, False)


def test_the_otherwise_of_an_obligation_refused_by_a_fallback_counts_from_that_step(tmp_path: Path) -> None:
    """The refusing prohibition is raised when R2's fallback starts, at D's breaking step: E
    between A and D at that instant does not count for R1's fallback, E after D does."""
    rules = (
        "R1 when A then X within 2 seconds otherwise E within 1 seconds\n"
        "R2 when B then not D within 5 seconds otherwise {not X within 5 seconds}\n"
        "R3 when B then not E within [1 seconds, 9 seconds]"
    )
    spec = load(_file(tmp_path, rules))
    for trace in (
        [(0, "B"), (0, "A"), (0, "E"), (0, "D")],
        [(0, "B"), (0, "A"), (0, "D"), (0, "E")],
        [(0, "B"), (0, "D"), (0, "A"), (0, "E")],
        [(0, "B"), (0, "A"), (0.5, "D"), (0.5, "E")],
        [(0, "B"), (0, "A"), (0.5, "E"), (0.5, "D")],
    ):
        assert accepts(spec, trace, False) == reference_accepts(spec, trace, False), trace
    assert not reference_accepts(spec, [(0, "B"), (0, "A"), (0, "E"), (0, "D")], False)
    assert reference_accepts(spec, [(0, "B"), (0, "A"), (0, "D"), (0, "E")], False)


def test_two_fallbacks_never_refuse_each_others_obligations_by_themselves(tmp_path: Path) -> None:
    """Each fallback forbids the other's event for 10 s. Refused at once by each other, both
    fallbacks would start at A and Y at 12 s would be allowed; but nothing refuses either
    first, so both are missed at 5 s, R1's fallback forbids Y until 15 s: Y at 12 s breaks it
    (the encoding ranks refusals so that no two justify each other)."""
    rules = (
        "R1 when A then X within 5 seconds otherwise {not Y within 10 seconds}\n"
        "R2 when A then Y within 5 seconds otherwise {not X within 10 seconds}"
    )
    spec = load(_file(tmp_path, rules))
    for trace, ok in (
        ([(0, "A"), (12, "Y")], False),
        ([(0, "A"), (16, "Y")], True),
        ([(0, "A"), (1, "X"), (2, "Y")], True),
    ):
        assert reference_accepts(spec, trace, False) is ok
        assert accepts(spec, trace, False) is ok, trace


def test_an_obligation_met_before_the_refusing_step_at_that_instant_is_not_refused(tmp_path: Path) -> None:
    """D breaks R1 at 1 s, and R1's fallback forbids Y: R2 (Y owed until 2 s) is refused at D's
    step, unless Y came first at that instant (then it is met). Refused, R2's fallback owes C."""
    rules = (
        "R1 when B then not D within 5 seconds otherwise {not Y within 5 seconds}\n"
        "R2 when A then Y within 2 seconds otherwise {C within 1 seconds}"
    )
    spec = load(_file(tmp_path, rules))
    cases = (
        ([(0, "B"), (0, "A"), (1, "Y"), (1, "D")], True),
        ([(0, "B"), (0, "A"), (1, "D"), (1, "Y")], False),
        ([(0, "B"), (0, "A"), (1, "D"), (1.5, "C")], True),
        ([(0, "B"), (0, "A"), (1, "D"), (2.5, "C")], False),
    )
    for trace, ok in cases:
        assert reference_accepts(spec, trace, False) is ok, trace
        assert accepts(spec, trace, False) is ok, trace


# ---------------------------------------------------------------------- generated rule sets

SECONDS = st.integers(min_value=1, max_value=5)
EVENTS = ["X", "Y"]  # few events: the rules meet often


@st.composite
def _leaf(draw: st.DrawFn) -> str:
    event = draw(st.sampled_from(EVENTS))
    k = draw(SECONDS)
    kind = draw(st.sampled_from(["owe", "forbid", "forbid-long", "forbid-untimed", "forbid-ever"]))
    if kind == "owe":
        return f"{event} within {k} seconds"
    if kind in ("forbid", "forbid-long"):  # a long one covers more obligations' windows: refuses
        return f"not {event} within {k + 5 * (kind == 'forbid-long')} seconds"
    return f"not {event}" if kind == "forbid-untimed" else f"not {event} eventually"


@st.composite
def _response(draw: st.DrawFn) -> str:
    """An obligation with an otherwise holding a prohibition (braced, maybe in a clause), a
    prohibition in a braced inner clause, or a plain item."""
    event = draw(st.sampled_from(EVENTS))
    k = draw(SECONDS)
    kinds = ["otherwise", "otherwise", "otherwise-clause", "inner", "plain", "forbid-otherwise"]
    kind = draw(st.sampled_from(kinds))
    if kind == "otherwise":
        return f"{event} within {k} seconds otherwise {{{draw(_leaf())}}}"
    if kind == "otherwise-clause":
        return f"{event} within {k} seconds otherwise {{{draw(_leaf())} unless {{c}} then {draw(_leaf())}}}"
    if kind == "inner":  # with c, the braced clause and its default; else the rule's default
        inner = f"{draw(_leaf())} unless (not {{c}}) then {draw(_leaf())}"
        return f"{draw(_leaf())} unless {{c}} then {{{inner}}}"
    if kind == "forbid-otherwise":
        return f"not {event} within {k} seconds otherwise {{{draw(_leaf())}}}"
    return draw(_leaf())


@st.composite
def _rule_set(draw: st.DrawFn) -> str:
    n = draw(st.integers(min_value=2, max_value=3))
    triggers = draw(st.lists(st.sampled_from(["A", "B"]), min_size=n, max_size=n))
    return "\n".join(f"R{i} when {triggers[i - 1]} then {draw(_response())}" for i in range(1, n + 1))


TIMES = st.integers(min_value=0, max_value=16).map(lambda t: t / 2)
TRACES = st.tuples(  # both triggers early, then a few responses: the rules' windows meet
    st.lists(
        st.tuples(st.integers(min_value=0, max_value=6).map(lambda t: t / 2), st.sampled_from("AB")),
        min_size=1,
        max_size=3,
    ),
    st.lists(st.tuples(TIMES, st.sampled_from("XY")), max_size=4),
).map(lambda p: sorted(p[0] + p[1], key=lambda s: s[0]))

SLOW = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@SLOW
@given(rules=_rule_set(), traces=st.lists(TRACES, min_size=1, max_size=4), c=st.booleans())
def test_the_encoding_accepts_a_trace_exactly_when_the_reference_does(
    tmp_path: Path, rules: str, traces: list[list[tuple[float, str]]], c: bool
) -> None:
    spec = load(_file(tmp_path, rules))
    for trace in traces:
        assert accepts(spec, trace, c) == reference_accepts(spec, trace, c), (rules, trace, c)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rules=_rule_set(), traces=st.lists(TRACES, min_size=1, max_size=3), c=st.booleans())
def test_generated_rule_sets_with_nested_prohibitions_agree_with_the_reference(
    tmp_path: Path, rules: str, traces: list[list[tuple[float, str]]], c: bool
) -> None:
    path = _file(tmp_path, rules)
    steps = [[Step(0.0, None, {"c": c}), *(Step(t, e) for t, e in trace), Step(END)] for trace in traces]
    agrees(path, Settings(timeout=20.0, bound=3), steps)


# ---------------------------------------------------------------------- with priorities

PRIORITY_HEAD = "def_start event A event B event C event D event X event Y def_end\n"


@st.composite
def _prioritised(draw: st.DrawFn) -> tuple[str, frozenset[tuple[str, str]]]:
    """test_priorities.py's rule sets, now with obligations that have an ``otherwise`` (left out
    there while their fallback after a refusal counted from the wrong step) and prohibitions
    inside one; distinct triggers, no zero-length deadlines (priorities.py's known limits)."""
    triggers = draw(st.permutations(["A", "B", "D"]))
    rules = []
    for i in range(1, 4):
        event, k = draw(st.sampled_from(["X", "Y"])), draw(SECONDS)
        kind = draw(st.sampled_from(["owe-otherwise", "forbid", "owe", "owe-forbidding"]))
        item = {
            "owe-otherwise": f"{event} within {k} seconds otherwise C within {draw(SECONDS)} seconds",
            "forbid": f"not {event} within {k + 1} seconds",
            "owe": f"{event} within {k} seconds",
            "owe-forbidding": f"{event} within {k} seconds otherwise {{not {draw(st.sampled_from('XY'))} "
            f"within {draw(SECONDS) + 1} seconds}}",
        }[kind]
        rules.append(f"R{i} when {triggers[i - 1]} then {item}")
    high, low = draw(st.permutations(["R1", "R2", "R3"]))[:2]
    return "\n".join(rules), frozenset({(high, low)})


def test_a_conflict_aware_cancellation_at_a_raising_step_follows_what_came_before_it(tmp_path: Path) -> None:
    """R1 > R2, conflict-aware. B at R1's deadline (3 s) raises R2's prohibition of X there, so
    the clash is forced at 3 s -- just after B's step, as the reference applies it: an X at 3 s
    before B has met R1 already (nothing to cancel, R2 binds from B on: a later X breaks it),
    one after B comes after the cancellation (it meets R1 and breaks nothing)."""
    rules = "R1 when A then X within 3 seconds\nR2 when B then not X within 4 seconds"
    spec = load(_file(tmp_path, rules))
    s = Settings(priorities=frozenset({("R1", "R2")}), priority_semantics=PrioritySemantics.CONFLICT_AWARE)
    cases = (
        ([(0, "A"), (3, "X"), (3, "B"), (3.5, "X")], False),  # met before B: R2 kept, X breaks it
        ([(0, "A"), (3, "X"), (3, "B"), (7, "X")], False),  # R2's window ends at 7 s, inclusive
        ([(0, "A"), (3, "X"), (3, "B"), (7.5, "X")], True),
        ([(0, "A"), (3, "B"), (3, "X")], True),  # X after B: R2 cancelled first, R1 met
        ([(0, "A"), (3, "B"), (3, "X"), (3.5, "X")], True),
        ([(0, "A"), (3, "B"), (3.5, "X")], False),  # R2 cancelled, but R1's X is late
        ([(0, "A"), (2.5, "X"), (3, "B"), (3.5, "X")], False),
    )
    for trace, ok in cases:
        assert reference_accepts(spec, trace, False, s) is ok, trace
        assert accepts(spec, trace, False, s) is ok, trace


def test_a_fallback_raised_at_a_deadline_clashes_with_no_window_that_closed_there(tmp_path: Path) -> None:
    """R1 > R2, conflict-aware. R1's fallback forbids Y from R1's deadline, once time passes it.
    When R2's Y is due at that same instant, both windows close together first: R2 is missed
    (its fallback owes C), nothing is cancelled. Due later, R2 is cancelled at its deadline."""
    rules = (
        "R1 when A then X within 1 seconds otherwise {not Y within 2 seconds}\n"
        "R2 when B then Y within 1 seconds otherwise C within 1 seconds"
    )
    spec = load(_file(tmp_path, rules))
    s = Settings(priorities=frozenset({("R1", "R2")}), priority_semantics=PrioritySemantics.CONFLICT_AWARE)
    cases = (
        ([(0, "B"), (0, "A")], False),  # both due at 1 s: R2 missed, then C missed
        ([(0, "B"), (0, "A"), (1.5, "C")], True),
        ([(0, "B"), (0, "A"), (2.5, "C")], False),
        ([(0, "A"), (0.5, "B")], True),  # R2 due at 1.5 s, R1's fallback forbids Y: cancelled then
    )
    for trace, ok in cases:
        assert reference_accepts(spec, trace, False, s) is ok, trace
        assert accepts(spec, trace, False, s) is ok, trace


def test_an_obligation_refused_before_its_clash_is_forced_cancels_nothing(tmp_path: Path) -> None:
    """R3 > R1, conflict-aware. R3 forbids R1's Y to its deadline, which would cancel R1 then;
    but B, before that, raises R2's prohibition (no priority orders R1 and R2) over what is
    left of R1's window: R1 is refused there and its fallback owes C -- blocked first, it is no
    longer pending when the clash is due, so nothing is cancelled (the encoding cancelled R1 at
    its deadline, sparing the fallback). At the instant the clash is raised, the order decides."""
    rules = (
        "R1 when A then Y within 1 seconds otherwise C within 2 seconds\n"
        "R2 when B then not Y within 4 seconds\n"
        "R3 when D then not Y within 2 seconds"
    )
    path = tmp_path / "rules.sleec"
    path.write_text(PRIORITY_HEAD + f"rule_start\n{rules}\nrule_end\n", encoding="utf-8")
    spec = load(path)
    s = Settings(priorities=frozenset({("R3", "R1")}), priority_semantics=PrioritySemantics.CONFLICT_AWARE)
    cases = (
        ([(0, "D"), (0.5, "A"), (1, "B")], False),  # refused at 1 s, C never comes
        ([(0, "D"), (0.5, "A"), (1, "B"), (2, "C")], True),
        ([(0, "D"), (0.5, "A"), (1, "B"), (3.5, "C")], False),  # C after its window [1, 3]
        ([(0, "D"), (0.5, "A"), (1.5, "B")], True),  # B at the deadline: R1 cancelled first
        ([(0, "A"), (1, "B"), (1, "D")], False),  # refused at B's step, before D raises the clash
        ([(0, "A"), (1, "D"), (1, "B")], True),  # cancelled once D's step is over, before B
        ([(0, "D"), (1, "B"), (1, "A")], False),  # refused as A raises it
    )
    for trace, ok in cases:
        assert reference_accepts(spec, trace, False, s) is ok, trace
        assert accepts(spec, trace, False, s) is ok, trace


PRIORITY_TRACES = st.lists(
    st.tuples(st.integers(min_value=0, max_value=16).map(lambda t: t / 2), st.sampled_from("ABCDXY")),
    min_size=1,
    max_size=5,
).map(lambda xs: [Step(t, e) for t, e in sorted(xs, key=lambda s: s[0])] + [Step(END)])


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rs=_prioritised(), aware=st.booleans(), traces=st.lists(PRIORITY_TRACES, min_size=1, max_size=3))
def test_generated_rule_sets_with_priorities_and_fallbacks_agree_with_the_reference(
    tmp_path: Path, rs: tuple[str, frozenset[tuple[str, str]]], aware: bool, traces: list[list[Step]]
) -> None:
    rules, pairs = rs
    path = tmp_path / "rules.sleec"
    path.write_text(PRIORITY_HEAD + f"rule_start\n{rules}\nrule_end\n", encoding="utf-8")
    semantics = PrioritySemantics.CONFLICT_AWARE if aware else PrioritySemantics.CANCEL
    agrees(path, Settings(priorities=pairs, priority_semantics=semantics, timeout=20.0), traces)
