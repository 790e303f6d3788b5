"""The issuer alone: a response becomes obligations, read fail-closed where a value is unknown."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.runtime.issuer import Issued, after, prohibitions
from cosleec.runtime.model import MAX_WINDOW_S, Fixed, ItemSpec, Obligation, ResponseSpec

from .build import Parts, parts

TK = "R1 when E then F within (n) seconds and not Rec within (n) minutes"
LEGOS = "R2 when E then F within [n seconds, 100 seconds] and not Rec within [n seconds, 100 seconds]"
INNER = "R3 when E then F unless b then { not Rec within 10 minutes unless a then not Help within 5 seconds }"


def issued(p: Parts, rule: str, clause: int = 0) -> Issued:
    r = p.core.ruleset.rule(rule)
    return p.core.issuer.issue(r.response_of(clause), rule)


def windows(i: Issued) -> list[tuple[str, bool, float, float | None]]:
    return [(o.event, o.negated, o.from_s, o.within_s) for o in i.obligations]


# ---------------------------------------------------------------------------- unknown deadlines


def test_an_unknown_deadline_is_now_for_an_obligation_and_the_longest_for_a_prohibition() -> None:
    p = parts(TK)
    assert windows(issued(p, "R1")) == [("F", False, 0.0, 0.0), ("Rec", True, 0.0, MAX_WINDOW_S)]


def test_an_unknown_interval_start_is_now_for_both_and_closes_an_obligation_at_once() -> None:
    p = parts(LEGOS)
    assert windows(issued(p, "R2")) == [("F", False, 0.0, 0.0), ("Rec", True, 0.0, 100.0)]
    p.update(n=3)
    assert windows(issued(p, "R2")) == [("F", False, 3.0, 100.0), ("Rec", True, 3.0, 100.0)]


@settings(max_examples=60)
@given(st.floats(-3e10, 3e10, allow_nan=False) | st.integers(-(10**12), 10**12))
def test_a_deadline_read_on_the_context_is_its_value_or_fail_closed_out_of_range(n: float) -> None:
    p = parts(TK)
    p.update(n=n)
    seconds, minutes = float(n), float(n * 60)
    ok = [abs(x) <= MAX_WINDOW_S for x in (seconds, minutes)]
    assert windows(issued(p, "R1")) == [
        ("F", False, 0.0, seconds if ok[0] else 0.0),
        ("Rec", True, 0.0, minutes if ok[1] else MAX_WINDOW_S),
    ]


# ---------------------------------------------------------------------------- inner choices


def test_an_undetermined_inner_choice_issues_the_prohibitions_of_every_candidate() -> None:
    p = parts(INNER)
    out = issued(p, "R3", clause=1)
    assert not out.determined and out.missing == ("a",)
    assert windows(out) == [("Rec", True, 0.0, 600.0), ("Help", True, 0.0, 5.0)]


@pytest.mark.parametrize(
    ("a", "want"), [(True, [("Help", True, 0.0, 5.0)]), (False, [("Rec", True, 0.0, 600.0)])]
)
def test_a_determined_inner_choice_issues_its_clause(a: bool, want: list[Any]) -> None:
    p = parts(INNER)
    p.update(a=a)
    out = issued(p, "R3", clause=1)
    assert out.determined and out.missing == ()
    assert windows(out) == want


def test_an_undetermined_inner_choice_issues_no_obligation_that_requires_an_event() -> None:
    p = parts("R4 when E then F unless b then { G within 1 seconds unless a then not Help within 5 seconds }")
    out = issued(p, "R4", clause=1)
    assert not out.determined
    assert windows(out) == [("Help", True, 0.0, 5.0)]  # G may not be owed: it is not issued


def test_no_response_issues_nothing_determined() -> None:
    p = parts(INNER)
    assert issued(p, "R3", clause=0).determined
    out = p.core.issuer.issue(None, "R3")
    assert out == Issued(())


def test_an_undetermined_rule_forbids_what_any_clause_that_could_apply_forbids() -> None:
    p = parts("R5 when E then not Rec within 1 seconds unless a then not Help within 2 seconds")
    rule = p.core.ruleset.rule("R5")
    out = p.core.issuer.undetermined(rule, (None,))
    assert not out.determined
    assert windows(out) == [("Rec", True, 0.0, 1.0), ("Help", True, 0.0, 2.0)]
    assert windows(p.core.issuer.undetermined(rule, ())) == [("Rec", True, 0.0, 1.0)]  # the default only
    assert windows(p.core.issuer.undetermined(rule, (True,))) == [("Help", True, 0.0, 2.0)]


# ---------------------------------------------------------------------------- the memo


def test_a_fixed_response_is_issued_once_and_shared() -> None:
    p = parts("R1 when E then F within 5 seconds R2 when E then F within 5 seconds")
    r1, r2 = p.core.ruleset.rule("R1").default, p.core.ruleset.rule("R2").default
    assert r1.fixed and r2.fixed
    first = p.core.issuer.items(r1, "R1")
    assert p.core.issuer.items(r1, "R1") is first
    other = p.core.issuer.items(r2, "R2")
    assert [o.rule for o in first] == ["R1"] and [o.rule for o in other] == ["R2"]


def test_a_response_that_reads_the_context_is_issued_anew_each_time() -> None:
    p = parts(TK)
    spec = p.core.ruleset.rule("R1").default
    assert not spec.fixed
    p.update(n=1)
    first = p.core.issuer.items(spec, "R1")
    p.update(n=2)
    again = p.core.issuer.items(spec, "R1")
    assert [o.within_s for o in first] == [1.0, 60.0] and [o.within_s for o in again] == [2.0, 120.0]


# ---------------------------------------------------------------------------- else


@pytest.mark.parametrize(
    ("alternative", "untimed", "want"),
    [
        ("G within 10 seconds", "none", ((("G", 0.0, 10.0),),)),
        ("G", "none", ((("G", 0.0, None),),)),
        ("G", "immediate", ((("G", 0.0, 1.0),),)),
        ("G", 3.0, ((("G", 0.0, 3.0),),)),
        ("G eventually", 3.0, ((("G", 0.0, None),),)),
        ("not G within 3 seconds", "none", ()),  # a prohibition never fulfils it
        ("G within 3 seconds and not Help within 2 seconds", "none", ()),  # nor does a branch holding one
        ("G within n seconds", "none", ()),  # an unknown value decides it: never
        ("{ G within 3 seconds unless {a} then Help within 4 seconds }", "none", ()),
    ],
)
def test_an_else_alternative_becomes_windows_or_never_fulfils(
    alternative: str, untimed: Any, want: Any
) -> None:
    p = parts(f"R1 when E then F within 5 seconds else {alternative}", untimed=untimed)
    assert issued(p, "R1").obligations[0].alternatives == want


@pytest.mark.parametrize(("a", "event", "hi"), [(True, "Help", 4.0), (False, "G", 3.0)])
def test_an_else_alternative_chooses_its_own_clause_now(a: bool, event: str, hi: float) -> None:
    p = parts(
        "R1 when E then F within 5 seconds else { G within 3 seconds unless {a} then Help within 4 seconds }"
    )
    p.update(a=a)
    assert issued(p, "R1").obligations[0].alternatives == (((event, 0.0, hi),),)


def test_a_prohibition_takes_no_else() -> None:
    p = parts("R1 when E then not F within 5 seconds else G within 3 seconds")
    assert issued(p, "R1").obligations[0].alternatives == ()


# ---------------------------------------------------------------------------- what an otherwise could forbid


def test_an_undetermined_decision_enforces_the_prohibitions_its_otherwise_would_start() -> None:
    p = parts(
        "R1 when E then not G within 1 seconds and F within 5 seconds otherwise not Rec within 60 seconds"
    )
    obligations = issued(p, "R1").obligations
    assert [(o.event, o.from_s, o.within_s, o.rule) for o in prohibitions(obligations)] == [
        ("G", 0.0, 1.0, "R1"),  # its own prohibitions first, as they are
        ("Rec", 5.0, 65.0, "R1"),  # then the otherwise's, from the deadline that would start it
    ]


def known(x: float) -> Fixed:
    return Fixed(x)


def unknown(v: dict[str, Any]) -> float:
    return float(v["n"])  # KeyError with no context: depends on a measure


def item(
    event: str, *, negated: bool = False, lo: Any = None, hi: Any = None, otherwise: Any = None
) -> ItemSpec:
    return ItemSpec(
        key=f"R1:{event}",
        event=event,
        negated=negated,
        lo=lo,
        hi=hi,
        eventually=False,
        otherwise=otherwise,
        alternative=None,
    )


BOUND = st.integers(0, 10_000).map(float) | st.just(9e9)
UNKNOWN = st.none()  # a bound over a measure: not known until the otherwise starts


@settings(max_examples=200)
@given(
    chain=st.lists(BOUND | UNKNOWN, max_size=4),
    lo=st.none() | BOUND | st.just("unknown"),
    hi=st.none() | BOUND | st.just("unknown"),
    first=st.integers(0, 1000).map(float),
    span=st.integers(0, 1000).map(float),
    values=st.lists(st.integers(0, 10**6).map(float), min_size=6, max_size=6),
)
def test_after_covers_every_window_the_otherwise_chain_could_forbid(
    chain: list[float | None],
    lo: float | str | None,
    hi: float | str | None,
    first: float,
    span: float,
    values: list[float],
) -> None:
    def bound(x: float | str | None) -> Any:
        return None if x is None else unknown if x == "unknown" else known(float(x))

    spec = ResponseSpec((item("Rec", negated=True, lo=bound(lo), hi=bound(hi)),))
    for d in reversed(chain):  # F0 within d0 otherwise F1 within d1 otherwise ... not Rec
        spec = ResponseSpec((item("F", hi=unknown if d is None else known(d), otherwise=spec),))
    last = first + span
    (got,) = after(spec, first, last, "R1")
    assert (got.event, got.negated, got.rule) == ("Rec", True, "R1")
    # whatever values the unknown bounds take, every window the prohibition could have lies inside
    real = iter(values)
    delay = sum(next(real) if d is None else d for d in chain)
    real_lo = 0.0 if lo is None else next(real) if lo == "unknown" else float(lo)
    real_hi = 0.0 if hi is None else next(real) if hi == "unknown" else float(hi)
    assert got.from_s <= first + delay + real_lo
    assert got.within_s is not None
    assert got.within_s >= min(MAX_WINDOW_S, last + delay + real_hi)
    assert got.within_s <= MAX_WINDOW_S
    if all(d is not None for d in chain) and "unknown" not in (lo, hi):  # nothing unknown: exactly it
        assert got.from_s == first + delay + real_lo
        assert got.within_s == min(MAX_WINDOW_S, last + delay + real_hi)


def test_after_reads_an_otherwise_across_its_inner_clauses() -> None:
    p = parts(
        "R1 when E then F within 5 seconds otherwise { not Rec within 2 seconds unless a then not G within 3 seconds }"
    )
    otherwise = p.core.ruleset.rule("R1").default.items[0].otherwise
    assert otherwise is not None
    got = after(otherwise, 5.0, 7.0, "R1")
    assert [(o.event, o.from_s, o.within_s) for o in got] == [("Rec", 5.0, 9.0), ("G", 5.0, 10.0)]


def test_an_otherwise_obligation_with_no_otherwise_forbids_nothing() -> None:
    spec = ResponseSpec((item("F", hi=known(1.0)),))
    assert after(spec, 0.0, 0.0, "R1") == []
    assert prohibitions((Obligation(event="F", within_s=1.0, rule="R1"),)) == []
