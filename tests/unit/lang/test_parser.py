"""Parsing: both dialects, the paper notation, attachment rules (§4.5), syntax errors."""

from __future__ import annotations

import pytest

from cosleec.lang import analyse, format_spec, parse
from cosleec.lang import ast as A
from cosleec.lang.parser import CONTEXTUAL_KEYWORDS, KEYWORDS

DEFS = """def_start
  event E event F event G event H
  measure a : boolean measure b : boolean measure c : boolean measure d : boolean
  measure x : numeric measure lvl : scale(low, medium, high)
  constant K = 5
def_end
"""


def rules(body: str, **kw: object) -> tuple[A.Rule, ...]:
    return parse(DEFS + "rule_start\n" + body + "\nrule_end\n", **kw).rules  # type: ignore[arg-type]


def n(name: str) -> A.Name:
    return A.Name(name)


def test_tk_and_or_share_one_level_left_to_right() -> None:
    (r,) = rules("R when E and a and b or c and d then F")
    assert r.trigger.condition == A.BinOp(
        "and", A.BinOp("or", A.BinOp("and", n("a"), n("b")), n("c")), n("d")
    )


def test_not_binds_tighter_than_and_but_looser_than_comparison() -> None:
    (r,) = rules("R when E and not a and b then F")
    assert r.trigger.condition == A.BinOp("and", A.Not(n("a")), n("b"))
    (r,) = rules("R when E and not x > 5 then F")
    assert r.trigger.condition == A.Not(A.Compare(">", n("x"), A.IntLit(5)))


def test_legos_braces_parse_to_the_same_ast_as_tk() -> None:
    (tk,) = rules("R when E and not a then F within 60 seconds unless lvl > medium then F within 10 seconds")
    (lg,) = rules(
        "R when E and (not {a}) then F within 60 seconds unless ({lvl} > medium) then F within 10 seconds"
    )
    assert tk == lg


def test_unless_belongs_to_the_rule_not_to_otherwise() -> None:
    (r,) = rules("R when E then F within 5 seconds otherwise G unless a then H")
    assert len(r.response.defeaters) == 1
    item = r.response.items[0]
    assert item.otherwise is not None and item.otherwise.defeaters == ()


def test_braced_otherwise_branch_carries_its_own_defeater() -> None:
    (r,) = rules("R when E then F within 5 seconds otherwise {G unless a} unless b then H")
    fallback = r.response.items[0].otherwise
    assert fallback is not None and len(fallback.defeaters) == 1
    assert len(r.response.defeaters) == 1


def test_otherwise_chains_nest_to_the_right_and_else_is_greedy() -> None:
    (r,) = rules("R when E then F within 1 seconds otherwise G within 2 minutes otherwise H")
    inner = r.response.items[0].otherwise
    assert inner is not None and inner.items[0].otherwise is not None
    (r,) = rules("R when E then F within 5 seconds otherwise G else H")
    item = r.response.items[0]
    assert item.alternative is None
    assert item.otherwise is not None and item.otherwise.items[0].alternative is not None


def test_unbraced_then_branch_ends_at_the_next_unless() -> None:
    (r,) = rules("R when E then F unless a then G unless b then H unless c")
    assert [d.response is None for d in r.response.defeaters] == [False, False, True]


def test_conjunction_extension_and_strict_rejects_it() -> None:
    (r,) = rules("R when E then F and G within 3 seconds unless a then H and F")
    assert [i.occurrence.event for i in r.response.items] == ["F", "G"]
    d = r.response.defeaters[0].response
    assert d is not None and [i.occurrence.event for i in d.items] == ["H", "F"]
    result = analyse(DEFS + "rule_start R when E then F and G rule_end", strict=True)
    assert [x.code for x in result.errors] == ["extension-conjunction"]


def test_legos_forms() -> None:
    (r,) = rules("R when E then F within [1 seconds, 30 seconds] else G eventually")
    occ = r.response.items[0].occurrence
    assert occ.limit is not None and occ.limit.lo is not None
    (r,) = rules("R when E then F within (120 - ((22 - {x}) * 15)) seconds")
    assert r.response.items[0].occurrence.limit is not None
    (r,) = rules("R when E then not F")
    assert r.response.items[0].occurrence.negated


