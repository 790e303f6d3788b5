"""Static checks (sleec-language.md §5): every error of a file in one run, stable codes."""

from __future__ import annotations

import pytest

from cosleec.lang import analyse
from cosleec.lang.checker import Options

DEFS = """def_start
  event E event F
  measure a : boolean measure x : numeric
  measure lvl : scale(low, medium, high) measure mood : scale(calm, upset)
  constant K = 5 constant J = K constant L = J
def_end
"""


LEGOS_DEFS = DEFS.replace("constant J = K constant L = J", "constant J = -> K constant L = -> J")


def codes(rules: str, **kw: object) -> list[str]:
    # rules using LEGOS-only syntax get LEGOS-style definitions (no dialect mix)
    legos = any(tok in rules for tok in ("{", "[", "-2", "+", "F otherwise"))
    result = analyse((LEGOS_DEFS if legos else DEFS) + "rule_start\n" + rules + "\nrule_end\n", **kw)  # type: ignore[arg-type]
    return [d.code for d in result.diagnostics if d.severity.value != "note"]


@pytest.mark.parametrize(
    ("rule", "expected"),
    [
        ("R when E then F", []),
        ("R when Undeclared then F", ["undeclared-event"]),
        ("R when a then F", ["not-an-event"]),
        ("R when E then x", ["not-an-event"]),
        ("R when E and E then F", ["not-a-measure"]),
        ("R when E and nope then F", ["undeclared"]),
        ("R when E and a > a then F", ["bool-relop"]),
        ("R when E and (({a} + 1) > 2) then F", ["arith-type"]),
        ("R when E and lvl > calm then F", ["scale-literal"]),
        ("R when E and lvl > 3 then F", ["type"]),
        ("R when E and lvl >= medium and mood = upset then F", []),
        ("R when E and a = true then F", []),
        ("R when E and x then F", ["not-boolean"]),
        ("R when E and x > 2.5 then F", ["decimal"]),
        ("R when E then F within 3 minute", ["bad-unit"]),
        ("R when E then F within a seconds", ["bad-deadline"]),
        ("R when E then F within L seconds", []),
        ("R when E then F within -2 seconds", ["bad-deadline"]),
        ("R when E then F within [30 seconds, 1 seconds]", ["bad-deadline"]),
        ("R when E and a or x > 1 and a then F", ["mixed-and-or"]),
        ("R when E and (a or x > 1) and a then F", []),
        ("R when E then F unless a unless a", ["duplicate-hedge"]),
        ("R when E then F unless a and x > 1 then E unless a", ["unreachable-hedge"]),
        ("R when E then F unless false", ["unreachable-hedge"]),
        ("R when E then F\nR when E then F", ["duplicate-rule"]),
        ("R when E then F otherwise E", ["untimed-otherwise", "untimed-fallback"]),
        ("R when E then F within 1 seconds otherwise E within 1 seconds", []),
    ],
)
def test_rule_checks(rule: str, expected: list[str]) -> None:
    assert codes(rule) == expected


def test_all_errors_of_a_file_are_reported_in_one_run() -> None:
    got = codes("R1 when X then F\nR2 when E and lvl > calm then Y\nR3 when E then F within 2 hour")
    assert got == ["undeclared-event", "scale-literal", "undeclared-event", "bad-unit"]


def test_strict_precedence_turns_the_warning_into_an_error() -> None:
    result = analyse(
        DEFS + "rule_start R when E and a or a and a then F rule_end", options=Options(strict_precedence=True)
    )
    assert [d.code for d in result.errors] == ["mixed-and-or"]


@pytest.mark.parametrize(
    ("defs", "expected"),
    [
        ("event A measure A : boolean", ["duplicate-name"]),
        ("event A event A", ["redeclared"]),
        ("measure m : scale(lo, hi, lo)", ["duplicate-literal"]),
        ("event lo measure m : scale(lo, hi)", ["literal-clash"]),
        ("constant A = B constant B = A", ["constant-cycle"]),
        ("constant A = Z", ["undeclared"]),
        ("event E constant A = E", ["constant-ref"]),
        ("fluent F <{A}, {B}>", ["unsupported-fluent"]),
    ],
)
def test_definition_checks(defs: str, expected: list[str]) -> None:
    result = analyse(f"def_start event Q {defs} def_end rule_start R when Q then Q rule_end")
    assert [d.code for d in result.diagnostics] == expected


def test_fragment_without_def_block_needs_infer_defs() -> None:
    text = "rule_start R1 when Start and ({risk} > low) then Act unless {urgent} rule_end"
    assert [d.code for d in analyse(text).errors] == ["no-def-block"]
    result = analyse(text, infer_defs=True)
    assert result.ok and result.spec is not None
    types = {m.name: str(m.type) for m in result.spec.measures}
    assert types == {"risk": "scale(low)", "urgent": "boolean"}


def test_relations_and_nonstandard_relation_words() -> None:
    text = LEGOS_DEFS + (
        "rule_start R when E then F rule_end\nrelation_start\n witness E F\n measure imply {a} ({x} > 1)\n"
        " conflict E F\n effect E {a}\n when E then {a} until F and ({x} > 2)\n relation_end"
    )
    result = analyse(text)
    assert [d.code for d in result.errors] == ["nonstandard-relation", "nonstandard-relation"]
    assert result.spec is not None and len(result.spec.relations) == 5
