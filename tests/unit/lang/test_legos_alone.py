"""The checker's LEGOS pieces built alone, on a hand-made scope: :class:`LegosReader` (compat.py,
how ``legos_compat`` reads what LEGOS-SLEEC lets through) and the LEGOS-SLEEC blocks
(legos.py: concerns, purposes, relations) -- no parser, no Checker."""

from __future__ import annotations

import pytest

from cosleec.lang import Options
from cosleec.lang import ast as A
from cosleec.lang.compat import LegosReader, LegosReading
from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink
from cosleec.lang.expressions import Expressions
from cosleec.lang.legos import check_relations, check_situations
from cosleec.lang.responses import Responses
from cosleec.lang.scope import Scope

M = A.MeasureDecl("m", A.ScaleType(("m1", "m2", "m3")))
S = A.MeasureDecl("s", A.ScaleType(("s0", "s1", "s2", "s3", "s4")))
AT = A.Span(3, 7, 3, 9)


def scope(*, legos_compat: bool = True, repeat_limit: int = 20, **spec: object) -> Scope:
    """A scope whose table knows the events E, F, the scale measures m and s (and the
    constant K = 1), as the declarations pass leaves it."""
    s = Scope(
        A.Specification((), (), **spec),  # type: ignore[arg-type]
        DiagnosticSink("t.sleec"),
        Options(legos_compat=legos_compat, repeat_limit=repeat_limit),
    )
    s.table.events.update(E=A.EventDecl("E"), F=A.EventDecl("F"))
    s.table.measures.update(m=M, s=S)
    s.table.constants["K"] = A.ConstantDecl("K", 1)
    s.table.constant_values["K"] = 1
    for decl in (M, S):
        assert isinstance(decl.type, A.ScaleType)
        for lit in decl.type.literals:
            s.owners_of.setdefault(lit, []).append(decl.name)
            s.scale_literals.add(lit)
    return s


def measure() -> A.Name:
    return A.Name("m", braced=True)


def only(sink: DiagnosticSink) -> Diagnostic:
    (d,) = sink.items
    return d


# ---------------------------------------------------------------- LegosReader: literals of another scale


def test_a_literal_of_another_scale_is_read_as_the_literal_at_its_position() -> None:
    sc = scope()
    reader = LegosReader(sc)
    lit = A.Name("s1", parenthesized=1, span=AT)
    e = A.Compare("=", measure(), lit)
    assert reader.literal(e, lit, "s1", "m", M.type)  # type: ignore[arg-type]
    old, new = reader.reading.exprs[id(lit)]
    assert old is lit and new == A.Name("m2") and new.span == AT and new.parenthesized == 1
    d = only(sc.sink)
    assert (d.severity.value, d.code, d.span) == ("warning", "scale-literal", AT)
    assert d.message == (
        "`s1` is not in the scale of `m` (m1, m2, m3); LEGOS-SLEEC reads a scale literal as its "
        "position in its own scale, and `s1` is the 2nd of `s`'s, so cosleec reads it as `m2`, "
        "the 2nd of `m`'s"
    )
    assert d.hint == "write `m2` if that is what is meant"


@pytest.mark.parametrize(
    ("op", "literal_on_the_left", "value"),
    [
        ("<", False, True),  # every position of m (0..2) is below 4
        (">=", False, False),
        ("=", False, False),
        ("<>", False, True),
        ("<", True, False),  # s4 < {m}: m > 4, never
        (">", True, True),  # s4 > {m}: m < 4, always
    ],
)
def test_a_literal_beyond_the_scale_makes_the_comparison_a_constant(
    op: str, literal_on_the_left: bool, value: bool
) -> None:
    sc = scope()
    reader = LegosReader(sc)
    lit = A.Name("s4", span=AT)
    e = A.Compare(op, lit, measure()) if literal_on_the_left else A.Compare(op, measure(), lit)
    e = A.Compare(e.op, e.left, e.right, parenthesized=2, span=A.Span(3, 1, 3, 20))
    lit = e.left if literal_on_the_left else e.right
    assert reader.literal(e, lit, "s4", "m", M.type)  # type: ignore[arg-type]
    ((old, new),) = reader.reading.exprs.values()
    assert old is e and new == A.BoolLit(value) and new.span == e.span and new.parenthesized == 2
    d = only(sc.sink)
    assert d.code == "scale-literal" and d.span == AT
    assert "beyond the 3 of `m`'s" in d.message and f"always {str(value).lower()}" in d.message