def test_a_sign_is_part_of_the_number_and_its_spacing_is_recorded() -> None:
    # (a signed number is LEGOS syntax, the rest TK: a dialect mix, but the tree is built)
    spec = analyse(DEFS + "rule_start\nR when E and x > - 3 and x < +4 and x <> -5 then F\nrule_end").spec
    assert spec is not None
    c = spec.rules[0].trigger.condition
    assert c == A.BinOp(
        "and",
        A.BinOp("and", A.Compare(">", n("x"), A.IntLit(-3)), A.Compare("<", n("x"), A.IntLit(4))),
        A.Compare("<>", n("x"), A.IntLit(-5)),
    )
    lits = [cmp.right for cmp in (c.left.left, c.left.right, c.right)]  # type: ignore[union-attr]
    assert [(lit.sign, lit.span[1], lit.span[3]) for lit in lits] == [
        ("- ", 18, 21),
        ("+", 30, 32),
        ("-", 42, 44),
    ]
    (r,) = rules("R when E and ((x - 3) > 0) then F")  # after a number, `-` is subtraction
    assert r.trigger.condition == A.Compare(">", A.BinOp("-", n("x"), A.IntLit(3)), A.IntLit(0))


def test_parentheses_are_counted() -> None:
    (r,) = rules("R when E and ((x > 3)) and (((a))) and (2) > x then F")
    c = r.trigger.condition
    assert isinstance(c, A.BinOp) and isinstance(c.left, A.BinOp) and isinstance(c.right, A.Compare)
    assert (c.left.left.parenthesized, c.left.right.parenthesized, c.right.left.parenthesized) == (2, 3, 1)
    assert c.parenthesized == 0


def test_tk_keyword_escape_and_comments() -> None:
    spec = parse(
        "/* block\n comment */ def_start event ^E // line\n event F def_end rule_start R when E then F rule_end"
    )
    assert spec.rules[0].trigger.event == "E"


def test_paper_notation_is_case_insensitive_and_names_rules() -> None:
    spec = parse(
        "WHEN CurtainOpenRequest THEN OpenCurtains\n"
        "UNLESS UserUndressed IN WHICH CASE (Refuse AND ExplainWhy)\n"
        "unless UserDistressed in which case (WarnUser and OpenCurtains)\n"
        "when Fall then CallNurse within 2 minutes\n"
    )
    assert spec.dialect is A.Dialect.PAPER
    assert [r.name for r in spec.rules] == ["R1", "R2"]
    r1 = spec.rules[0]
    assert [d.condition for d in r1.response.defeaters] == [n("UserUndressed"), n("UserDistressed")]
    assert {e.name for e in spec.events} >= {"CurtainOpenRequest", "Refuse", "ExplainWhy", "WarnUser"}
    assert all(isinstance(m.type, A.BooleanType) for m in spec.measures)


@pytest.mark.parametrize(
    ("text", "dialect"),
    [
        ("R when E and a then F", A.Dialect.TK),
        ("R when E and {a} then F", A.Dialect.LEGOS),
        ("R when E then F eventually", A.Dialect.LEGOS),
        ("R when E then F", A.Dialect.TK),
    ],
)
def test_dialect_detection(text: str, dialect: A.Dialect) -> None:
    assert analyse(DEFS + "rule_start " + text + " rule_end").dialect is dialect


def test_forced_dialects_are_strict() -> None:
    codes = {
        d.code for d in analyse(DEFS + "rule_start R when E and {a} then F rule_end", dialect="tk").errors
    }
    assert codes == {"dialect"}
    errs = analyse(DEFS + "rule_start R when E and a and b then F rule_end", dialect="legos").errors
    assert {d.code for d in errs} == {"dialect"} and len(errs) >= 2


def test_mixed_dialects_are_rejected_at_the_tk_construct() -> None:
    errs = analyse(DEFS + "rule_start R when E and {a} and {b} then F rule_end").errors
    assert errs and all(e.code == "mixed-dialect" for e in errs)
    assert errs[0].span.line == 7


@pytest.mark.parametrize(
    ("body", "code"),
    [
        ("R when E or F then G", "trigger-or"),
        ("R when not E then G", "negated-trigger"),
        ("R when E and x < 1 < 2 then G", "comparison-chain"),
        ("R when E then G within 4 / 2 seconds", "division"),
        ("R when E then Gé", "non-ascii"),
        ("R when E then G /* open", "unterminated-comment"),
        ("R when E then then", "syntax"),
    ],
)
def test_syntax_errors_have_precise_messages(body: str, code: str) -> None:
    result = analyse(DEFS + "rule_start\n" + body + "\nrule_end")
    assert result.errors and result.errors[0].code == code
    assert result.errors[0].span.line == 8
    assert result.spec is None


