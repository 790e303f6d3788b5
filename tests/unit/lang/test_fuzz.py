"""Robustness: whatever the input, the front-end only ever answers with diagnostics.

`analyse` must never raise and `parse` may raise only SleecError. Inputs: token soup from
Hypothesis, and random mutations of real corpus files. COSLEEC_FUZZ sets the number of
inputs per test (2,000 by default; set it to 100000 for a long run).
"""

from __future__ import annotations

import os
import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.lang import SleecError, analyse, parse
from cosleec.lang.lexer import CONTEXTUAL_KEYWORDS, KEYWORDS
from tests.conftest import corpus_files

N = int(os.environ.get("COSLEEC_FUZZ", "2000"))

# every keyword the lexer knows, plus names, numbers, punctuation and junk
TOKENS = [
    *sorted(KEYWORDS | CONTEXTUAL_KEYWORDS),
    "R1",
    "E",
    "F",
    "a",
    "b",
    "x",
    "low",
    "high",
    "0",
    "5",
    "-3",
    "2.5",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "=",
    "->",
    "<",
    ">",
    "<=",
    ">=",
    "<>",
    "+",
    "-",
    "*",
    "/",
    "//",
    "/*",
    "*/",
    "^",
    "é",
    "\\rtf",
    "WHEN",
    "THEN",
    "UNLESS",
    "IN",
    "WHICH",
    "CASE",
]


def _assert_only_diagnostics(text: str) -> None:
    result = analyse(text, infer_defs=True)
    for d in result.diagnostics:
        assert d.code and d.message and d.span.line >= 0
    try:
        parse(text)
    except SleecError as e:
        assert e.diagnostics


@settings(max_examples=N, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.lists(st.sampled_from(TOKENS) | st.text(max_size=3), max_size=60).map(" ".join))
def test_token_soup_only_yields_diagnostics(text: str) -> None:
    _assert_only_diagnostics(text)


def _mutate(rng: random.Random, text: str) -> str:
    for _ in range(rng.randint(1, 4)):
        if not text:
            break
        i, j = sorted(rng.randrange(len(text) + 1) for _ in range(2))
        op = rng.randrange(5)
        if op == 0:
            text = text[:i] + text[j:]  # delete a span
        elif op == 1:
            text = text[:i] + text[i:j] + text[i:]  # duplicate a span
        elif op == 2:
            text = text[:i] + " " + rng.choice(TOKENS) + " " + text[i:]  # insert a token
        elif op == 3:
            text = text[:i]  # truncate
        else:
            text = text[:i] + chr(rng.randrange(1, 0x250)) + text[i:]  # a stray character
    return text


def test_mutated_corpus_files_only_yield_diagnostics() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    rng = random.Random(int(os.environ.get("COSLEEC_FUZZ_SEED", "1")))
    texts = [f.read_text(encoding="utf-8", errors="replace") for f in files]
    for _ in range(N):
        _assert_only_diagnostics(_mutate(rng, rng.choice(texts)))
