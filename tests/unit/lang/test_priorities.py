"""Rule priorities, cosleec's extension (sleec-language.md §13.4): the `priority_start` block,
its checks, the strict modes, the printer, and the functions of `cosleec.lang.priorities`."""

from __future__ import annotations

import random
from itertools import pairwise

import pytest

from cosleec.errors import UserError
from cosleec.lang import analyse, closure, cycle, format_spec, pairs, parse, parse_priority
from cosleec.lang import ast as A
from cosleec.lang.diagnostics import Diagnostic, Severity

RULES = """def_start
  event E event F
  measure m : boolean
def_end
rule_start
  Rule1 when E then F
  Rule2 when F then E
  Rule3 when E then F within 5 seconds
  Rule21 when E and m then F
rule_end
"""


def spec_with(block: str, **kw: object) -> A.Specification:
    return parse(RULES + block, **kw)  # type: ignore[arg-type]


def diagnostics(block: str, **kw: object) -> list[Diagnostic]:
    return analyse(RULES + block, "rules.sleec", **kw).diagnostics  # type: ignore[arg-type]


def codes(block: str, **kw: object) -> list[str]:
    return [d.code for d in diagnostics(block, **kw)]


# ---------------------------------------------------------------------------- parsing


def test_a_single_pair() -> None:
    spec = spec_with("priority_start Rule21 > Rule3 priority_end")
    assert spec.priorities == (A.Priority("Rule21", "Rule3"),)
    assert pairs(spec) == [("Rule21", "Rule3")]


def test_a_chain_declares_its_consecutive_pairs() -> None:
    spec = spec_with("priority_start\n  Rule21 > Rule3 > Rule2 > Rule1\npriority_end")
    assert pairs(spec) == [("Rule21", "Rule3"), ("Rule3", "Rule2"), ("Rule2", "Rule1")]


def test_entries_need_no_separator_and_keep_file_order() -> None:
    spec = spec_with("priority_start\n  Rule21 > Rule3\n  Rule3 > Rule2 > Rule1 Rule21 > Rule1\npriority_end")
    assert pairs(spec) == [("Rule21", "Rule3"), ("Rule3", "Rule2"), ("Rule2", "Rule1"), ("Rule21", "Rule1")]
    # a chain may also run over lines: layout only separates tokens
    spec = spec_with("priority_start Rule21\n  >\n Rule3 priority_end")
    assert pairs(spec) == [("Rule21", "Rule3")]


def test_an_empty_block_and_no_block() -> None:
    result = analyse(RULES + "priority_start priority_end")
    assert result.ok, result.render()
    assert result.spec is not None and result.spec.priorities == ()
    assert [b.kind for b in result.spec.blocks] == ["def", "rule", "priority"]
    assert parse(RULES).priorities == ()


def test_the_block_is_recorded_and_may_sit_among_the_legos_blocks() -> None:
    legos = RULES.replace("E and m", "E and {m}")
    text = legos + "priority_start Rule1 > Rule2 priority_end\nrelation_start witness E F relation_end"
    result = analyse(text)
    assert result.ok, result.render()
    assert result.spec is not None and result.spec.dialect is A.Dialect.LEGOS
    assert [b.kind for b in result.spec.blocks] == ["def", "rule", "priority", "relation"]
    assert pairs(result.spec) == [("Rule1", "Rule2")]


def test_spans_of_a_pair_and_of_its_names() -> None:
    spec = spec_with("priority_start\n  Rule21 > Rule2 > Rule1\npriority_end")
    first, second = spec.priorities
    line = RULES.count("\n") + 2
    assert first.span == A.Span(line, 3, line, 17)  # "  Rule21 > Rule2 > Rule1"
    assert first.higher_span == A.Span(line, 3, line, 9)
    assert first.lower_span == A.Span(line, 12, line, 17)
    assert second.higher_span == first.lower_span
    assert second.span == A.Span(line, 12, line, 25)
    mark = spec.blocks[-1]
    assert mark.kind == "priority" and mark.span == A.Span(line - 1, 1, line - 1, 15)


