"""Where the shared SLEEC corpus lives, for tests and benchmarks.

The corpus (215 real ``.sleec`` files) sits beside the project, in
``../shared/sleec-corpus``; ``$COSLEEC_CORPUS`` points elsewhere. It is never copied into
the project. :func:`corpus_files` is what tests and benchmarks call: under CI (``$CI``
set) a missing corpus is an error, not a reason to skip silently.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["CorpusMissingError", "corpus_dir", "corpus_files"]


class CorpusMissingError(FileNotFoundError):
    """The corpus is not where tests look for it; raised only when it is required."""


def corpus_dir() -> Path:
    """The corpus folder: ``$COSLEEC_CORPUS``, else ``../shared/sleec-corpus`` beside the checkout."""
    override = os.environ.get("COSLEEC_CORPUS")
    if override:
        return Path(override)
    return Path(__file__).resolve().parents[3].parent / "shared" / "sleec-corpus"


def corpus_files(*, required: bool | None = None) -> list[Path]:
    """Every ``.sleec`` file of the corpus, sorted; ``[]`` when absent and not required.

    ``required`` defaults to "under CI" (``$CI`` set): there a missing corpus raises
    :class:`CorpusMissingError`, so a CI run can never pass by skipping the corpus tests.
    """
    folder = corpus_dir()
    files = sorted(folder.glob("*.sleec")) if folder.is_dir() else []
    if required is None:
        required = bool(os.environ.get("CI"))
    if required and not files:
        raise CorpusMissingError(f"the SLEEC corpus is not at {folder} (set COSLEEC_CORPUS)")
    return files
