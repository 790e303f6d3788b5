"""The one conftest: COP isolation for every test, the corpus location, Hypothesis settings.

- COP: the public ``cosleec.testing.plugin`` gives each test a clean global COP
  configuration and restores it afterwards.
- Corpus: ``../shared/sleec-corpus`` (or ``$COSLEEC_CORPUS``); under CI (``$CI`` set) a
  missing corpus fails the run instead of skipping the corpus tests.
- Hypothesis keeps its example database outside the work tree.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir
from hypothesis.database import DirectoryBasedExampleDatabase

from cosleec.testing import corpus_dir, corpus_files

pytest_plugins = ["cosleec.testing.plugin"]

ROOT = Path(__file__).resolve().parent.parent
CORPUS = corpus_dir()

HYPOTHESIS_HOME = Path(tempfile.gettempdir()) / "cosleec-hypothesis"
set_hypothesis_home_dir(str(HYPOTHESIS_HOME))  # everything Hypothesis stores, out of the work tree
settings.register_profile("cosleec", database=DirectoryBasedExampleDatabase(HYPOTHESIS_HOME / "examples"))
settings.load_profile("cosleec")


@pytest.fixture
def corpus() -> list[Path]:
    """The corpus files, or a skip when the corpus is absent (never under CI: there it fails)."""
    files = corpus_files()
    if not files:
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    return files