def test_priority_start_and_end_are_reserved() -> None:
    (err,) = analyse("def_start event priority_start def_end rule_start R when E then F rule_end").errors
    assert err.code == "syntax" and "reserved keyword" in (err.hint or "")
    # ... but SLEEC-TK's escape makes one a name, and relation words are names outside relations
    text = (
        "def_start event E def_end rule_start ^priority_end when E then E witness when E then E rule_end\n"
        "priority_start ^priority_end > witness priority_end"
    )
    spec = parse(text)
    assert pairs(spec) == [("priority_end", "witness")]
    assert parse(format_spec(spec)) == spec


@pytest.mark.parametrize(
    ("block", "where"),
    [
        ("priority_start Rule1 > priority_end", "priority_end"),
        ("priority_start Rule1 priority_end", "priority_end"),
        ("priority_start Rule1 > > Rule2 priority_end", ">"),
        ("priority_start > Rule1 priority_end", ">"),
        ("priority_start Rule1 < Rule2 priority_end", "<"),
        ("priority_start Rule1, Rule2 priority_end", ","),
        ("priority_start Rule1 > Rule2", "end of file"),
    ],
)
def test_malformed_blocks_are_syntax_errors(block: str, where: str) -> None:
    errors = analyse(RULES + block).errors
    assert [d.code for d in errors] == ["syntax"]
    assert where in errors[0].message


def test_the_block_comes_after_the_rule_block_once() -> None:
    defs, rules = RULES.split("rule_start")
    early = analyse(defs + "priority_start Rule1 > Rule2 priority_end rule_start" + rules)
    assert [d.code for d in early.errors] == ["block-order"]
    assert "after the rule block" in early.errors[0].message
    twice = analyse(RULES + "priority_start Rule1 > Rule2 priority_end priority_start priority_end")
    assert [d.code for d in twice.errors] == ["duplicate-block"]


# ---------------------------------------------------------------------------- checks


def test_an_unknown_rule_with_did_you_mean() -> None:
    (d,) = diagnostics("priority_start\n  Rule21 > Rul3\npriority_end")
    assert d.code == "undeclared-rule" and d.severity is Severity.ERROR
    assert d.message == "`Rul3` in a priority is not a rule"
    assert d.hint == "did you mean `Rule3`?"
    line = RULES.count("\n") + 2
    assert d.span == A.Span(line, 12, line, 16)
    assert d.header() == f"rules.sleec:{line}:12: error: `Rul3` in a priority is not a rule"
    (d,) = diagnostics("priority_start Rule21 > Zebra priority_end")
    assert d.code == "undeclared-rule" and d.hint is None


def test_a_name_of_another_kind_is_not_a_rule() -> None:
    (d,) = diagnostics("priority_start m > Rule1 priority_end")
    assert d.code == "not-a-rule"
    assert d.message == "`m` in a priority is a measure, not a rule"
    (d,) = diagnostics("priority_start Rule1 > E priority_end")
    assert d.message == "`E` in a priority is an event, not a rule"


def test_a_rule_above_itself() -> None:
    (d,) = diagnostics("priority_start Rule1 > Rule1 priority_end")
    assert d.code == "priority-self" and d.message == "rule `Rule1` is declared above itself"
    # an unknown name above itself is reported once, as unknown
    assert codes("priority_start Nope > Nope priority_end") == ["undeclared-rule"]


def test_a_cycle_is_named_at_the_pair_that_closes_it() -> None:
    (d,) = diagnostics("priority_start\n  Rule1 > Rule2\n  Rule2 > Rule1\npriority_end")
    assert d.code == "priority-cycle"
    assert d.message == "priorities form a cycle: Rule1 > Rule2 > Rule1"
    line = RULES.count("\n") + 3
    assert d.span.line == line
    assert [(note, span.line) for note, span in d.related] == [("`Rule1 > Rule2` declared here", line - 1)]
    assert d.hint is not None