def test_several_syntax_errors_are_reported_in_one_run() -> None:
    text = (
        DEFS
        + "rule_start\nR1 when E or F then G\nR2 when E then G within 4 / 2 seconds\nR3 when not E then G\nrule_end"
    )
    codes = [d.code for d in analyse(text).errors]
    assert codes == ["trigger-or", "division", "negated-trigger"]


def test_rtf_and_block_structure_errors() -> None:
    assert [d.code for d in analyse("{\\rtf1\\ansi def_start").errors] == ["rtf"]
    assert "block-order" in {
        d.code
        for d in analyse("rule_start R when E then F rule_end def_start event E event F def_end").errors
    }
    result = analyse("def_start event E event F def_end relation_begin")
    assert result.errors[0].hint == "did you mean `relation_start`?"


def test_reserved_keywords_cannot_be_names() -> None:
    result = analyse("def_start event when def_end rule_start R when when then when rule_end")
    assert result.errors
    (err,) = analyse("def_start event fluent def_end rule_start R when E then F rule_end").errors
    assert err.code == "syntax" and err.hint == "`fluent` is a reserved keyword and cannot be used as a name"


# the language reference §3, plus the words of the fork extensions (§4.6) the grammar parses
# and of cosleec's priority and semantics blocks (§13.4, §7.4)
RESERVED = {
    *("def_start", "def_end", "rule_start", "rule_end", "concern_start", "concern_end"),
    *("purpose_start", "purpose_end", "relation_start", "relation_end", "priority_start", "priority_end"),
    *("semantics_start", "semantics_end"),
    *("event", "measure", "constant", "boolean", "numeric", "scale", "when", "then", "and", "or", "not"),
    *("within", "otherwise", "unless", "else", "eventually", "exists", "while", "meanwhile"),
    *("true", "false", "seconds", "minutes", "hours", "days", "fluent"),
}
RELATION_ONLY = {
    *("witness", "mutualExclusive", "equal", "happenBefore", "isContradictoryWith", "imply", "iff"),
    *("opposite", "invariant", "causation", "includes", "forbid", "until", "for", "conflict", "effect"),
}


def test_keywords_read_from_the_grammar_are_the_reference_ones() -> None:
    assert RESERVED == KEYWORDS
    assert RELATION_ONLY == CONTEXTUAL_KEYWORDS


def test_tk_escape_makes_a_keyword_a_name() -> None:
    """SLEEC-TK's `^when` is the name `when` (the language reference §3); the printer writes it back."""
    text = (
        "def_start event ^when event F measure ^within : boolean def_end\n"
        "rule_start R when ^when and ^within then F unless not ^within then ^when rule_end"
    )
    result = analyse(text)
    assert result.ok, result.render()
    assert result.spec is not None
    (r,) = result.spec.rules
    assert r.trigger == A.Trigger("when", n("within"))
    assert {e.name for e in result.spec.events} == {"when", "F"}
    printed = format_spec(result.spec)
    assert "event ^when" in printed and "then ^when" in printed
    assert parse(printed) == result.spec
    # the escape is TK syntax: LEGOS-SLEEC's grammar has no `^`
    errs = analyse(text, dialect="legos").errors
    assert {e.code for e in errs} == {"dialect"}
    assert any("`^` keyword escape" in e.message for e in errs)


def test_relation_keywords_are_reserved_only_in_relation_blocks() -> None:
    text = (
        "def_start event witness event until event F measure for : boolean def_end\n"
        "rule_start R when witness and for then until rule_end\n"
        "relation_start witness ^witness F when F and ^for then true until ^until relation_end"
    )
    result = analyse(text)
    assert not [e for e in result.errors if e.code == "syntax"], result.render()
    assert result.spec is not None
    assert result.spec.relations[0] == A.EventRelation("witness", "witness", "F")
    # printed back with escapes, which no tool reads next to a relation block (a TK/LEGOS mix)
    again = analyse(format_spec(result.spec))
    assert again.spec == result.spec
    assert {e.code for e in again.errors} == {"mixed-dialect"}
    bad = analyse(DEFS + "rule_start R when E then F rule_end relation_start witness E until relation_end")
    assert [e.code for e in bad.errors] == ["syntax"]


def test_paper_notation_has_comments_like_the_dsl() -> None:
    spec = parse("// the paper's rules\nWHEN Fall THEN CallNurse /* soon */ WITHIN 2 minutes\n")
    assert spec.dialect is A.Dialect.PAPER and len(spec.rules) == 1


def test_the_ast_knows_the_grammars_comparison_operators() -> None:
    from cosleec.lang import ast as A
    from cosleec.lang.parser import SLEEC

    assert SLEEC.rel_ops == A.REL_OPS
