"""Issue 33, item 6: a rule file declares the clause semantics it is written for
(``semantics_start unless nested semantics_end``, lang/declared.py)."""

from __future__ import annotations

import pytest

from cosleec.errors import ConfigurationError
from cosleec.lang import HedgeSemantics, analyse, clause_semantics_for, format_source, format_spec

DEFS = "def_start\n  event A\n  event B\n  event C\n  measure x: boolean\ndef_end\n"
RULES = "rule_start\n  R1 when A then B unless x then C unless x then B\nrule_end\n"


def block(*entries: str) -> str:
    return "semantics_start\n" + "".join(f"  {e}\n" for e in entries) + "semantics_end\n"


@pytest.mark.parametrize(
    ("value", "expected"), [("nested", HedgeSemantics.NESTED), ("last-wins", HedgeSemantics.LAST_WINS)]
)
def test_the_declared_semantics_is_the_specifications(value: str, expected: HedgeSemantics) -> None:
    for text in (block(f"unless {value}") + DEFS + RULES, DEFS + RULES + block(f"unless {value}")):
        result = analyse(text)
        assert result.spec is not None and result.spec.clause_semantics is expected, result.render()
    assert analyse(DEFS + RULES).spec.clause_semantics is None  # type: ignore[union-attr]


def test_the_hedge_lint_reads_the_files_semantics_and_its_hint_names_the_block() -> None:
    # `unless x ... unless x`: under last-wins clause 1 is dead, under nested clause 2 too
    plain = [d for d in analyse(DEFS + RULES).diagnostics if d.code == "duplicate-hedge"]
    assert [d.message for d in plain] == [
        "clause 1 has the same condition as clause 2; under last-wins semantics clause 1 never applies"
    ]
    assert plain[0].hint is not None and "`semantics_start unless nested semantics_end`" in plain[0].hint
    nested = analyse(DEFS + RULES + block("unless nested"))
    (d,) = [d for d in nested.diagnostics if d.code == "duplicate-hedge"]
    assert "under nested semantics" in d.message and d.hint is not None and "semantics_start" not in d.hint


def test_mistakes_in_the_block() -> None:
    text = DEFS + RULES + block("unless nestd", "unless last-wins") + block("unless nested")
    errors = [(d.code, d.span.line, d.span.col, d.hint) for d in analyse(text).errors]
    assert errors == [
        ("unknown-semantics", 11, 10, "did you mean `nested`?"),
        ("duplicate-semantics", 12, 3, "keep one `unless` line"),
        ("duplicate-block", 14, 1, None),
        ("duplicate-semantics", 15, 3, "keep one `unless` line"),
    ]
    (warn,) = [d for d in analyse(DEFS + RULES + block()).diagnostics if d.code == "empty-semantics"]
    assert warn.span.line == 10
    syntax = analyse(DEFS + RULES + block("untimed none")).errors
    assert [d.code for d in syntax] == ["syntax"] and "`unless`" in syntax[0].message


def test_strict_modes_reject_the_block() -> None:
    text = DEFS + RULES + block("unless nested")
    assert [(d.code, d.span.line) for d in analyse(text, strict=True).errors] == [("extension-semantics", 10)]
    for dialect in ("tk", "legos"):
        (err,) = [d for d in analyse(text, dialect=dialect).errors if "semantics block" in d.message]
        assert "cosleec extension" in err.message and err.span.line == 10


def test_fmt_and_the_printer_keep_the_block() -> None:
    text = "// how to read these rules\n" + block("unless last-wins") + DEFS + RULES
    result = analyse(text)
    assert result.spec is not None
    kept = format_source(text, result.spec)
    assert kept.startswith(
        "// how to read these rules\nsemantics_start\n    unless last-wins\nsemantics_end\n"
    )
    again = analyse(format_spec(result.spec))
    assert again.spec == result.spec and again.spec is not None
    assert again.spec.clause_semantics is HedgeSemantics.LAST_WINS
    with pytest.raises(Exception, match="the paper notation has no semantics block"):
        format_source(text, result.spec, dialect="paper")


def test_which_semantics_to_read_a_file_with() -> None:
    declared = analyse(DEFS + RULES + block("unless nested"), "r.sleec").spec
    silent = analyse(DEFS + RULES).spec
    assert declared is not None and silent is not None
    assert clause_semantics_for(silent) is HedgeSemantics.LAST_WINS
    assert clause_semantics_for(silent, "nested") is HedgeSemantics.NESTED
    assert clause_semantics_for(declared) is HedgeSemantics.NESTED
    assert clause_semantics_for(declared, HedgeSemantics.NESTED) is HedgeSemantics.NESTED
    with pytest.raises(ConfigurationError) as info:
        clause_semantics_for(declared, "last-wins", option="--semantics")
    e = info.value
    assert "--semantics last-wins contradicts" in e.message and "`unless nested`" in e.message
    assert e.where == "r.sleec:11:3" and "leave out --semantics" in e.hint
    with pytest.raises(ConfigurationError, match="did you mean 'nested'"):
        clause_semantics_for(silent, "nestd")
