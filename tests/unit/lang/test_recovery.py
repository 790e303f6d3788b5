"""Issue 33, item 3: every syntax error of a file is reported, and so are the checker's
findings about the rules that parsed (lang/recovery.py)."""

from __future__ import annotations

import random
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.lang import analyse
from cosleec.lang.incremental import IncrementalAnalyser
from cosleec.testing import corpus_files

DEFS = "def_start\n  event A\n  event B\n  measure m: boolean\ndef_end\n"

BROKEN = DEFS + (
    "rule_start\n"
    "  R1: when A then B\n"  # line 7: syntax
    "  R2 when A then Bx\n"  # line 8: an undeclared event, in a rule that parses
    "  R3 when A and m == true then B\n"  # line 9: syntax
    "  R4 when Q then B\n"  # line 10: an undeclared event
    "rule_end\n"
    "priority_start\n  R1 > R2\n  R4 > R3\npriority_end\n"  # names blanked rules: no error for that
)


def where(text: str) -> list[tuple[str, int]]:
    return [(d.code, d.span.line) for d in analyse(text, "r.sleec").errors]


def test_every_syntax_error_and_the_checks_of_the_rules_that_parsed() -> None:
    result = analyse(BROKEN, "r.sleec")
    assert result.spec is None  # the file does not parse: no specification comes out
    assert [(d.code, d.span.line) for d in result.errors] == [
        ("rule-colon", 7),
        ("undeclared-event", 8),
        ("double-equals", 9),
        ("undeclared-event", 10),
    ]
    rendered = result.render()
    for line in (7, 8, 9, 10):
        assert f"r.sleec:{line}:" in rendered


def test_an_error_close_behind_another_is_heard_once_the_first_rule_is_blanked() -> None:
    # the parser keeps quiet for three tokens after an error: `R2:` comes sooner than that
    text = DEFS + (
        "rule_start\n"
        "  R1 when A then not B for 10 minutes\n"  # line 7
        "  R2: when A then B\n"  # line 8: within the parser's quiet after line 7
        "  R3 when A then Bx\n"  # line 9: a check of a rule that parses
        "  R4 when A then B within 1 minutes\n"
        "rule_end\n"
    )
    assert where(text) == [("for-duration", 7), ("rule-colon", 8), ("undeclared-event", 9)]


def test_a_file_whose_every_rule_is_broken_reports_each_and_no_cascade() -> None:
    rules = "".join(f"  R{i}: when A then B\n" for i in range(1, 6))
    assert where(DEFS + "rule_start\n" + rules + "rule_end\n") == [
        ("rule-colon", line) for line in range(7, 12)
    ]


def test_no_checks_after_an_error_outside_the_rule_block() -> None:
    # a broken declaration would make every rule using it an error: no guessing
    text = DEFS.replace("event B", "event B extra") + "rule_start\n  R1 when A then Q\nrule_end\n"
    assert [code for code, _ in where(text)] == ["syntax"]


def test_the_incremental_analyser_reports_the_same() -> None:
    inc = IncrementalAnalyser("r.sleec")
    assert [(d.code, d.span.line) for d in inc.analyse(BROKEN).errors] == where(BROKEN)


def _boundaries(text: str) -> list[int]:
    """The offsets where a rule starts (after the first) or `rule_end` does, in ``text``."""
    spec = analyse(text).spec
    assert spec is not None
    lines = text.splitlines(keepends=True)
    starts = [sum(len(x) for x in lines[: r.span.line - 1]) + r.span.col - 1 for r in spec.rules[1:]]
    return [*starts, text.index("rule_end", starts[-1] if starts else 0)]


_CACHE: list[tuple[Path, str, list[int]]] = []


def _parsing_corpus() -> list[tuple[Path, str, list[int]]]:
    """The corpus files that parse, with their rule boundaries (read once per session)."""
    if not _CACHE:
        for path in corpus_files():
            text = path.read_text(encoding="utf-8")
            result = analyse(text)
            if result.spec is not None and result.spec.rules and "rule_end" in text:
                _CACHE.append((path, text, _boundaries(text)))
    return _CACHE


GARBAGE = (")", ";", ":", "==", "}")
"""Tokens that no rule can end with or start with: inserted between two rules, each is an error there."""


def test_garbage_at_any_rule_boundary_of_the_corpus_is_reported_there() -> None:
    files = _parsing_corpus()
    rng = random.Random(33)
    assert len(files) > 100 or not corpus_files()
    for path, text, boundaries in files:
        at = rng.choice(boundaries)
        junk = rng.choice(GARBAGE)
        broken = text[:at] + junk + " " + text[at:]
        result = analyse(broken, path.name)  # never a traceback
        line = text.count("\n", 0, at) + 1
        assert any(d.span.line == line for d in result.errors), (path.name, line, result.render()[:400])


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_two_independent_broken_rules_are_both_reported(data: st.DataObject) -> None:
    files = [f for f in _parsing_corpus() if len(f[2]) >= 3]
    if not files:
        return
    path, text, boundaries = data.draw(st.sampled_from(files))
    spots = boundaries[:-1]  # rule starts: one whole rule between the two insertions
    i = data.draw(st.integers(0, len(spots) - 2))
    j = data.draw(st.integers(i + 1, len(spots) - 1))
    a, b = spots[i], spots[j]
    junk = data.draw(st.sampled_from(GARBAGE))
    broken = text[:a] + junk + " " + text[a:b] + junk + " " + text[b:]
    lines = {d.span.line for d in analyse(broken).errors}
    assert {text.count("\n", 0, a) + 1, text.count("\n", 0, b) + 1} <= lines, path.name
