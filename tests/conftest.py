"""Shared test fixtures: where the SLEEC corpus lives (tests skip cleanly without it)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("COSLEEC_CORPUS", ROOT.parent / "shared" / "sleec-corpus"))


def corpus_files() -> list[Path]:
    return sorted(CORPUS.glob("*.sleec")) if CORPUS.is_dir() else []


@pytest.fixture
def corpus() -> list[Path]:
    files = corpus_files()
    if not files:
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    return files