def test_a_longer_cycle_through_a_chain_is_reported_once() -> None:
    (d,) = diagnostics("priority_start Rule21 > Rule3 > Rule2 > Rule1 > Rule3 priority_end")
    assert d.code == "priority-cycle"
    assert d.message == "priorities form a cycle: Rule3 > Rule2 > Rule1 > Rule3"
    assert len(d.related) == 2
    # two separate cycles: two errors; a cycle only through unknown names: none
    assert codes("priority_start Rule1 > Rule2 > Rule1 Rule3 > Rule21 > Rule3 priority_end") == [
        "priority-cycle",
        "priority-cycle",
    ]
    assert codes("priority_start X > Y > X priority_end") == ["undeclared-rule"] * 4


def test_a_pair_declared_twice_is_a_warning() -> None:
    result = analyse(RULES + "priority_start\n  Rule1 > Rule2\n  Rule3 > Rule1 > Rule2\npriority_end")
    assert result.ok
    (d,) = result.diagnostics
    assert d.code == "duplicate-priority" and d.severity is Severity.WARNING
    assert d.message == "`Rule1 > Rule2` is declared twice"
    assert d.related[0][0] == "first declared here"
    # a pair implied by others is no repeat
    assert codes("priority_start Rule1 > Rule2 > Rule3 Rule1 > Rule3 priority_end") == []


def test_all_problems_of_a_block_in_one_run() -> None:
    got = codes(
        "priority_start\n  Rule1 > Rule1\n  Rul2 > Rule3\n  Rule2 > Rule3 > Rule2\n  Rule2 > Rule3\npriority_end"
    )
    assert got == ["priority-self", "undeclared-rule", "priority-cycle", "duplicate-priority"]


def test_repeated_mistakes_are_folded() -> None:
    block = "priority_start " + " ".join(f"Nope{i} > Rule1" for i in range(50)) + " priority_end"
    found = codes(block)
    assert found.count("undeclared-rule") == 21  # 20 and one "... and 30 more" summary


def test_a_long_chain_checks_without_recursion() -> None:
    n = 3000
    rules = "\n".join(f"R{i} when E then F" for i in range(n))
    chain = " > ".join(f"R{i}" for i in range(n))
    text = f"def_start event E event F def_end rule_start {rules} rule_end priority_start {chain} > R0 priority_end"
    (d,) = analyse(text).diagnostics
    assert d.code == "priority-cycle" and len(d.related) == 8 and len(d.message) < 300


# ---------------------------------------------------------------------------- strict modes


@pytest.mark.parametrize(
    ("kw", "code", "words"),
    [
        ({"strict": True}, "extension-priority", "rejected by --strict"),
        ({"dialect": "tk"}, "dialect", "SLEEC-TK rejects it"),
        ({"dialect": "legos"}, "dialect", "LEGOS-SLEEC rejects it"),
        ({"dialect": "tk", "strict": True}, "extension-priority", "rejected by --strict"),
    ],
)
def test_strict_modes_reject_the_extension(kw: dict[str, object], code: str, words: str) -> None:
    text = RULES.replace("E and m", "E and {m}") if kw.get("dialect") == "legos" else RULES
    result = analyse(text + "priority_start Rule1 > Rule2 priority_end", **kw)  # type: ignore[arg-type]
    (d,) = result.errors
    assert d.code == code and "cosleec extension" in d.message and words in d.message
    assert d.span.line == RULES.count("\n") + 1 and d.span.col == 1


def test_strict_rejects_an_empty_block_too() -> None:
    assert codes("priority_start priority_end", strict=True) == ["extension-priority"]


def test_the_block_says_nothing_about_the_dialect() -> None:
    assert analyse(RULES + "priority_start Rule1 > Rule2 priority_end").dialect is A.Dialect.TK


def test_the_paper_notation_has_no_priority_block() -> None:
    assert analyse("when E then F\npriority_start R1 > R2 priority_end", dialect="paper").errors


# ---------------------------------------------------------------------------- printer


def test_the_printer_writes_one_pair_a_line_and_reads_back() -> None:
    spec = spec_with("priority_start Rule21 > Rule3 > Rule2\n Rule1 > Rule2 priority_end")
    text = format_spec(spec)
    assert text.endswith(
        "priority_start\n    Rule21 > Rule3\n    Rule3 > Rule2\n    Rule1 > Rule2\npriority_end\n"
    )
    assert parse(text) == spec
    assert format_spec(parse(text)) == text
    legos = format_spec(spec, A.Dialect.LEGOS)
    assert "priority_start" in legos and parse(legos) == spec


