"""Public test helpers for cosleec users and its own tests (floor 2: may import nodes and below).

- :func:`isolated_cop` -- run a block, then restore the global COP configuration;
  the pytest plugin ``cosleec.testing.plugin`` applies it to every test;
- :func:`corpus_files`, :func:`corpus_dir` -- the shared SLEEC corpus (a missing corpus
  fails under CI instead of skipping);
- :func:`percentile` -- the nearest-rank percentile the benchmarks report.

Importing this face never needs pytest.
"""

from cosleec.testing.browser import CHROMIUM, CHROMIUM_ARGS
from cosleec.testing.cop import isolated_cop
from cosleec.testing.corpus import CorpusMissingError, corpus_dir, corpus_files
from cosleec.testing.stats import percentile

__all__ = [
    "CHROMIUM",
    "CHROMIUM_ARGS",
    "CorpusMissingError",
    "corpus_dir",
    "corpus_files",
    "isolated_cop",
    "percentile",
]
