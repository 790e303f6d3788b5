"""The encoding's parts built alone on a hand-made State (analysis/state.py): Terms, Windows and
Relations -- no Encoding, no unfolding -- and the one thing State itself promises, its order."""

from __future__ import annotations

import dataclasses

import pytest
import z3

from cosleec.analysis.relations import Relations
from cosleec.analysis.slots import Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms, as_float
from cosleec.analysis.windows import Windows
from cosleec.lang import HedgeSemantics, Reading
from cosleec.lang import ast as A

LEVEL = A.ScaleType(("low", "mid", "high"))
MEASURES: dict[str, A.MeasureType] = {"busy": A.BooleanType(), "temp": A.NumericType(), "level": LEVEL}


def state(
    *, relations: tuple[A.Relation, ...] = (), semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
) -> State:
    ctx = z3.Context()
    spec = A.Specification((), (), relations=relations)
    return State(
        ctx=ctx,
        spec=spec,
        constants={"LIMIT": 30},
        reading=Reading(semantics=semantics),
        bound=2,
        measures=MEASURES,
        solver=z3.Solver(ctx=ctx),
        timeout_ms=0,
        deadline=None,
        guard=z3.BoolVal(True, ctx),
        rules_by_event={},
        rule_lit={},
        relation_lit=[z3.Bool(f"relation!{i}", ctx) for i in range(len(relations))],
        complete=True,
        refusers={},
    )


def snapshot(terms: Terms, name: str = "s") -> dict[str, z3.ExprRef]:
    return {m: terms.var(m, name) for m in MEASURES}


def proves(st: State, claim: z3.BoolRef) -> bool:
    """``claim`` holds in every model of what the solver has (the domains, the chains)."""
    st.solver.push()
    st.solver.add(z3.Not(claim))
    answer = st.solver.check()
    st.solver.pop()
    return bool(answer == z3.unsat)


def test_the_fields_keep_the_order_the_encoding_lets_go_of_them_in() -> None:
    """A field moved changes which models z3 finds, and so witnesses (state.py)."""
    assert [f.name for f in dataclasses.fields(State)] == [
        "ctx", "spec", "constants", "reading", "bound", "measures", "solver", "timeout_ms", "deadline",
        "slots", "by_event", "fallbacks", "bans", "guard", "situation", "rules_by_event", "rule_lit",
        "relation_lit", "complete", "refusers", "extra", "ids", "fresh", "unfolded", "choices", "truths",
        "above", "rule", "firing", "cut", "cuts", "raised",  # declared priorities: last, so nothing before moves
        # prohibitions inside an otherwise (refusals.py): after those, for the same reason
        "deferred", "fallback_bans", "owed", "within", "imposed",
    ]  # fmt: skip


# ---------------------------------------------------------------- Terms


def test_a_snapshot_has_a_variable_of_its_measures_kind_and_a_scale_its_positions() -> None:
    st = state()
    terms = Terms(st)
    snap = snapshot(terms)
    assert (snap["busy"].sort(), snap["temp"].sort(), snap["level"].sort()) == (
        z3.BoolSort(st.ctx),
        z3.RealSort(st.ctx),
        z3.IntSort(st.ctx),
    )
    assert str(snap["temp"]) == "s!temp"
    terms.domain(snap)
    assert proves(st, z3.And(snap["level"] >= 0, snap["level"] <= 2))
    assert not proves(st, snap["level"] <= 1)


def test_conditions_and_numbers_read_literals_constants_and_scales() -> None:
    st = state()
    terms = Terms(st)
    snap = snapshot(terms)
    terms.domain(snap)
    above = A.Compare(">", A.Name("level"), A.Name("low"))  # low is position 0
    assert proves(st, terms.truth(above, snap) == (snap["level"] >= 1))
    hot = A.Compare(">=", A.Name("temp"), A.BinOp("+", A.Name("LIMIT"), A.IntLit(2)))
    assert proves(st, terms.truth(hot, snap) == (snap["temp"] >= 32))
    either = A.BinOp("or", A.Name("busy"), A.Not(A.BoolLit(True)))
    assert proves(st, terms.truth(either, snap) == snap["busy"])
    assert terms.truth(None, snap).eq(z3.BoolVal(True, st.ctx))
    assert terms.truth(above, snap) is terms.truth(above, snap)  # built once per condition and snapshot
    minutes = A.Duration(A.IntLit(2), "minutes")
    assert as_float(z3.simplify(terms.seconds(minutes, snap))) == 120.0


