"""The 18 LEGOS case studies (N-Check's evaluation) analysed whole: no exception, every
witness confirmed by the reference semantics, every finding well formed."""

from __future__ import annotations

import pytest

from cosleec.analysis import BOUNDED, CHECKS, DEFAULT_BOUND, PROVED, Settings, analyse_file
from cosleec.lang import load
from cosleec.testing import corpus_dir

STUDIES = ["ALMI", "ASPEN", "Autocar", "BSN", "CSI", "DAISY", "gdpr", "dressingAssist", "safescade"]
CORPUS = corpus_dir()
FILES = sorted(
    p.name for study in STUDIES for p in CORPUS.glob(f"NickF0211__LEGOS-SLEEC__{study}__*.sleec")
) or [f"NickF0211__LEGOS-SLEEC__{s}__missing.sleec" for s in STUDIES]

pytestmark = pytest.mark.slow  # about 20 s for the 18 files on two cores


def test_the_eighteen_case_studies_are_there() -> None:
    if not CORPUS.is_dir():
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    assert len(FILES) == 18


@pytest.mark.parametrize("name", FILES)
def test_a_case_study_analyses_cleanly(name: str) -> None:
    path = CORPUS / name
    if not path.exists():
        pytest.skip(f"SLEEC corpus not found at {CORPUS}")
    report = analyse_file(path, Settings(), CHECKS, legos_compat=True)
    assert not report.failed, [d.message for d in report.diagnostics if d.is_error]
    lines = report.source.splitlines()
    spec = load(path, legos_compat=True)  # type: ignore[call-arg]
    names = {r.name for r in spec.rules} | {f"relation {i + 1}" for i in range(len(spec.relations))}
    unconfirmed = []
    for f in report.findings:
        assert f.code in CHECKS
        assert f.status in (PROVED, BOUNDED)
        assert f.bound == (DEFAULT_BOUND if f.status == BOUNDED else None), f
        assert set(f.rules) <= names, f
        assert 1 <= f.span.line <= len(lines), f
        if f.witness is not None:
            assert f.witness.steps and f.witness.timeline
            if not f.witness.confirmed:
                unconfirmed.append(f"{f.code} {f.subject}")
    assert not unconfirmed, unconfirmed
