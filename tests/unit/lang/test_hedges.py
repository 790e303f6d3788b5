"""Clause choice (`cosleec.lang.hedges`) against an oracle written from the definitions.

The oracle states each semantics as the language reference words it, clause by clause,
and reads unknown values by the meaning of "undetermined": a clause is chosen for sure
only if every way of filling in the unknowns chooses it.
"""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.lang.hedges import HedgeSemantics, Unknowns, blockers, choose, decisive, reachable

LAST, NESTED = HedgeSemantics.LAST_WINS, HedgeSemantics.NESTED


def oracle_known(values: list[bool], semantics: HedgeSemantics) -> int:
    n = len(values)
    for i in range(1, n + 1):
        if semantics is LAST:  # clause i: its condition holds and no later one does
            if values[i - 1] and not any(values[i:]):
                return i
        elif all(values[:i]) and (i == n or not values[i]):  # 1..i hold, i+1 does not
            return i
    return 0


def oracle(values: list[bool | None], semantics: HedgeSemantics) -> int | None:
    holes = [i for i, v in enumerate(values) if v is None]
    answers = set()
    for fill in itertools.product((False, True), repeat=len(holes)):
        full = list(values)
        for i, v in zip(holes, fill):
            full[i] = v
        answers.add(oracle_known(full, semantics))  # type: ignore[arg-type]
    return answers.pop() if len(answers) == 1 else None


values3 = st.lists(st.sampled_from([True, False, None]), max_size=7)


@given(values3, st.sampled_from(list(HedgeSemantics)))
def test_choose_is_the_definition(values: list[bool | None], semantics: HedgeSemantics) -> None:
    assert choose(values, semantics) == oracle(values, semantics)


@given(values3, st.sampled_from(list(HedgeSemantics)), st.booleans())
def test_unknowns_read_as_a_value(values: list[bool | None], semantics: HedgeSemantics, read: bool) -> None:
    policy = Unknowns.TRUE if read else Unknowns.FALSE
    filled = [read if v is None else v for v in values]
    assert choose(values, semantics, policy) == oracle_known(filled, semantics)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("values", "last", "nested"),
    [
        ([], 0, 0),
        ([False, False], 0, 0),
        ([True, False], 1, 1),
        ([False, True], 2, 0),  # nested: clause 2 needs clause 1 to hold
        ([True, True], 2, 2),
        ([True, True, False], 2, 2),
        ([True, False, True], 3, 1),  # the two semantics disagree
        ([None, True], 2, None),  # last-wins needs nothing before a later clause that holds
        ([True, None], None, None),
        ([False, None], None, 0),  # nested: clause 1 fails, nothing after it matters
    ],
)
def test_examples(values: list[bool | None], last: int | None, nested: int | None) -> None:
    assert choose(values, LAST) == last
    assert choose(values, NESTED) == nested


@given(values3, st.sampled_from(list(HedgeSemantics)))
def test_decisive_values_alone_decide(values: list[bool | None], semantics: HedgeSemantics) -> None:
    clause = choose(values, semantics)
    keep = decisive(values, clause, semantics)
    if clause is None:
        assert keep == tuple(i + 1 for i, v in enumerate(values) if v is None)
        return
    only = [v if i + 1 in keep else None for i, v in enumerate(values)]
    assert choose(only, semantics) == clause  # the named values suffice ...
    for k in keep:  # ... and each of them is needed
        without = [None if i + 1 == k else v for i, v in enumerate(only)]
        assert choose(without, semantics) != clause


@given(
    st.lists(st.none() | st.booleans(), max_size=8),
    st.sampled_from(list(HedgeSemantics)),
    st.sampled_from(list(Unknowns)),
)
def test_decisive_shortcut_names_what_the_search_names(
    values: list[bool | None], semantics: HedgeSemantics, unknown: Unknowns
) -> None:
    """The last-wins shortcut (issue 16) against the search it replaces: the chosen clause
    and every later one, never an earlier one, all of them when none holds."""
    from cosleec.lang.hedges import _decisive_by_search

    clause = choose(values, semantics, unknown)
    if clause is not None:
        assert decisive(values, clause, semantics, unknown) == _decisive_by_search(
            values, clause, semantics, unknown
        )


def test_decisive_names_the_clauses_an_explanation_needs() -> None:
    assert decisive([True, False], 1, LAST) == (1, 2)
    assert decisive([True, True, False], 2, NESTED) == (1, 2, 3)
    assert decisive([False, False], 0, LAST) == (1, 2)
    assert decisive([False, True], 0, NESTED) == (1,)
    assert decisive([False, True, False], 2, LAST) == (2, 3)