@pytest.mark.parametrize(
    ("semantics", "held", "chosen"),
    [
        (HedgeSemantics.LAST_WINS, (True, True), 2),  # the last clause that holds
        (HedgeSemantics.LAST_WINS, (True, False), 1),
        (HedgeSemantics.LAST_WINS, (False, False), 0),  # the default response
        (HedgeSemantics.NESTED, (False, True), 0),  # each clause needs the ones before it
        (HedgeSemantics.NESTED, (True, False), 1),
        (HedgeSemantics.NESTED, (True, True), 2),
    ],
)
def test_exactly_the_clause_the_semantics_chooses_applies(
    semantics: HedgeSemantics, held: tuple[bool, bool], chosen: int
) -> None:
    st = state(semantics=semantics)
    terms = Terms(st)
    snap = snapshot(terms)
    c1, c2 = A.Name("busy"), A.Compare(">", A.Name("temp"), A.IntLit(0))
    clauses = (A.Defeater(c1), A.Defeater(c2))
    applies = terms.chosen(clauses, snap)
    situation = z3.And(
        snap["busy"] if held[0] else z3.Not(snap["busy"]), snap["temp"] > 0 if held[1] else snap["temp"] <= 0
    )
    for k, term in enumerate(applies):
        assert proves(st, z3.Implies(situation, term if k == chosen else z3.Not(term))), k


def test_each_clause_asks_once_per_clause_and_leaves_the_solver_as_it_was() -> None:
    st = state()
    terms = Terms(st)
    snap = snapshot(terms)
    clauses = tuple(A.Defeater(A.Compare(">", A.Name("temp"), A.IntLit(n))) for n in (10, 20))
    asked: list[int] = []

    def ask(k: int, applies: z3.BoolRef) -> None:
        asked.append(k)
        # under last-wins, clause 1 applies when temp > 10 and not temp > 20
        if k == 1:
            assert proves(st, z3.Implies(applies, snap["temp"] <= 20))

    before = len(st.solver.assertions())
    terms.each_clause(clauses, snap, ask)
    assert asked == [2, 1, 0] and len(st.solver.assertions()) == before


def test_fresh_names_count_up_across_the_encoding() -> None:
    st = state()
    terms = Terms(st)
    assert [str(terms.fresh("goal")), str(terms.fresh("goal"))] == ["goal!0", "goal!1"]
    assert terms.fresh_number() == 2 and next(st.fresh) == 3  # one counter, the state's


# ---------------------------------------------------------------- Windows


def slot(st: State, n: int, event: str) -> Slot:
    s = Slot(
        n,
        event,
        0,
        z3.Real(f"t{n}", st.ctx),
        z3.Int(f"p{n}", st.ctx),
        z3.Bool(f"in{n}", st.ctx),
        {},
    )
    st.slots.append(s)
    st.by_event.setdefault(event, []).append(s)
    return s


def occurrence(*, within: int | None = None, after: int | None = None, **kw: bool) -> A.Occurrence:
    lim = None
    if within is not None:
        lo = None if after is None else A.Duration(A.IntLit(after), "seconds")
        lim = A.TimeLimit(A.Duration(A.IntLit(within), "seconds"), lo)
    return A.Occurrence("E", kw.get("negated", False), lim, kw.get("eventually", False))


@pytest.mark.parametrize(
    ("occ", "has_otherwise", "untimed", "window"),
    [
        (occurrence(within=5), False, None, (10.0, 15.0)),
        (occurrence(within=5, after=2), False, None, (12.0, 15.0)),
        (occurrence(eventually=True), False, None, (10.0, None)),
        (occurrence(negated=True), False, None, (10.0, 10.0)),  # an untimed prohibition: the instant
        (occurrence(), True, None, (10.0, 10.0)),  # an untimed obligation with an otherwise
        (occurrence(), False, None, (10.0, None)),  # the reading's "no deadline"
        (occurrence(), False, 3.0, (10.0, 13.0)),
    ],
)
def test_an_items_window(
    occ: A.Occurrence, has_otherwise: bool, untimed: float | None, window: tuple[float, float | None]
) -> None:
    st = state()
    windows = Windows(st, Terms(st))
    lo, hi = windows.window(occ, has_otherwise, z3.RealVal(10, st.ctx), {}, untimed)
    got = (as_float(z3.simplify(lo)), None if hi is None else as_float(z3.simplify(hi)))
    assert got == window


