"""The checker's passes built alone on a Scope (lang/scope.py), without parsing or a Checker:
the declarations, the expressions, the responses and the unreachable-clause question."""

from __future__ import annotations

import pytest

from cosleec.lang import HedgeSemantics, Options
from cosleec.lang import ast as A
from cosleec.lang.compat import LegosReader
from cosleec.lang.declarations import Declarations, check_name, kind_word
from cosleec.lang.diagnostics import DiagnosticSink
from cosleec.lang.expressions import BOOL, NUM, Expressions, type_word
from cosleec.lang.responses import Responses
from cosleec.lang.scope import Scope
from cosleec.lang.unreachable import check_clauses

LVL = A.MeasureDecl("lvl", A.ScaleType(("low", "high")))
DEFS: tuple[A.Definition, ...] = (
    A.EventDecl("E"),
    A.MeasureDecl("a", A.BooleanType()),
    A.MeasureDecl("x", A.NumericType()),
    LVL,
    A.ConstantDecl("K", 5),
    A.ConstantDecl("J", "K"),
)


def scope(defs: tuple[A.Definition, ...] = DEFS, **opt: object) -> Scope:
    s = Scope(A.Specification(defs, ()), DiagnosticSink("t.sleec"), Options(**opt))  # type: ignore[arg-type]
    Declarations(s).check()
    return s


def codes(s: Scope) -> list[str]:
    return [d.code for d in s.sink.items]


# ---------------------------------------------------------------- declarations


def test_the_table_literals_and_constant_values() -> None:
    s = scope()
    assert s.sink.items == []
    assert (list(s.table.events), list(s.table.measures), s.table.constant_values) == (
        ["E"],
        ["a", "x", "lvl"],
        {"K": 5, "J": 5},
    )
    assert s.scale_literals == {"low", "high"} and s.owners_of == {"low": ["lvl"], "high": ["lvl"]}
    assert s.owners("low") == "lvl" and s.owners("nope") == ""


def test_a_cycle_of_constants_is_reported_once() -> None:
    s = scope((A.ConstantDecl("A1", "B1"), A.ConstantDecl("B1", "C1"), A.ConstantDecl("C1", "A1")))
    assert codes(s) == ["constant-cycle"]
    assert s.sink.items[0].message == "constants refer to each other in a cycle: A1 -> B1 -> C1 -> A1"
    assert s.table.constant_values == {}
    # a constant that leads into a cycle is not part of it: the cycle is said once, from its start
    lasso = scope((A.ConstantDecl("D1", "A1"), A.ConstantDecl("A1", "B1"), A.ConstantDecl("B1", "A1")))
    assert [d.message for d in lasso.sink.items] == [
        "constants refer to each other in a cycle: A1 -> B1 -> A1"
    ]


@pytest.mark.parametrize(
    ("defs", "expected"),
    [
        ((A.EventDecl("E"), A.EventDecl("E")), ["redeclared"]),  # the same again: a warning
        ((A.EventDecl("E"), A.MeasureDecl("E", A.BooleanType())), ["duplicate-name"]),
        ((A.MeasureDecl("m", A.ScaleType(("u", "u"))),), ["duplicate-literal"]),
        ((A.EventDecl("u"), A.MeasureDecl("m", A.ScaleType(("u",)))), ["literal-clash"]),
        ((A.ConstantDecl("C", "E"), A.EventDecl("E")), ["constant-ref"]),
        ((A.ConstantDecl("C", "KK"), A.ConstantDecl("K", 1)), ["undeclared"]),
        ((A.EventDecl("1E"),), ["malformed-name"]),
        ((A.FluentDecl("f", ("E",), ()),), ["unsupported-fluent"]),
    ],
)
def test_what_a_def_block_can_get_wrong(defs: tuple[A.Definition, ...], expected: list[str]) -> None:
    assert codes(scope(defs)) == expected


