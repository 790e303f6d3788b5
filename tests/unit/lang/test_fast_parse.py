"""The fast parse (issue 32) reads every text as the general one does.

Two fast paths, each held to what it replaces, on the corpus, mutated corpus files, token
soup, paper-notation text and hypothesis-generated text rich in what scanning gets wrong
(comments opened and not closed, BOMs, tabs, form feeds, stray characters, keywords in and
out of a relation block):

- the scanning pattern's layout (lexer.layout_pattern, one character class and the
  comments) against the plain form ``(?:ws|comment|bom)*`` it replaces: the same
  ``(layout, token)`` pairs; and the scanner's tokens against Lark's own lexer, an
  independent oracle (type, text, offset, line, column), up to where Lark stops;
- ``CompiledLALR.parse_text`` (scanning while it parses, no token object for a terminal no
  rule keeps) against the general driver over the scanner's tokens: the same value --
  spans and hints included -- and the same problems, tokens and positions included.
"""

from __future__ import annotations

import dataclasses
import random
import re
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lark import UnexpectedCharacters

from cosleec.lang import ast as A
from cosleec.lang import transformer as T
from cosleec.lang.lalr import SyntaxProblem
from cosleec.lang.lexer import BAD_CHAR, layout_pattern
from cosleec.lang.parser import _DSL_MARK, _PAPER_MARK, PAPER, SLEEC, Grammar, looks_like_paper
from cosleec.testing import corpus_files

from .strategies import TOKENS, mutate, mutate_words, paper_text, token_soup
from .test_parser_crosscheck import SEED, N, shape

GRAMMARS = [SLEEC, PAPER]

PIECES = [
    *TOKENS,
    " ",
    "  ",
    "\n",
    "\r\n",
    "\t",
    "\f",
    "\v",
    "\ufeff",
    "\u00a0",
    "//",
    "// note\n",
    "/*",
    "*/",
    "/* c */",
    "/** x **/",
    "/",
    "*",
    "$",
    "é",
    "^",
    "^when",
    "12.5",
    "3.",
    "relation_start",
    "relation_end",
    "witness",
    "until",
    "WHEN",
    "When",
    "when",
    "def_start",
    "rule_start",
    "// def_start\n",
    "/* rule_start */",
]
"""What the generated texts are made of: the token soup's words, and the characters and
fragments where layout, comments and keywords are decided."""

texts = st.lists(st.sampled_from(PIECES), max_size=60).map("".join)


def _ignored(g: Grammar) -> list[str]:
    ignore = set(g.lark.lexer_conf.ignore)
    return [t.pattern.to_regexp() for t in g.lark.terminals if t.name in ignore]


def _plain(g: Grammar) -> re.Pattern[str]:
    """The scanning pattern with the plain layout form ``(?:a|b|...)*`` (the old one)."""
    fast = g.lexicon._scan.pattern
    layout = f"({layout_pattern(_ignored(g))})"
    assert fast.startswith(layout)
    return re.compile(f"((?:{'|'.join(_ignored(g))})*)" + fast[len(layout) :])


PLAIN = {g.name: _plain(g) for g in GRAMMARS}


def same_pairs(g: Grammar, text: str) -> None:
    assert g.lexicon.pairs(text) == PLAIN[g.name].findall(text), repr(text)


def lark_agrees(g: Grammar, text: str) -> None:
    """The scanner's tokens are Lark's own lexer's (with the relation-keyword post-lexer), up
    to the first character Lark cannot read, where the scanner has a BAD_CHAR token."""
    ours = [tuple(t) for t in g.lexicon.tokens(text)]
    theirs: list[tuple[Any, ...]] = []
    try:
        for t in g.lark.lex(text):
            theirs.append((t.type, t.value, t.start_pos, t.line, t.column))
    except UnexpectedCharacters as e:
        bad = ours[len(theirs)]
        assert (bad[0], bad[2], bad[3], bad[4]) == (BAD_CHAR, e.pos_in_stream, e.line, e.column), repr(text)
        ours = ours[: len(theirs)]
    assert ours == theirs, repr(text)


def same_parse(g: Grammar, text: str) -> bool:
    """``parse_text`` and ``parse(tokens)`` agree on ``text``; return whether it parsed."""
    general: list[SyntaxProblem] = []
    fast: list[SyntaxProblem] = []
    expected = g.driver.parse(g.lexicon.tokens(text), general)
    got = g.driver.parse_text(g.lexicon, text, fast)
    assert fast == general, repr(text)
    assert shape(got) == shape(expected), repr(text)
    return not general


