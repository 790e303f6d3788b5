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
from cosleec.testing import corpus_files

from .strategies import TOKENS, mutate

N = int(os.environ.get("COSLEEC_FUZZ", "2000"))


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


def test_mutated_corpus_files_only_yield_diagnostics() -> None:
    files = corpus_files()
    if not files:
        pytest.skip("SLEEC corpus not found")
    rng = random.Random(int(os.environ.get("COSLEEC_FUZZ_SEED", "1")))
    texts = [f.read_text(encoding="utf-8", errors="replace") for f in files]
    for _ in range(N):
        _assert_only_diagnostics(mutate(rng, rng.choice(texts)))