def test_an_occurrence_counts_in_its_window_after_the_raising_step_only() -> None:
    st = state()
    windows = Windows(st, Terms(st))
    x, y = slot(st, 0, "E"), slot(st, 1, "E")
    lo, hi = z3.RealVal(1, st.ctx), z3.RealVal(2, st.ctx)
    occurs = windows.occurs("E", lo, hi, lambda s: s.t > x.t)
    st.solver.add(x.present, x.t == 0)
    assert proves(st, occurs == z3.And(y.present, y.t >= 1, y.t <= 2))
    assert proves(st, z3.Not(windows.occurs("F", lo, hi, lambda s: s.present)))  # no slot of F


def test_only_deadlines_the_reference_cannot_read_are_guarded() -> None:
    st = state()
    windows = Windows(st, Terms(st))
    snap = snapshot(Terms(st))
    timed = A.Response((A.ResponseItem(occurrence(within=5)),))
    assert windows.in_range(timed, snap) is None  # a constant deadline of 5 s: always readable
    longest = A.Response(
        (A.ResponseItem(A.Occurrence("E", limit=A.TimeLimit(A.Duration(A.IntLit(10**10), "seconds")))),)
    )
    assert windows.in_range(longest, snap) is None  # 1e10 s, the longest the reference reads
    huge = A.Response(
        (A.ResponseItem(A.Occurrence("E", limit=A.TimeLimit(A.Duration(A.IntLit(10**11), "seconds")))),)
    )
    assert windows.in_range(huge, snap) is not None
    read = A.Duration(A.Name("temp"), "seconds")
    by_measure = A.Response((A.ResponseItem(A.Occurrence("E", limit=A.TimeLimit(read))),))
    guard = windows.in_range(by_measure, snap)
    assert guard is not None and proves(st, guard == z3.And(snap["temp"] >= -1e10, snap["temp"] <= 1e10))


# ---------------------------------------------------------------- Relations


def test_what_each_relation_demands_beside_an_occurrence() -> None:
    st = state(
        relations=(
            A.EventRelation("witness", "A", "B"),
            A.EventRelation("equal", "C", "A"),
            A.EventRelation("happenBefore", "D", "A"),
            A.EventRelation("mutualExclusive", "A", "E"),  # demands nothing
            A.EventMeasureRelation("causation", "G", A.BoolLit(True)),
            A.UntilRelation(A.Trigger("A"), A.BoolLit(True), "H"),
        )
    )
    relations = Relations(st, Terms(st))
    assert list(relations.demands("A")) == [
        ("B", "witness A B"),
        ("C", "equal C A"),
        ("D", "happenBefore D A"),
        ("G", "causation G"),
        ("H", "until H"),
    ]
    assert list(relations.demands("B")) == [("G", "causation G")]
    assert list(relations.demands("G")) == []  # causation demands the event of others, not of itself


def test_measure_relations_hold_on_every_snapshot_guarded_by_their_literal() -> None:
    busy, hot = A.Name("busy"), A.Compare(">", A.Name("temp"), A.IntLit(40))
    st = state(relations=(A.MeasureRelation("imply", hot, busy), A.EventRelation("witness", "A", "B")))
    terms = Terms(st)
    relations = Relations(st, terms)
    snap = snapshot(terms)
    guarded = relations.assumptions(snap)
    lit = st.relation_lit[0]
    assert proves(st, guarded == z3.Implies(lit, z3.Implies(snap["temp"] > 40, snap["busy"])))
    mutual = A.MeasureRelation("mutualExclusive", hot, busy)
    assert proves(
        st, relations.on_snapshot(mutual, snap) == z3.Implies(snap["temp"] > 40, z3.Not(snap["busy"]))
    )
    iff = A.MeasureRelation("iff", hot, busy)
    assert proves(st, relations.on_snapshot(iff, snap) == (snap["busy"] == (snap["temp"] > 40)))


def test_an_event_relation_over_the_slots() -> None:
    st = state(relations=(A.EventRelation("witness", "A", "B"),))
    relations = Relations(st, Terms(st))
    a, b = slot(st, 0, "A"), slot(st, 1, "B")
    holds = relations.holds(st.spec.relations[0])
    assert proves(st, holds == z3.Implies(a.present, z3.And(b.present, b.t == a.t)))