def test_lint_and_tk_names() -> None:
    defs = (
        A.EventDecl("e"),
        A.MeasureDecl("M", A.BooleanType()),
        A.ConstantDecl("k", 1),
        A.EventDecl("STOP"),
    )
    assert codes(scope(defs)) == []
    assert codes(scope(defs, lint=True)) == ["naming", "naming", "naming"]
    assert codes(scope(defs, tk_names=True)) == ["tk-reserved"]
    s = scope(())
    check_name(s, "P", A.NO_SPAN)  # a name SLEEC-TK rejects: only with tk_names
    assert codes(s) == []
    assert [kind_word(d) for d in DEFS[:3]] == ["an event", "a measure", "a measure"]


def test_did_you_mean_is_asked_once_per_name_and_only_when_shown() -> None:
    s = scope((*DEFS, A.ConstantDecl("LIMIT", 9)))
    assert s.did_you_mean("LIMT", "constants", "undeclared") == "did you mean `LIMIT`?"
    s.table.constants.clear()  # the answer given is kept
    assert s.did_you_mean("LIMT", "constants", "undeclared") == "did you mean `LIMIT`?"
    assert s.did_you_mean("LIMT", "events", "undeclared") is None  # among the events: nothing close
    with s.sink.folding("rule `R`", 1):
        s.sink.error("undeclared", "one")
        assert s.did_you_mean("lvll", "values", "undeclared") is None  # folded: not searched
    assert s.did_you_mean("lvll", "values", "undeclared") == "did you mean `lvl`?"


# ---------------------------------------------------------------- expressions


def expressions(s: Scope) -> Expressions:
    return Expressions(s, LegosReader(s))


@pytest.mark.parametrize(
    ("e", "ty"),
    [
        (A.Name("a"), BOOL),
        (A.Name("x"), NUM),
        (A.Name("K"), NUM),
        (A.Name("lvl"), ("scale", "lvl")),
        (A.Name("low"), ("lit", "low")),
        (A.BinOp("+", A.Name("x"), A.IntLit(1)), NUM),
        (A.Compare("<", A.Name("lvl"), A.Name("high")), BOOL),
        (A.Name("E"), None),  # an event is no value
    ],
)
def test_types(e: A.Expr, ty: object) -> None:
    assert expressions(scope()).expr(e) == ty


def test_constant_values_of_expressions() -> None:
    ex = expressions(scope())
    assert ex.const_eval(A.BinOp("*", A.Name("J"), A.BinOp("-", A.IntLit(3), A.IntLit(1)))) == 10
    assert ex.const_eval(A.BinOp("+", A.Name("x"), A.IntLit(1))) is None  # a measure is not constant


@pytest.mark.parametrize(("strict", "severity"), [(False, "warning"), (True, "error")])
def test_and_or_mixed_without_parentheses(strict: bool, severity: str) -> None:
    s = scope(strict_precedence=strict)
    e = A.BinOp("or", A.BinOp("and", A.Name("a"), A.Name("a")), A.Name("a"))
    expressions(s).condition(e)
    (d,) = s.sink.items
    assert (d.code, d.severity.value) == ("mixed-and-or", severity)
    paren = A.BinOp("or", A.BinOp("and", A.Name("a"), A.Name("a"), parenthesized=1), A.Name("a"))
    s2 = scope()
    expressions(s2).condition(paren)
    assert s2.sink.items == []


@pytest.mark.parametrize(
    ("e", "code"),
    [
        (A.Compare("=", A.Name("lvl"), A.Name("hgh")), "scale-literal"),  # no literal anywhere
        (A.Compare(">", A.Name("a"), A.Name("a")), "bool-relop"),
        (A.Compare("=", A.Name("low"), A.Name("high")), "type"),  # two literals
        (A.Compare("=", A.Name("x"), A.Name("low")), "type"),  # a literal and a number
        (A.Name("x"), "not-boolean"),
        (A.Compare("=", A.Name("x", arrow=True), A.IntLit(1)), "kind"),
    ],
)
def test_what_a_condition_can_get_wrong(e: A.Expr, code: str) -> None:
    s = scope()
    expressions(s).condition(e)
    assert codes(s) == [code]


def test_an_unknown_literal_gets_the_closest_of_the_scale() -> None:
    s = scope()
    expressions(s).condition(A.Compare("=", A.Name("lvl"), A.Name("hgh")))
    assert s.sink.items[0].hint == "did you mean `high`?"
    assert type_word(("scale", "lvl")) == "the scale of `lvl`" and type_word(None) == "an unknown value"


