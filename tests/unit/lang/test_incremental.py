"""The incremental front end (lang/incremental.py) gives :func:`analyse`'s result exactly --
diagnostics, the specification and every span in it -- on the corpus and on edits of it,
while parsing only the pieces an edit touched."""

from __future__ import annotations

import dataclasses
import random
from pathlib import Path
from typing import Any

import pytest

from cosleec.lang import CheckResult, IncrementalAnalyser, analyse
from cosleec.lang.incremental import PIECE_RULES
from cosleec.testing.corpus import corpus_files

ROOT = Path(__file__).resolve().parents[3]


def spans(node: Any) -> list[Any]:
    """Every field of an AST, spans included (equality of AST nodes leaves spans out)."""
    if isinstance(node, tuple | list):
        return [spans(x) for x in node]
    if dataclasses.is_dataclass(node) and not isinstance(node, type):
        return [type(node).__name__, *(spans(getattr(node, f.name)) for f in dataclasses.fields(node))]
    return [node]


def same(a: CheckResult, b: CheckResult) -> None:
    assert a.diagnostics == b.diagnostics
    assert a.dialect == b.dialect
    assert spans(a.spec) == spans(b.spec)
    assert (a.symbols is None) == (b.symbols is None)


def rules_text(n: int) -> str:
    events = "\n".join(f"    event E{i}" for i in range(n))
    rules = "\n".join(
        f"    R{i} when E{i} and m > {i} then A within {i + 1} seconds unless ok then B" for i in range(n)
    )
    return (
        f"def_start\n{events}\n    event A\n    event B\n    measure m : numeric\n    measure ok : boolean\n"
        f"def_end\n\nrule_start\n{rules}\nrule_end\n"
    )


def test_every_corpus_file_reads_as_the_whole_parse_reads_it() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("the SLEEC corpus is not here")
    cut = 0
    for f in files:
        text = f.read_text(encoding="utf-8", errors="replace")
        inc = IncrementalAnalyser(str(f))
        same(inc.analyse(text), analyse(text, str(f)))
        cut += not inc.reuse.whole
    assert cut > 100  # most files were read in pieces, not all by the fallback


def test_edits_of_corpus_files_read_as_the_whole_parse_reads_them() -> None:
    """Random one-character edits (typing, deleting, a line break) of the largest files, each
    checked incrementally against a whole parse: syntax errors and their recovery included."""
    files = sorted(corpus_files(), key=lambda f: f.stat().st_size)[-6:]
    files.append(ROOT / "examples" / "assistive_care" / "rules.sleec")
    rng = random.Random(18)
    for f in files:
        text = f.read_text(encoding="utf-8", errors="replace")
        inc = IncrementalAnalyser(str(f))
        inc.analyse(text)
        for _ in range(12):
            at = rng.randrange(len(text))
            what = rng.choice(["x", "\n", "", " ", "(", "7"])
            text = text[:at] + what + text[at + (what == "") :]
            same(inc.analyse(text), analyse(text, str(f)))


def test_an_edit_inside_a_rule_parses_that_rules_piece_alone() -> None:
    text = rules_text(400)
    inc = IncrementalAnalyser()
    inc.analyse(text)
    assert not inc.reuse.whole and inc.reuse.parsed == inc.reuse.pieces
    assert inc.reuse.pieces > 400 // PIECE_RULES // 2
    at = text.index("R200 when E200 and m > 200") + len("R200 when E200 and m > 2")
    edited = text[:at] + "1" + text[at:]
    result = inc.analyse(edited)
    assert inc.reuse.parsed == 1 and not inc.reuse.whole
    same(result, analyse(edited))
    again = inc.analyse(edited)  # nothing changed: nothing parsed
    assert inc.reuse.parsed == 0
    same(again, result)


def test_a_new_line_moves_only_the_rules_below_it() -> None:
    text = rules_text(400)
    inc = IncrementalAnalyser()
    inc.analyse(text)
    at = text.index("\n    R300 when")
    edited = text[:at] + "\n" + text[at:]
    result = inc.analyse(edited)
    assert 0 < inc.reuse.parsed < inc.reuse.pieces // 2  # the rules above kept their pieces
    same(result, analyse(edited))
    assert result.spec is not None and result.spec.rule("R300").span.line == text[:at].count("\n") + 3


def test_a_syntax_error_is_reported_by_the_whole_parse_and_pieces_come_back_after() -> None:
    text = rules_text(50)
    inc = IncrementalAnalyser()
    inc.analyse(text)
    at = text.index("then A within 21")
    broken = text[:at] + "then then " + text[at + len("then ") :]
    result = inc.analyse(broken)
    assert inc.reuse.whole and result.spec is None
    same(result, analyse(broken))
    assert [d.code for d in result.diagnostics] == ["syntax"]
    inc.analyse(text)
    assert not inc.reuse.whole


@pytest.mark.parametrize(
    "text",
    [
        "def_start event E def_end rule_start R1 when E then E rule_end",  # one line: no cut
        "def_start event E def_end\nrule_start\n/*\nR1 when E then E\n*/\nR2 when E then E\nrule_end\n",
        "def_start event E def_end\nrule_start\n// R0 when E\nR1 when E then E\nR2 when E then E\n",  # no end
        "def_start event E def_end\nrule_start\nR1 when E then E\nR2 when E then E\n/* open",
        "WHEN E THEN A\nR2 when E then A\n",  # the paper notation
        "def_start event E def_end\nrule_start\nR1 when E then E\nrule_end\nconcern_start\nc1 when E then E\n"
        "concern_end\nrule_start\nR2 when E then E\nrule_end\n",
        "\ufeffdef_start event E def_end\r\nrule_start\r\n\tR1 when E then E\r\n\tR2\twhen E then E\r\nrule_end\r\n",
    ],
)
def test_texts_the_pieces_must_not_misread(text: str) -> None:
    """Comments, a missing rule_end, an unterminated comment, the paper notation, a second
    rule block, a BOM, CRLF and tabs: the same result as the whole parse."""
    inc = IncrementalAnalyser()
    same(inc.analyse(text), analyse(text))
    same(inc.analyse(text + "\n"), analyse(text + "\n"))


def test_a_rule_commented_out_is_no_place_to_cut() -> None:
    """Cut inside a comment, a piece would not parse and the whole text would be parsed:
    the same result, but no longer incremental."""
    # the first rule line is always a cut: here, the one in the comment would be
    text = rules_text(40).replace("rule_start\n", "rule_start\n/*\n    R99 when E1 then A\n*/\n")
    inc = IncrementalAnalyser()
    same(inc.analyse(text), analyse(text))
    assert not inc.reuse.whole
