"""The language server's parts without the connection: positions in every encoding, the
index of names on LEGOS-SLEEC's blocks, settings, and the on-save analysis's time limit
(a real process, killed)."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest
from lsprotocol import types as T

from cosleec.lang import Options
from cosleec.lang import ast as A
from cosleec.lsp import Document, Kind, LineIndex, Role, Settings
from cosleec.lsp import features as F
from cosleec.lsp.onsave import OnSave, Outcome

ROOT = Path(__file__).resolve().parents[3]

LEGOS = """def_start event E event F event G measure a : boolean measure x : numeric
  measure s : scale(lo, hi) measure t : scale(hi, top) constant K = 3 constant J = -> K def_end
rule_start
  R1 when E and ({a} and ({x} > K)) then F within [1 seconds, 5 seconds] unless (not {a}) then not G
  R2 when F and ({s} = hi) then G unless ({t} = hi) then E
rule_end
concern_start c1 when E and {a} then F concern_end
purpose_start p1 exists E while F meanwhile (when F then E) purpose_end
relation_start witness E F causation G {a} when E then {a} until G relation_end
"""


def position(text: str, needle: str, into: int = 0, nth: int = 0) -> T.Position:
    i = -1
    for _ in range(nth + 1):
        i = text.index(needle, i + 1)
    i += into
    return T.Position(line=text.count("\n", 0, i), character=i - text.rfind("\n", 0, i) - 1)


@pytest.mark.parametrize(
    ("encoding", "units"),
    [("utf-16", 2 + 1 + 1), ("utf-8", 4 + 2 + 1), ("utf-32", 1 + 1 + 1)],
)
def test_positions_count_in_the_agreed_encoding(encoding: str, units: int) -> None:
    text = "first\n𝔘ü x = 1\n"
    lines = LineIndex(text, encoding)
    x = text.index("x")
    assert lines.position(x) == T.Position(line=1, character=units)
    assert lines.to_offset(T.Position(line=1, character=units)) == x
    assert lines.span_range(A.Span(2, 4, 2, 5)).start.character == units
    assert lines.to_offset(T.Position(line=1, character=999)) == text.index("\n", x)  # past the end: the end
    assert lines.to_offset(T.Position(line=9, character=0)) == len(text)


def test_a_lone_carriage_return_is_a_line_to_lsp_but_not_to_the_scanner() -> None:
    text = "a\rb\r\nc\nd"
    lines = LineIndex(text)
    assert lines.position(text.index("b")) == T.Position(line=1, character=0)
    assert lines.position(text.index("c")) == T.Position(line=2, character=0)
    assert lines.line_col(text.index("c")) == (2, 1)  # the scanner counts `\n` only
    assert lines.offset(2, 1) == text.index("c")
    assert lines.to_offset(T.Position(line=1, character=5)) == text.index("\r\n")


def test_the_index_reads_every_legos_block() -> None:
    doc = Document(uri="file:///legos.sleec", text=LEGOS, version=1)
    assert doc.result().ok, doc.result().render()
    index = doc.index()
    where = {(u.role, u.where) for u in index.uses_of((Kind.EVENT, "G"))}
    assert where >= {
        (Role.DECLARED, ""),
        (Role.FORBIDDEN, "R1.1"),
        (Role.OBLIGED, "R2"),
        (Role.NAMED, "relation"),
    }
    relation_uses = [u for u in index.uses_of((Kind.EVENT, "G")) if u.where == "relation"]
    assert [LEGOS[u.start : u.end] for u in relation_uses] == ["G", "G"]  # causation G, until G
    assert {u.where for u in index.uses_of((Kind.EVENT, "E"))} >= {
        "concern c1",
        "purpose p1",
        "relation",
        "R2.1",
    }
    # `hi` of s and `hi` of t are two symbols: each compared with its own measure
    assert [LEGOS[u.start - 6 : u.end] for u in index.uses_of((Kind.SCALE_VALUE, "s.hi"))] == [
        "e(lo, hi",
        "{s} = hi",
    ]
    assert [LEGOS[u.start - 6 : u.end] for u in index.uses_of((Kind.SCALE_VALUE, "t.hi"))] == [
        "scale(hi",
        "{t} = hi",
    ]
    assert [u.role for u in index.uses_of((Kind.CONSTANT, "K"))] == [Role.DECLARED, Role.READ, Role.READ]
    assert [LEGOS[u.start : u.end] for u in index.uses_of((Kind.MEASURE, "a"))] == ["a"] * 6
    hover = F.hover(doc, position(LEGOS, "K)"))
    assert hover is not None and "**constant** `K` = `3`" in str(hover.contents)
    outline = [s.name for s in F.document_symbols(doc)]
    assert outline == ["definitions", "rules", "concerns", "purposes"]


def test_a_negated_escaped_response_is_found_at_its_name() -> None:
    text = (
        "def_start event E event ^when def_end rule_start R1 when E then not ^when within 3 seconds rule_end"
    )
    doc = Document(uri="file:///escaped.sleec", text=text, version=1)
    assert doc.result().ok
    uses = doc.index().uses_of((Kind.EVENT, "when"))
    assert [text[u.start : u.end] for u in uses] == ["^when", "^when"]
    assert [u.role for u in uses] == [Role.DECLARED, Role.FORBIDDEN]


def test_completion_while_the_text_has_a_syntax_error_offers_the_last_names() -> None:
    text = (ROOT / "examples" / "curtains.sleec").read_text(encoding="utf-8")
    doc = Document(uri="file:///c.sleec", text=text, version=1)
    doc.result()
    broken = text.replace("rule_end", "    R2 when CurtainOpenRequest then \nrule_end")
    doc.set_text(broken, 2)
    assert doc.result().spec is None
    labels = {i.label for i in F.completion(doc, position(broken, "\nrule_end")).items}
    assert {"OpenCurtains", "userUndressed", "when", "unless"} <= labels
    with pytest.raises(F.Refusal, match="does not parse"):
        F.rename(doc, position(broken, "OpenCurtains"), "Open")


def test_formatting_keeps_crlf_and_edits_whole_lines() -> None:
    text = (ROOT / "examples" / "curtains.sleec").read_text(encoding="utf-8").replace("\n", "\r\n")
    messy = text.replace("    event Refuse", "    event    Refuse")
    doc = Document(uri="file:///c.sleec", text=messy, version=1)
    [edit] = F.formatting(doc)
    assert edit.range.start == position(messy, "    event    Refuse")
    lines = doc.lines
    start, end = lines.to_offset(edit.range.start), lines.to_offset(edit.range.end)
    assert messy[:start] + edit.new_text + messy[end:] == text


def test_settings_come_from_initialization_options() -> None:
    s = Settings.from_json(
        {"dialect": "tk", "lint": True, "semantics": "nested", "analysisTimeout": 5, "other": 1}
    )
    assert (s.dialect, s.lint, str(s.semantics), s.analysis_timeout) == ("tk", True, "nested", 5)
    assert Settings.from_json(None) == Settings()
    with pytest.raises(ValueError, match="formatWidth must be a int"):
        Settings.from_json({"formatWidth": "wide"})
    with pytest.raises(ValueError, match="analysis must be a bool"):
        Settings.from_json({"analysis": 1})


def test_an_analysis_past_its_time_limit_is_killed_and_said_so() -> None:
    text = (ROOT / "examples" / "analysis" / "curtains.sleec").read_text(encoding="utf-8")
    got: list[Outcome] = []
    done = threading.Event()

    def finished(uri: str, outcome: Outcome) -> None:
        got.append(outcome)
        done.set()

    runner = OnSave(finished)
    try:
        runner.start(
            "file:///a.sleec",
            text,
            "a.sleec",
            options=Options(),
            dialect="auto",
            timeout=0.05,
            legos_compat=False,
        )
        assert done.wait(30)
        assert got[0].timed_out and not got[0].diagnostics and got[0].text == text
    finally:
        runner.close()


def test_without_pygls_every_command_works_and_lsp_says_what_to_install() -> None:
    """pygls is the `lsp` extra: the CLI imports it only when `cosleec lsp` runs."""
    code = (
        "import sys; sys.modules['pygls'] = None\n"
        "from cosleec.cli.main import main\n"
        "assert main(['check', 'examples/curtains.sleec']) == 0\n"
        "sys.exit(main(['lsp']))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert run.returncode == 1, run.stderr
    assert "cosleec lsp needs pygls" in run.stderr and "pip install 'cosleec[lsp]'" in run.stderr