def plain_looks_like_paper(text: str) -> bool:
    """parser.looks_like_paper as it was: the DSL marks searched in the text with the
    scanner's comments replaced by spaces."""
    mark = _DSL_MARK.search(text)
    if mark is not None and ("//" in text[: mark.start()] or "/*" in text[: mark.start()]):
        cut, last = [], 0
        for offset, comment in SLEEC.lexicon.comments(text):
            cut += [text[last:offset], " "]
            last = offset + len(comment)
        mark = _DSL_MARK.search("".join([*cut, text[last:]]))
    return mark is None and _PAPER_MARK.search(text) is not None


def every_check(text: str) -> None:
    assert looks_like_paper(text) == plain_looks_like_paper(text), repr(text)
    for g in GRAMMARS:
        same_pairs(g, text)
        lark_agrees(g, text)
        same_parse(g, text)


def test_layout_pattern_forms() -> None:
    """Character runs join one class; anything else (a negated class, a class with an edge
    `-`, a longer pattern) stays an alternative of its own."""
    assert layout_pattern(["[ \t]+", "\ufeff"]) == "[ \t\ufeff]*"
    assert layout_pattern(["[ \t]+", "//[^\n]*"]) == "[ \t]*(?:(?://[^\n]*)[ \t]*)*"
    assert layout_pattern(["[^a]+", "[a-]+", "ab"]) == "(?:[^a]+|[a-]+|ab)*"
    assert layout_pattern([]) == ""


def test_the_corpus() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    parsed = 0
    for f in files:
        text = f.read_text(encoding="utf-8", errors="replace")
        assert looks_like_paper(text) == plain_looks_like_paper(text), f.name
        same_pairs(SLEEC, text)
        lark_agrees(SLEEC, text)
        parsed += same_parse(SLEEC, text)
    assert parsed >= 190  # most files parse: the values are compared, not only the errors


def test_mutated_corpus_files() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    rng = random.Random(SEED)
    sources = [f.read_text(encoding="utf-8", errors="replace") for f in files]
    for _ in range(N // 8):
        every_check(mutate(rng, rng.choice(sources)))
        every_check(mutate_words(rng, rng.choice(sources)))


def test_token_soup_and_paper_text() -> None:
    rng = random.Random(SEED)
    for _ in range(N // 4):
        every_check(token_soup(rng))
        every_check(mutate(rng, paper_text(rng)))


@settings(max_examples=max(N // 4, 50), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(text=texts)
def test_generated_text(text: str) -> None:
    every_check(text)


@pytest.mark.parametrize(
    "text",
    [
        "",
        "\ufeff",
        "/* never closed",
        "rule_start R1 when A then B /* open",
        "def_start event A def_end rule_start R1 when A then B rule_end // end",
        "rule_start\n  R1 when A then B\n\n\t\f",
        "rule_start R1 when A then B $ rule_end",
        "relation_start witness A B relation_end rule_start until when A then B rule_end",
        # a token the driver resynchronised for and still cannot take is dropped, not tried
        # again (found by fuzzing a mutant that retried it)
        "Rule0 when until THEN (Start and NOT Stop and ^\u0233when)\n  UNLESS true in which case "
        "Alarm\n  unless ({busy}) AND {flag} IN WHICH CASE (Star\u00aft AND Stop AND Help)\nWhen "
        "Alarm then (NOT Start and Alarm WITHIN 30 minute)\n  UNLESS temp = 13\n  Unless ({flag})"
        "\nR2: WHEN Alarm THEN (Stop)",
    ],
)
def test_edges(text: str) -> None:
    every_check(text)


def test_nodes_built_in_place() -> None:
    """The driver's bodies build nodes without calling their class (transformer._in_place):
    the nodes are still of their class, frozen, equal to what the class makes; a call the
    rewrite cannot reproduce exactly is left as it is."""
    text = "rule_start R1 when A and not {m} then B within 3 seconds unless m rule_end"
    blocks = SLEEC.parse(text, [])
    rule = blocks[0].items[0]
    assert type(rule) is A.Rule and type(rule.trigger.condition) is A.Not
    with pytest.raises(dataclasses.FrozenInstanceError):
        rule.name = "R2"  # type: ignore[misc]
    name = rule.trigger.condition.operand
    assert shape(name) == shape(A.Name("m", braced=True, span=A.Span(1, 31, 1, 32)))
    assert sum("_object_new" in body for body in T._IN_PLACE.values()) >= 15
    for call in ["Span(1, 2, 3, 4)", "Name()", "Name(n, bogus=1)", "Name(*c0)", "Name(n, name=n)"]:
        assert T._in_place(f"return {call}", T.INLINE_ENV) == f"return {call}"
