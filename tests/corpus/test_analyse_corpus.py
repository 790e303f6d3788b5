"""``cosleec analyse`` on every file of the shared corpus: no exception, every witness confirmed.

A file with errors is reported with its diagnostics (``--legos-compat`` reads N-Check's case
studies); every other file is analysed with every check. CI runs at bound 3 with one second
per question (about a minute for the 215 files); ``COSLEEC_ANALYSE_FULL=1`` runs the
defaults (bound 6, 5 s per question; a few minutes).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from cosleec.analysis import CHECKS, Settings, analyse_file
from cosleec.testing import corpus_files

FULL = os.environ.get("COSLEEC_ANALYSE_FULL") == "1"
SETTINGS = Settings() if FULL else Settings(bound=3, timeout=1.0)
FILES = corpus_files()


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_every_corpus_file_is_analysed_without_an_exception(path: Path) -> None:
    report = analyse_file(path, SETTINGS, legos_compat=True)
    if report.failed:  # the corpus has real defects: reported as diagnostics, not analysed
        assert report.findings == [] and any(d.is_error for d in report.diagnostics)
        return
    assert {f.code for f in report.findings} <= set(CHECKS)
    for f in report.findings:
        assert f.span.line > 0 or f.code in ("unimplemented-clause",), f
        assert f.status == "proved" or (f.bound is not None and f.bound <= SETTINGS.bound)
        if f.witness is not None:
            assert f.witness.confirmed, (f.code, f.subject)
        if f.code in ("vacuous-conflict", "situational-conflict", "purpose-blocked"):
            assert f.rules, f  # a conflict or a blocked purpose always names its cause


def test_the_corpus_is_there() -> None:
    assert len(FILES) >= 200 or not os.environ.get("CI")