def test_priorities_take_part_in_equality_and_an_empty_block_prints_as_none() -> None:
    assert spec_with("priority_start Rule1 > Rule2 priority_end") != spec_with("")
    assert spec_with("priority_start Rule2 > Rule1 priority_end") != spec_with(
        "priority_start Rule1 > Rule2 priority_end"
    )
    empty = spec_with("priority_start priority_end")
    assert "priority_start" not in format_spec(empty) and parse(format_spec(empty)) == empty


# ---------------------------------------------------------------------------- functions


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("Rule21 > Rule3", [("Rule21", "Rule3")]),
        ("Rule21>Rule3", [("Rule21", "Rule3")]),
        ("  A >B\t>  C \n", [("A", "B"), ("B", "C")]),
        ("^when > _x1", [("when", "_x1")]),
    ],
)
def test_parse_priority(text: str, expected: list[tuple[str, str]]) -> None:
    assert parse_priority(text) == expected


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("", "empty priority"),
        ("   ", "empty priority"),
        ("Rule21", "names one rule"),
        ("Rule21 >", "a rule name is missing"),
        ("> Rule3", "a rule name is missing"),
        ("A > > B", "a rule name is missing"),
        ("A < B", "`A < B` is not a rule name"),
        ("A >= B", "`= B` is not a rule name"),
        ("A > B, C > D", "`B, C` is not a rule name"),
        ("A B > C", "`A B` is not a rule name"),
        ("1A > B", "`1A` is not a rule name"),
    ],
)
def test_parse_priority_rejects_malformed_text(text: str, words: str) -> None:
    with pytest.raises(UserError) as info:
        parse_priority(text)
    assert words in str(info.value)
    assert "write it as HIGHER > LOWER" in info.value.hint
    assert isinstance(info.value, ValueError)  # a ConfigurationError, for callers catching ValueError


def test_parse_priority_hints_at_the_direction_of_less_than() -> None:
    with pytest.raises(UserError) as info:
        parse_priority("Rule3 < Rule21")
    assert info.value.hint.startswith("the higher rule comes first")


def test_parse_priority_clips_what_it_quotes() -> None:
    with pytest.raises(UserError) as info:
        parse_priority("x" * 10_000 + " > !")
    assert len(info.value.message) < 200


def test_closure() -> None:
    assert closure([]) == frozenset()
    assert closure([("A", "B"), ("B", "C"), ("D", "C")]) == {("A", "B"), ("B", "C"), ("A", "C"), ("D", "C")}
    assert closure([("A", "B"), ("B", "A")]) == {("A", "B"), ("B", "A"), ("A", "A"), ("B", "B")}
    assert closure(iter([("A", "B"), ("A", "B")])) == {("A", "B")}


def test_cycle() -> None:
    assert cycle([]) is None
    assert cycle([("A", "B"), ("B", "C"), ("A", "C")]) is None
    assert cycle([("A", "A")]) == ["A", "A"]
    assert cycle([("A", "B"), ("B", "A")]) == ["A", "B", "A"]
    # the shortest cycle through the first-named rule of the first cyclic group
    assert cycle([("X", "A"), ("A", "B"), ("B", "C"), ("C", "A"), ("B", "A")]) == ["A", "B", "A"]
    assert cycle(iter([("Z", "Y"), ("P", "Q"), ("Q", "P"), ("Y", "Z")])) == ["Z", "Y", "Z"]


def test_cycle_agrees_with_the_closure() -> None:
    rng = random.Random(7)
    names = "ABCDEFG"
    for _ in range(300):
        ps = [(rng.choice(names), rng.choice(names)) for _ in range(rng.randint(0, 8))]
        found = cycle(ps)
        looped = any(a == b for a, b in closure(ps))
        assert (found is not None) == looped, ps
        if found is not None:
            assert found[0] == found[-1] and len(found) >= 2
            assert all(step in set(ps) for step in pairwise(found))