@pytest.mark.parametrize(("op", "value"), [("<", True), (">=", False), ("=", False)])
def test_a_literal_just_past_the_scale_is_beyond_it(op: str, value: bool) -> None:
    """A one-literal scale (position 0) against the 2nd literal of another (position 1)."""
    sc = scope()
    sc.table.measures["one"] = A.MeasureDecl("one", A.ScaleType(("only",)))
    reader = LegosReader(sc)
    lit = A.Name("s1")
    e = A.Compare(op, A.Name("one", braced=True), lit)
    assert reader.literal(e, lit, "s1", "one", sc.table.measures["one"].type)  # type: ignore[arg-type]
    ((old, new),) = reader.reading.exprs.values()
    assert old is e and new == A.BoolLit(value)
    assert "beyond the 1 of `one`'s" in only(sc.sink).message


def test_a_literal_at_two_positions_has_no_legos_reading() -> None:
    """LEGOS-SLEEC's one table of literals asserts a literal has one position."""
    sc = scope()
    other = A.MeasureDecl("t", A.ScaleType(("x", "s1")))  # s1 is 2nd here too: still one position
    far = A.MeasureDecl("u", A.ScaleType(("s1",)))  # ... and 1st here: two positions
    sc.table.measures.update(t=other, u=far)
    reader = LegosReader(sc)
    sc.owners_of["s1"] += ["t"]
    assert reader.position("s1") == 1
    sc.owners_of["s1"] += ["u"]
    assert reader.position("s1") is None
    lit = A.Name("s1")
    assert not reader.literal(A.Compare("=", measure(), lit), lit, "s1", "m", M.type)  # type: ignore[arg-type]
    assert not reader.number(lit, "s1")
    assert sc.sink.items == [] and not reader.reading


# ---------------------------------------------------------------- LegosReader: scales and numbers


def test_a_literal_compared_with_a_number_is_read_as_its_position() -> None:
    sc = scope()
    reader = LegosReader(sc)
    lit = A.Name("s3", parenthesized=1, span=AT)
    assert reader.number(lit, "s3")
    ((old, new),) = reader.reading.exprs.values()
    assert old is lit and new == A.IntLit(3) and new.span == AT and new.parenthesized == 1
    d = only(sc.sink)
    assert (d.code, d.span) == ("type", AT)
    assert d.message.startswith("scale literal `s3` (of `s`) is compared with a number;")
    assert d.message.endswith("so cosleec reads it as 3")


@pytest.mark.parametrize(
    ("op", "c", "reading"),
    [
        (">", 0, A.Name("m1")),
        (">", 2, A.Name("m3")),
        (">", 3, A.BoolLit(False)),  # beyond the scale: m (0..2) > 3 never holds
        ("<", 3, A.BoolLit(True)),
        (">", -1, A.BoolLit(True)),  # below it: m > -1 always holds
        ("=", -1, A.BoolLit(False)),
    ],
)
def test_a_scale_compared_with_a_constant_number(op: str, c: int, reading: A.Expr) -> None:
    sc = scope()
    reader = LegosReader(sc)
    number = A.IntLit(c, span=AT)
    e = A.Compare(op, measure(), number, span=A.Span(3, 1, 3, 20))
    assert reader.scale_number(e, "m", number, op, c)
    ((old, new),) = reader.reading.exprs.values()
    assert new == reading
    assert old is (number if isinstance(reading, A.Name) else e)
    d = only(sc.sink)
    assert d.code == "type" and d.span == e.span
    assert d.hint == "compare with a literal of `m`: m1, m2, m3"
    assert "(0 to 2)" in d.message


def test_a_named_constant_is_shown_with_its_value() -> None:
    sc = scope()
    reader = LegosReader(sc)
    k = A.Name("K")
    assert reader.scale_number(A.Compare("=", measure(), k), "m", k, "=", 1)
    assert "with a number (`K` = 1)" in only(sc.sink).message
    assert reader.reading.exprs[id(k)][1] == A.Name("m2")


# ---------------------------------------------------------------- LegosReader: names defined twice


def test_later_definitions_get_fresh_names_clear_of_every_name_in_use() -> None:
    reader = LegosReader(scope())
    rules = [A.Rule(n, A.Trigger("E"), A.Response(())) for n in ("R", "R", "R__2", "R")]
    nth: dict[str, int] = {}
    assert reader.rename(reader.reading.rules, 1, "R", nth, rules) == "R__3"  # R__2 is taken
    assert reader.rename(reader.reading.rules, 3, "R", nth, rules) == "R__4"  # R__3 given already
    assert reader.reading.rules == {1: "R__3", 3: "R__4"} and nth == {"R": 3}
    # each block's names are its own: a concern R is not a rule R
    concerns = [A.Situation("R", "when", A.Trigger("E")), A.Situation("R", "when", A.Trigger("E"))]
    assert reader.rename(reader.reading.concerns, 1, "R", {}, concerns) == "R__2"
    assert reader.reading


def test_an_empty_reading_is_falsy() -> None:
    assert not LegosReading() and not LegosReader(scope()).reading


# ---------------------------------------------------------------- legos.py: concerns and purposes


def responses(sc: Scope) -> Responses:
    return Responses(sc, Expressions(sc, LegosReader(sc)))


