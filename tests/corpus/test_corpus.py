"""Conformance on the real corpus (../shared/sleec-corpus; skipped when absent locally, failing under CI)."""

from __future__ import annotations

import collections
from pathlib import Path

import pytest

from cosleec.lang import analyse, analyse_file, format_spec
from cosleec.testing import corpus_dir

from .expected import REJECTED

CORPUS = corpus_dir()


def index() -> dict[str, tuple[bool, str]]:
    """file -> (accepted by at least one tool, notes), from the corpus' INDEX.md."""
    out: dict[str, tuple[bool, str]] = {}
    for line in (CORPUS / "INDEX.md").read_text(encoding="utf-8").splitlines():
        if line.startswith("| ") and ".sleec`" in line:
            cols = [c.strip() for c in line.split("|")]
            out[cols[2].strip("`")] = (cols[7].startswith("yes") or cols[8].startswith("yes"), cols[10])
    return out


def test_corpus_conformance(corpus: list[Path], capsys: pytest.CaptureFixture[str]) -> None:
    idx = index()
    assert len(idx) == len(corpus) == 215
    tally: collections.Counter[str] = collections.Counter()
    problems = []
    for path in corpus:
        accepted, notes = idx[path.name]
        result = analyse_file(path)
        codes = {d.code for d in result.errors}
        if accepted:
            if result.spec is None:
                problems.append(
                    f"{path.name}: accepted by its tool but does not parse: {result.render()[:300]}"
                )
            elif codes:
                expected = REJECTED.get(path.name)
                if expected is None or expected[0] != codes:
                    problems.append(f"{path.name}: unexpected errors {sorted(codes)}")
                tally["accepted, rejected for a named defect"] += 1
            else:
                tally["accepted and clean"] += 1
        else:
            if not codes:
                problems.append(f"{path.name}: no tool accepts it, but cosleec reports no error")
            elif any(d.span.line == 0 for d in result.errors if d.code != "no-def-block"):
                problems.append(f"{path.name}: an error without a position")
            tally["rejected by every tool, and by cosleec"] += 1
        if "fragment" in notes:
            assert codes == {"no-def-block"}, path.name
            inferred = analyse_file(path, infer_defs=True)
            assert inferred.spec is not None and inferred.spec.measures, path.name
            tally["fragments readable with --infer-defs"] += 1 if inferred.ok else 0
    assert set(REJECTED) <= {p.name for p in corpus}
    assert not problems, "\n".join(problems)
    with capsys.disabled():
        print("\ncorpus tally:", dict(tally))


def test_every_parsed_corpus_file_round_trips_in_both_dialects(corpus: list[Path]) -> None:
    count = 0
    for path in corpus:
        result = analyse_file(path, infer_defs=True)
        if result.spec is None:
            continue
        for dialect in ("tk", "legos"):
            again = analyse(format_spec(result.spec, dialect), infer_defs=True)
            assert again.spec == result.spec, (path.name, dialect)
            count += 1
    assert count >= 2 * 190


def test_legos_defects_are_read_as_legos_reads_them(corpus: list[Path]) -> None:
    """Every LEGOS-dialect file rejected only for what LEGOS-SLEEC lets through (cross-scale
    literals, a scale against a number, duplicate names) is ok under ``legos_compat`` (§11 item 18),
    and the specification it gives checks clean without the option."""
    lenient = {"scale-literal", "type", "duplicate-rule", "duplicate-name"}
    count = 0
    for name, (codes, _) in REJECTED.items():
        result = analyse_file(CORPUS / name)
        if str(result.dialect) != "legos" or not codes <= lenient:
            continue
        compat = analyse_file(CORPUS / name, legos_compat=True)
        assert compat.ok and compat.spec is not None, (name, compat.render())
        again = analyse(format_spec(compat.spec, "legos"))
        assert again.ok and again.spec == compat.spec, name
        count += 1
    assert count >= 18
