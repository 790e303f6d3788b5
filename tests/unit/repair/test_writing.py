"""Edits of a rule file: only the stretch a repair changes moves, everything else (comments,
blank lines, the author's layout) stays byte for byte, in the file's own notation."""

from __future__ import annotations

from dataclasses import replace

import pytest

from cosleec.lang import analyse, rule_extents
from cosleec.lang import ast as A
from cosleec.repair.patch import Edit, Patch, Text, unified_diff
from cosleec.repair.writing import Writer, joined

TK = """def_start
    event E
    event X
    event Y
    measure m : boolean
def_end
rule_start
    // the first rule
    R1 when E then X // trails R1
        unless m then Y

    R2 when E and m then Y // about R2
    /* a block comment */
    R3 when Y then X
rule_end
"""

LEGOS = """def_start
    event E
    event X
    measure m : boolean
def_end
rule_start
    R1 when E and {m} then X
rule_end
"""


def spec_of(text: str) -> A.Specification:
    r = analyse(text, "t.sleec")
    assert r.ok and r.spec is not None, r.render()
    return r.spec


def test_a_rule_extent_runs_from_its_name_to_its_last_token_comments_left_out() -> None:
    ex = rule_extents(TK, spec_of(TK))
    assert TK[slice(*ex["R1"])] == "R1 when E then X // trails R1\n        unless m then Y"
    assert TK[slice(*ex["R2"])] == "R2 when E and m then Y"  # its trailing comment left out
    assert TK[slice(*ex["R3"])] == "R3 when Y then X"  # not `rule_end`


def test_the_last_rule_of_a_file_without_block_words_ends_at_its_last_token() -> None:
    text = "def_start\n event E\n event X\ndef_end\nrule_start\n R1 when E then X\nrule_end"
    ex = rule_extents(text, spec_of(text))
    assert text[slice(*ex["R1"])] == "R1 when E then X"


def test_removing_a_rule_removes_its_lines_and_nothing_else() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    out = Patch("remove-rule", "", ("R3",), (w.remove_rule(spec.rules[2]),)).apply(TK)
    assert out == TK.replace("    R3 when Y then X\n", "")


def test_a_rule_sharing_its_line_with_a_comment_keeps_the_comment() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    out = Patch("remove-rule", "", ("R2",), (w.remove_rule(spec.rules[1]),)).apply(TK)
    assert out == TK.replace("R2 when E and m then Y // about R2", " // about R2")
    out = Patch("remove-rule", "", ("R1",), (w.remove_rule(spec.rules[0]),)).apply(TK)
    assert "unless m then Y" not in out and "R1 when" not in out  # a comment inside it goes with it


def test_a_rewritten_rule_stays_in_place_with_its_indentation() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    r2 = spec.rules[1]
    new = replace(r2, trigger=replace(r2.trigger, condition=A.Not(A.Name("m"))))
    out = Patch("x", "", (), (w.replace_rule(r2, new),)).apply(TK)
    assert out == TK.replace("R2 when E and m then Y", "R2 when E and not m then Y")


def test_a_new_rule_goes_after_the_last_rule_with_its_indentation() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    rule = A.Rule("R4", A.Trigger("X"), A.Response((A.ResponseItem(A.Occurrence("Y")),)))
    out = Patch("add-rule", "", (), (w.add_rule(rule),)).apply(TK)
    assert out == TK.replace("R3 when Y then X\n", "R3 when Y then X\n    R4 when X then Y\n")
    assert spec_of(out).rules[-1] == rule


def test_a_rule_in_legos_is_written_in_legos() -> None:
    spec = spec_of(LEGOS)
    w = Writer(LEGOS, spec)
    r1 = spec.rules[0]
    new = replace(r1, response=replace(r1.response, defeaters=(A.Defeater(A.Name("m")),)))
    out = Patch("x", "", (), (w.replace_rule(r1, new),)).apply(LEGOS)
    assert "R1 when E and {m} then X unless {m}" in out
    assert spec_of(out).rules[0] == new


@pytest.mark.parametrize("existing", [False, True])
def test_a_priority_goes_into_the_block_or_a_new_one_at_the_end(existing: bool) -> None:
    text = TK + ("priority_start\n    R1 > R3\npriority_end\n" if existing else "")
    spec = spec_of(text)
    out = Patch("p", "", (), (Writer(text, spec).add_priority("R2", "R1"),)).apply(text)
    pairs = [(p.higher, p.lower) for p in spec_of(out).priorities]
    assert pairs == ([("R1", "R3"), ("R2", "R1")] if existing else [("R2", "R1")])
    assert out.count("priority_start") == 1


def test_a_fresh_name_is_free() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    assert w.fresh_name("R_c1") == "R_c1"
    assert w.fresh_name("R1") == "R1_2"
    assert w.fresh_name("E") == "E_2"  # an event's name is taken too
    assert w.fresh_name("R1", {"R1_2"}) == "R1_3"


def test_edits_apply_last_first_and_overlap_only_when_they_share_text() -> None:
    a = Patch("x", "", (), (Edit(0, 2, "AB"), Edit(4, 4, "!")))
    assert a.apply("0123456") == "AB23!456"
    assert a.size == 2 + 2 + 1
    assert a.overlaps(Patch("y", "", (), (Edit(1, 3, ""),)))
    assert not a.overlaps(Patch("y", "", (), (Edit(2, 4, ""),)))  # touching ends: apart
    assert not a.overlaps(Patch("y", "", (), (Edit(4, 4, "?"),)))  # two insertions at one place


def test_text_offsets_and_whole_lines() -> None:
    t = Text("ab\n  cd\nef")
    assert t.offset(2, 3) == 5 and t.indent(2) == "  " and t.line_end(3) == 10
    assert t.whole_lines(5, 7) == (3, 8)  # its line, newline included
    assert t.whole_lines(8, 9) == (8, 9)  # `f` shares its line with `e`


def test_the_diff_names_the_file_and_shows_only_the_change() -> None:
    d = unified_diff("a\nb\nc\n", "a\nc\n", "r.sleec")
    assert d.startswith("--- a/r.sleec\n+++ b/r.sleec\n") and "-b\n" in d and "\n+" not in d.split("\n", 2)[2]
    assert d.endswith("\n")
    assert "No newline" in unified_diff("a", "b", "r")


def test_two_new_priority_blocks_applied_together_make_one() -> None:
    spec = spec_of(TK)
    w = Writer(TK, spec)
    other = Edit(0, 0, "// rules\n")
    edits = joined((w.add_priority("R1", "R2"), other, w.add_priority("R2", "R3")))
    out = Patch("set", "", (), edits).apply(TK)
    assert out.count("priority_start") == 1 and out.startswith("// rules\n")
    assert [(p.higher, p.lower) for p in spec_of(out).priorities] == [("R1", "R2"), ("R2", "R3")]
    one = (w.add_priority("R1", "R2"), other)
    assert joined(one) == one