def situation(
    name: str, event: str = "E", *, line: int = 1, meanwhile: A.Situation | None = None
) -> A.Situation:
    return A.Situation(
        name,
        "when",
        A.Trigger(event, span=A.Span(line, 5, line, 6)),
        (A.Response((A.ResponseItem(A.Occurrence("F")),)),),
        meanwhile,
        span=A.Span(line, 1, line, 30),
    )


@pytest.mark.parametrize("legos_compat", [False, True])
def test_a_second_concern_of_a_name(legos_compat: bool) -> None:
    sc = scope(
        legos_compat=legos_compat,
        concerns=(situation("c", line=1), situation("c", line=2)),
        purposes=(situation("c", line=3),),  # a purpose c is no concern c
    )
    legos = LegosReader(sc)
    check_situations(sc, responses(sc), legos)
    d = only(sc.sink)
    assert d.code == "duplicate-name" and d.span.line == 2
    assert d.related == (("first defined here", A.Span(1, 1, 1, 30)),)
    if legos_compat:
        assert d.severity.value == "warning" and "calling this one `c__2`" in d.message
        assert d.hint == "give each concern a name of its own"
        assert legos.reading.concerns == {1: "c__2"} and legos.reading.purposes == {}
    else:
        assert d.severity.value == "error" and d.message == "concern `c` is defined twice"
        assert not legos.reading


def test_every_later_definition_points_at_the_first() -> None:
    sc = scope(legos_compat=True, concerns=tuple(situation("c", line=n) for n in (1, 2, 3)))
    legos = LegosReader(sc)
    check_situations(sc, responses(sc), legos)
    assert [d.related[0][1].line for d in sc.sink.items] == [1, 1]
    assert legos.reading.concerns == {1: "c__2", 2: "c__3"}


def test_every_situation_of_a_meanwhile_chain_is_checked() -> None:
    inner = situation("", "Nope", line=4)
    sc = scope(purposes=(situation("p", line=3, meanwhile=inner),))
    check_situations(sc, responses(sc), LegosReader(sc))
    d = only(sc.sink)
    assert (d.code, d.span.line) == ("undeclared-event", 4)
    assert d.message == "trigger `Nope` is not declared as an event"


def test_a_situations_repeated_mistakes_are_folded_under_its_name() -> None:
    bad = A.Response(tuple(A.ResponseItem(A.Occurrence(f"X{i}")) for i in range(3)))
    sc = scope(repeat_limit=1, concerns=(A.Situation("c", "when", A.Trigger("E"), (bad,)),))
    check_situations(sc, responses(sc), LegosReader(sc))
    assert [d.code for d in sc.sink.items] == ["undeclared-event", "undeclared-event"]
    assert sc.sink.items[1].message.startswith(
        "... and 2 more `undeclared-event` errors like this in concern `c`"
    )


# ---------------------------------------------------------------- legos.py: relations


@pytest.mark.parametrize(
    ("relation", "instead"),
    [
        (A.EventRelation("conflict", "E", "F"), "mutualExclusive"),
        (A.MeasureRelation("conflict", A.BoolLit(True), A.BoolLit(True)), "measure mutualExclusive"),
        (A.EventMeasureRelation("effect", "E", A.BoolLit(True)), "includes"),
    ],
)
def test_a_relation_word_no_grammar_has_is_an_error(relation: A.Relation, instead: str) -> None:
    sc = scope(relations=(relation,))
    check_relations(sc, responses(sc))
    d = only(sc.sink)
    assert d.code == "nonstandard-relation" and d.severity.value == "error"
    assert d.hint == f"did you mean `{instead}`?"


def test_a_relations_events_and_conditions_are_checked() -> None:
    at = A.Span(7, 1, 7, 40)
    relations: tuple[A.Relation, ...] = (
        A.EventRelation("witness", "E", "Nope", span=at),
        A.MeasureRelation("imply", A.BoolLit(True), A.IntLit(3)),
        A.EventMeasureRelation("includes", "Gone", A.BoolLit(True), span=at),
        A.UntilRelation(A.Trigger("E"), A.BoolLit(True), "Later", A.IntLit(1), span=at),
        A.ForRelation(A.Trigger("E"), A.BoolLit(True), A.Duration(A.IntLit(2), "parsecs", span=at)),
    )
    sc = scope(relations=relations)
    check_relations(sc, responses(sc))
    assert [(d.code, d.message) for d in sc.sink.items] == [
        ("undeclared-event", "relation `Nope` is not declared as an event"),
        ("not-boolean", "a condition must be true or false, not a number"),
        ("undeclared-event", "relation `Gone` is not declared as an event"),
        ("undeclared-event", "relation `Later` is not declared as an event"),
        ("not-boolean", "a condition must be true or false, not a number"),
        ("bad-unit", "`parsecs` is not a time unit"),
    ]
    assert {d.span for d in sc.sink.items if d.code == "undeclared-event"} == {at}