def test_reachable_with_static_facts() -> None:
    same = lambda i, j: (i, j) == (1, 2)  # noqa: E731 -- condition 1 implies condition 2
    assert reachable(2, LAST, implies=same) == {0, 2}  # clause 1 never wins: clause 2 holds too
    assert reachable(2, NESTED, implies=same) == {0, 2}  # nor under nested: 1 needs 2 not to hold
    later = lambda i, j: (i, j) == (1, 3)  # noqa: E731
    assert reachable(3, LAST, implies=later) == {0, 2, 3}
    assert reachable(3, NESTED, implies=later) == {0, 1, 3}  # nested: 1 needs only 2 false; 2 needs 3 false
    assert reachable(2, LAST, fixed={2: True}) == {2}
    assert reachable(3, NESTED, fixed={1: False}) == {0}
    assert reachable(40) is None  # too many free conditions: no answer rather than a slow one


# ---------------------------------------------------------------- the checker's lint uses them


def lint(conditions: list[str], semantics: HedgeSemantics) -> list[tuple[str, str]]:
    from cosleec.lang import analyse
    from cosleec.lang.checker import Options

    clauses = " ".join(f"unless {c} then B" for c in conditions)
    text = (
        "def_start event E event A event B measure m : boolean measure n : boolean measure k : boolean "
        f"def_end rule_start R1 when E then A {clauses} rule_end"
    )
    result = analyse(text, options=Options(semantics=semantics))
    assert result.ok, result.render()
    return [(d.code, d.message) for d in result.diagnostics if "hedge" in d.code]


def codes(conditions: list[str], semantics: HedgeSemantics) -> list[str]:
    return [c for c, _ in lint(conditions, semantics)]


def test_lint_follows_the_semantics() -> None:
    for sem in HedgeSemantics:  # clause 1 implies clause 2: never chosen under either
        assert codes(["m and n", "n"], sem) == ["unreachable-hedge"]
        assert codes(["m", "m"], sem) == ["duplicate-hedge"]
        assert codes(["m", "true"], sem) == ["unreachable-hedge"]
        assert codes(["m", "n", "k"], sem) == []  # independent conditions: all reachable
    # clause 1 implies clause 3: last-wins never picks clause 1; nested does (when 2 fails),
    # but never clause 2, which needs clause 1 and not clause 3
    assert [m[:18] for _, m in lint(["m and k", "n", "k"], LAST)] == ["clause 1 never app"]
    assert [m[:18] for _, m in lint(["m and k", "n", "k"], NESTED)] == ["clause 2 never app"]
    # clause 1 is `false`: under nested, clause 2 (which needs clause 1) is dead as well
    assert codes(["false", "n"], LAST) == ["unreachable-hedge"]
    nested = lint(["false", "n"], NESTED)
    assert [c for c, _ in nested] == ["unreachable-hedge", "unreachable-hedge"]
    assert "clause 1's condition is `false`" in nested[1][1]


def test_blockers_name_the_clause_that_keeps_another_dead() -> None:
    one_implies_two = lambda i, j: (i, j) == (1, 2)  # noqa: E731
    assert blockers(1, 2, LAST, implies=one_implies_two) == (2,)
    assert blockers(2, 2, NESTED, fixed={1: False}) == (1,)
    one_implies_three = lambda i, j: (i, j) == (1, 3)  # noqa: E731
    assert blockers(2, 3, NESTED, implies=one_implies_three) == (1, 3)
    assert blockers(1, 3, NESTED, implies=one_implies_three) == ()  # clause 1 is alive there


@given(values3, st.sampled_from(list(HedgeSemantics)), st.sampled_from([Unknowns.TRUE, Unknowns.FALSE]))
def test_decisive_under_a_reading_of_unknowns(
    values: list[bool | None], semantics: HedgeSemantics, policy: Unknowns
) -> None:
    clause = choose(values, semantics, policy)
    keep = decisive(values, clause, semantics, policy)
    read = [(policy == Unknowns.TRUE) if v is None else v for v in values]
    only = [v if i + 1 in keep else None for i, v in enumerate(read)]
    assert choose(only, semantics) == clause  # the named values, as the policy read them, suffice
    for k in keep:
        assert choose([None if i + 1 == k else v for i, v in enumerate(only)], semantics) != clause


def test_options_given_as_plain_strings_mean_the_same() -> None:
    assert choose([None], LAST, "undetermined") is None  # type: ignore[arg-type]  # fails closed
    assert choose([True, None], "last-wins", "undetermined") is None  # type: ignore[arg-type]
    assert choose([True, True, False], "nested") == 2  # type: ignore[arg-type]
    assert choose([None], LAST, "true") == 1  # type: ignore[arg-type]
