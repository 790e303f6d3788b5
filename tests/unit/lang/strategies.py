"""Hypothesis strategies for SLEEC ASTs (used by round-trip and fuzz tests)."""

from __future__ import annotations

from hypothesis import strategies as st

from cosleec.lang import ast as A

EVENTS = ["Start", "Stop", "Alarm", "Help"]
BOOLS = ["flag", "busy"]
NUMS = ["temp"]
SCALE = ("level", ("lo", "mid", "hi"))
CONSTS = ["LIMIT", "ALIAS"]

DEFINITIONS: tuple[A.Definition, ...] = (
    *(A.EventDecl(e) for e in EVENTS),
    *(A.MeasureDecl(b, A.BooleanType()) for b in BOOLS),
    *(A.MeasureDecl(n, A.NumericType()) for n in NUMS),
    A.MeasureDecl(SCALE[0], A.ScaleType(SCALE[1])),
    A.ConstantDecl("LIMIT", 30),
    A.ConstantDecl("ALIAS", "LIMIT"),
)

num_leaf = st.one_of(
    st.integers(-50, 500).map(A.IntLit),
    st.sampled_from(NUMS + CONSTS).map(A.Name),
)
num_expr = st.recursive(
    num_leaf,
    lambda inner: st.builds(A.BinOp, st.sampled_from(["+", "-", "*"]), inner, inner),
    max_leaves=4,
)
rel = st.sampled_from(["<", "<=", ">", ">=", "=", "<>"])
bool_leaf = st.one_of(
    st.sampled_from(BOOLS).map(A.Name),
    st.booleans().map(A.BoolLit),
    st.builds(A.Compare, rel, num_expr, num_expr),
    st.builds(lambda op, lit: A.Compare(op, A.Name(SCALE[0]), A.Name(lit)), rel, st.sampled_from(SCALE[1])),
)
condition = st.recursive(
    bool_leaf,
    lambda inner: st.one_of(
        st.builds(A.Not, inner),
        st.builds(A.BinOp, st.sampled_from(["and", "or"]), inner, inner),
    ),
    max_leaves=6,
)
duration = st.builds(A.Duration, num_expr, st.sampled_from(list(A.TIME_UNITS)))
time_limit = st.one_of(st.builds(A.TimeLimit, duration), st.builds(A.TimeLimit, duration, duration))
occurrence = st.builds(
    A.Occurrence, st.sampled_from(EVENTS), st.booleans(), st.none() | time_limit, st.booleans()
)


def _response(inner: st.SearchStrategy[A.Response]) -> st.SearchStrategy[A.Response]:
    item = st.builds(A.ResponseItem, occurrence, st.none() | inner, st.none() | inner)
    defeater = st.builds(A.Defeater, condition, st.none() | inner)
    return st.builds(
        A.Response,
        st.lists(item, min_size=1, max_size=2).map(tuple),
        st.lists(defeater, max_size=3).map(tuple),
    )


simple_response = st.builds(
    A.Response, st.lists(st.builds(A.ResponseItem, occurrence), min_size=1, max_size=2).map(tuple)
)
response = st.recursive(simple_response, _response, max_leaves=5)
trigger = st.builds(A.Trigger, st.sampled_from(EVENTS), st.none() | condition)

relation = st.one_of(
    st.builds(
        A.EventRelation,
        st.sampled_from(["witness", "equal", "mutualExclusive", "happenBefore"]),
        st.sampled_from(EVENTS),
        st.sampled_from(EVENTS),
    ),
    st.builds(
        A.MeasureRelation,
        st.sampled_from(["imply", "iff", "opposite", "mutualExclusive"]),
        condition,
        condition,
    ),
    st.builds(A.MeasureRelation, st.just("invariant"), condition),
    st.builds(
        A.EventMeasureRelation,
        st.sampled_from(["causation", "includes", "forbid"]),
        st.sampled_from(EVENTS),
        condition,
    ),
    st.builds(A.UntilRelation, trigger, condition, st.sampled_from(EVENTS), st.none() | condition),
    st.builds(A.ForRelation, trigger, condition, duration),
)
situation = st.builds(
    A.Situation,
    st.just(""),
    st.sampled_from(["when", "exists"]),
    trigger,
    st.lists(response, max_size=2).map(tuple),
)


@st.composite
def specifications(draw: st.DrawFn) -> A.Specification:
    rules = draw(st.lists(st.builds(A.Rule, st.just(""), trigger, response), min_size=1, max_size=3))
    rules = [A.Rule(f"R{i}", r.trigger, r.response) for i, r in enumerate(rules)]
    concerns = [
        A.Situation(f"c{i}", s.kind, s.trigger, s.responses)
        for i, s in enumerate(draw(st.lists(situation, max_size=2)))
    ]
    purposes = [
        A.Situation(f"p{i}", s.kind, s.trigger, s.responses)
        for i, s in enumerate(draw(st.lists(situation, max_size=2)))
    ]
    return A.Specification(
        DEFINITIONS,
        tuple(rules),
        tuple(concerns),
        tuple(purposes),
        tuple(draw(st.lists(relation, max_size=3))),
    )
