"""The fast driver against plain Lark: same verdict, same AST, on real and generated input.

cosleec parses with its own scanner (lexer.py) feeding its own LALR driver (lalr.py), which
reads Lark's table through Lark internals. The reference is plain Lark over the same grammar:
``Lark(grammar, parser="lalr", lexer="basic", transformer=ToAst())`` with its own lexer (and
the lexicon's post-lexer, which applies the relation-keyword rule of the language reference
§3). Every input is parsed both ways; the two must accept or reject it alike and, when they
accept, build identical ASTs -- spans and syntactic hints (braces, parentheses) included.

Inputs: every corpus file; mutations of corpus files, at random and word by word; token soup;
printed random ASTs in both dialects, whole and mutated; random text in the paper notation. COSLEEC_FUZZ scales the
generated inputs (2,000 by default; 100000 for a long run); COSLEEC_FUZZ_SEED varies them.
"""

from __future__ import annotations

import dataclasses
import os
import random
from typing import Any

import lark
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lark import UnexpectedInput

from cosleec.lang import ast as A
from cosleec.lang.lalr import SyntaxProblem
from cosleec.lang.parser import PAPER, SLEEC, Grammar
from cosleec.lang.printer import format_spec
from cosleec.lang.transformer import Block
from cosleec.testing import corpus_files

from .strategies import mutate, mutate_words, paper_text, specifications, token_soup

N = int(os.environ.get("COSLEEC_FUZZ", "2000"))
SEED = int(os.environ.get("COSLEEC_FUZZ_SEED", "1"))


def shape(x: Any) -> Any:
    """Everything a parse result holds -- spans and hints too, which AST equality ignores."""
    if isinstance(x, Block):
        return ("Block", x.kind, x.span, shape(x.items))
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return (type(x).__name__, *(shape(getattr(x, f.name)) for f in dataclasses.fields(x)))
    if isinstance(x, A.Span):
        return tuple(x)
    if isinstance(x, list | tuple):
        return (type(x).__name__, *(shape(v) for v in x))
    return x


def crosscheck(g: Grammar, text: str) -> bool:
    """Parse ``text`` both ways and compare; return whether it was accepted."""
    try:
        expected = g.lark.parse(text)
    except UnexpectedInput:
        expected = None
    problems: list[SyntaxProblem] = []
    got = g.parse(text, problems)
    if expected is None:
        assert got is None and problems, f"plain Lark rejects, the fast driver accepts:\n{text}"
        return False
    assert not problems, f"plain Lark accepts, the fast driver rejects ({problems[0]}):\n{text}"
    assert shape(got) == shape(expected), f"different ASTs:\n{text}"
    return True


def test_the_pinned_lark_is_installed() -> None:
    """lalr.read_lark_tables reads Lark internals of this version (pyproject.toml pins it)."""
    assert lark.__version__.startswith("1.3."), lark.__version__


def test_every_corpus_file() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    accepted = sum(crosscheck(SLEEC, f.read_text(encoding="utf-8", errors="replace")) for f in files)
    assert accepted >= 190


def test_mutated_corpus_files() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    rng = random.Random(SEED)
    texts = [f.read_text(encoding="utf-8", errors="replace") for f in files]
    for _ in range(N // 8):
        crosscheck(SLEEC, mutate(rng, rng.choice(texts)))
    accepted = sum(crosscheck(SLEEC, mutate_words(rng, rng.choice(texts))) for _ in range(N // 8))
    assert accepted >= N // 80


def test_token_soup() -> None:
    rng = random.Random(SEED)
    for _ in range(N // 2):
        text = token_soup(rng)
        crosscheck(SLEEC, text)
        crosscheck(PAPER, text)


def test_paper_notation() -> None:
    rng = random.Random(SEED)
    accepted = 0
    for _ in range(N // 8):
        text = paper_text(rng)
        accepted += crosscheck(PAPER, text)
        crosscheck(PAPER, mutate(rng, text))
        crosscheck(PAPER, mutate_words(rng, text))
    assert accepted >= N // 16


@settings(
    max_examples=max(N // 80, 5),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(spec=specifications(), seed=st.integers(0, 2**32))
def test_printed_specifications(spec: A.Specification, seed: int) -> None:
    rng = random.Random(seed)
    for dialect in (A.Dialect.TK, A.Dialect.LEGOS):
        text = format_spec(spec, dialect)
        assert crosscheck(SLEEC, text), text
        for _ in range(2):  # cheap next to drawing the specification
            crosscheck(SLEEC, mutate(rng, text))
            crosscheck(SLEEC, mutate_words(rng, text))


PRIORITY_HEAD = "def_start event E def_end rule_start R1 when E then E R2 when E then E rule_end\n"


@pytest.mark.parametrize(
    "block",
    [
        "priority_start priority_end",
        "priority_start R1 > R2 priority_end",
        "priority_start\n  R1 > R2 > R1\n  R2 > R1 R1 > R2\npriority_end",
        "priority_start ^when > witness until > R1 priority_end",  # escapes, relation words as names
        "priority_start R1 > > R2 priority_end",
        "priority_start > R1 priority_end",
        "priority_start R1 priority_end",
        "priority_start R1 < R2 priority_end",
        "priority_start R1 > R2",
        "priority_start R1 > R2 priority_end priority_start R2 > R1 priority_end",
        "relation_start witness E E relation_end priority_start witness > R1 priority_end",
    ],
)
def test_priority_blocks(block: str) -> None:
    """cosleec's priority block (sleec-language.md §13.4), well-formed and not, read both ways."""
    crosscheck(SLEEC, PRIORITY_HEAD + block)
