"""Repairing a file: its findings, each one's verified fixes, and a set that holds together.

:func:`repair_file` checks and analyses the file as ``cosleec analyse`` does, asks the
operators for candidates per finding, verifies each (verify.py), measures what else the
verified ones change (behaviour.py) and ranks them (fixes.py); then it builds the file's
patch set (together.py): the best fixes that verify *applied together*.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from cosleec.analysis import Coverage, Finding, Settings
from cosleec.lang import Diagnostic, read_source
from cosleec.repair.fixes import Repairs
from cosleec.repair.repairing import Budget, repairs_of
from cosleec.repair.together import PatchSet, together
from cosleec.repair.verify import Reading, key
from cosleec.repair.workers import in_parallel

SIDE_BY_SIDE_FROM = 4
"""Findings from which a file's repairs are shared out among worker processes: starting one
costs about a second (a fresh interpreter, the file analysed once more), which fewer
findings do not win back."""


@dataclass
class RepairReport:
    """The repairs of one file: per finding (in the analysis' order) and the patch set."""

    path: str
    source: str
    findings: list[Finding] = field(default_factory=list)
    unknown: list[str] = field(default_factory=list)
    repairs: list[Repairs] = field(default_factory=list)
    plan: PatchSet | None = None
    undecided: dict[str, list[str] | None] = field(default_factory=dict)  # as FileReport's
    diagnostics: list[Diagnostic] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def failed(self) -> bool:
        """The file could not be analysed (it has errors)."""
        return any(d.is_error for d in self.diagnostics)

    def of(self, f: Finding) -> Repairs | None:
        """The repairs of finding ``f``."""
        return next((r for r in self.repairs if key(r.finding) == key(f)), None)


def repair_file(
    path: str | Path,
    settings: Settings,
    *,
    legos_compat: bool = False,
    infer_defs: bool = False,
    coverage: Coverage | None = None,
    budget: Budget | None = None,
) -> RepairReport:
    """Analyse ``path`` and find verified, ranked repairs for each finding, and a patch set."""
    t0 = time.perf_counter()
    source, problem = read_source(path)
    if source is None:
        return RepairReport(str(path), "", diagnostics=[problem] if problem is not None else [])
    reading = Reading(str(path), settings, legos_compat, infer_defs, coverage)
    report = repair_text(source, reading, budget)
    report.seconds = time.perf_counter() - t0
    return report


def repair_text(source: str, reading: Reading, budget: Budget | None = None) -> RepairReport:
    """:func:`repair_file` on a text already read."""
    t0 = time.perf_counter()
    budget = budget or Budget()
    checked = reading.check(source)
    report = RepairReport(reading.path, source, diagnostics=list(checked.diagnostics))
    if not checked.ok or checked.spec is None:
        return report
    report.findings, report.unknown, left = reading.analyse(checked, budget.deadline)
    report.undecided = left
    if budget.workers > 1 and len(report.findings) >= SIDE_BY_SIDE_FROM:
        workers = min(budget.workers, len(report.findings))
        report.repairs = in_parallel(source, reading, report.findings, budget, workers)
    else:
        report.repairs = [
            repairs_of(f, source, checked, report.findings, reading, budget) for f in report.findings
        ]
    report.plan = together(source, checked.spec, report.findings, report.repairs, reading, budget.deadline)
    report.seconds = time.perf_counter() - t0
    return report


__all__ = ["RepairReport", "repair_file", "repair_text"]