# ---------------------------------------------------------------- responses


def responses(s: Scope) -> Responses:
    return Responses(s, expressions(s))


@pytest.mark.parametrize(
    ("unit", "seconds", "hint"),
    [
        ("minutes", 120.0, None),
        ("minute", None, "SLEEC uses plural units: `minutes`"),
        ("Seconds", None, "units are keywords, written in lower case: `seconds`"),
        ("secnds", None, "did you mean `seconds`?"),
    ],
)
def test_a_durations_length_and_unit(unit: str, seconds: float | None, hint: str | None) -> None:
    s = scope()
    d = A.Duration(A.IntLit(2), unit, span=A.Span(1, 10, 1, 11 + len(unit)))
    assert responses(s).duration(d) == seconds
    if hint is None:
        assert s.sink.items == []
    else:
        (diag,) = s.sink.items
        assert (diag.code, diag.hint) == ("bad-unit", hint)
        assert diag.span == A.Span(1, 11, 1, 11 + len(unit))  # at the unit, the span's last token


def test_an_interval_that_starts_after_it_ends() -> None:
    s = scope()
    occ = A.Occurrence(
        "E", limit=A.TimeLimit(A.Duration(A.IntLit(1), "seconds"), A.Duration(A.Name("K"), "seconds"))
    )
    responses(s).response(A.Response((A.ResponseItem(occ),)))
    assert [(d.code, d.message) for d in s.sink.items] == [
        ("bad-deadline", "interval starts after it ends (5 s > 1 s)")
    ]
    s = scope()
    point = A.TimeLimit(A.Duration(A.IntLit(5), "seconds"), A.Duration(A.Name("K"), "seconds"))
    responses(s).response(A.Response((A.ResponseItem(A.Occurrence("E", limit=point)),)))
    assert s.sink.items == []  # [5 s, 5 s]: one instant, a window all the same


def test_an_event_where_a_response_names_something_else() -> None:
    s = scope((*DEFS, A.EventDecl("Start")))
    r = responses(s)
    r.event("a", A.NO_SPAN, "response")
    r.event("Strat", A.NO_SPAN, "trigger")
    assert [(d.code, d.message, d.hint) for d in s.sink.items] == [
        ("not-an-event", "response `a` is a measure, not an event", None),
        ("undeclared-event", "trigger `Strat` is not declared as an event", "did you mean `Start`?"),
    ]


# ---------------------------------------------------------------- unreachable clauses


def clauses(*conds: A.Expr) -> A.Response:
    return A.Response((A.ResponseItem(A.Occurrence("E")),), tuple(A.Defeater(c) for c in conds))


@pytest.mark.parametrize(
    ("semantics", "conds", "found"),
    [
        (HedgeSemantics.LAST_WINS, (A.Name("a"), A.Name("a")), [("duplicate-hedge", 1)]),
        (HedgeSemantics.LAST_WINS, (A.BoolLit(False), A.Name("a")), [("unreachable-hedge", 1)]),
        (HedgeSemantics.LAST_WINS, (A.Name("a"), A.BoolLit(True)), [("unreachable-hedge", 1)]),
        (
            HedgeSemantics.NESTED,
            (A.BoolLit(False), A.Name("a")),
            [("unreachable-hedge", 1), ("unreachable-hedge", 2)],
        ),
        (HedgeSemantics.LAST_WINS, (A.Name("a"), A.Name("x")), []),
    ],
)
def test_clauses_no_situation_selects(
    semantics: HedgeSemantics, conds: tuple[A.Expr, ...], found: list[tuple[str, int]]
) -> None:
    sink = DiagnosticSink("t.sleec")
    resp = clauses(*conds)
    resp = A.Response(
        resp.items,
        tuple(A.Defeater(d.condition, span=A.Span(i + 1, 1, i + 1, 9)) for i, d in enumerate(resp.defeaters)),
    )
    check_clauses(sink, semantics, resp)
    assert [(d.code, d.span.line) for d in sink.items] == found
