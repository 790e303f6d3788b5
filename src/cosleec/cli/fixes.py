"""``cosleec analyse --fix``: under each finding, its verified repairs; per file, the patch set.

Each fix is shown as ``fix N (operator, proof): what it does``, then what else it changes in
the robot's behaviour (how many situations, how many outside the finding, a scenario or
two), then its unified diff. A finding without a fix says why. After a file's findings
comes its patch set -- the fixes that verify *applied together*, what ``--write`` writes --
and each finding it leaves unrepaired, with why. ``--json`` carries the same: each
finding's ``fixes`` and ``why_unrepaired``, each file's ``patch_set``.
"""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.text import Text

from cosleec.analysis import FileReport, Finding
from cosleec.repair import BehaviourChange, Fix, RepairReport, Repairs

SCENARIOS = 2
"""Scenarios shown per fix in text (``--json`` has them all)."""
NOT_TRIED = "not tried: --deadline passed before its turn"


def as_file_report(r: RepairReport) -> FileReport:
    """The analysis' view of a repaired file: what ``cosleec analyse`` prints and exports."""
    return FileReport(
        r.path,
        r.source,
        list(r.findings),
        list(r.unknown),
        {"total": r.seconds},
        list(r.diagnostics),
        dict(r.undecided),
    )


def why_unrepaired(report: RepairReport, f: Finding) -> str:
    """Why ``report``'s patch set leaves ``f`` unrepaired ('' when a fix of the set repairs it,
    its own or one chosen for another finding)."""
    plan = report.plan
    if plan is None:
        return own_why(report, f)
    if any(_same(g, f) for g, _ in plan.along):
        return ""
    for g, why in plan.unrepaired:
        if _same(g, f):
            return own_why(report, f) or why
    return ""


def own_why(report: RepairReport, f: Finding) -> str:
    """Why ``f`` has no fix of its own ('' when it has one)."""
    rep = report.of(f)
    if rep is None:
        return "not repaired"
    if rep.skipped:
        return NOT_TRIED  # the engine skips a finding once the deadline has passed
    return rep.why_none


def _along(report: RepairReport, f: Finding) -> str:
    """How the patch set repairs ``f`` with a fix chosen for another finding ('' if not)."""
    plan = report.plan
    return next((how for g, how in plan.along if _same(g, f)), "") if plan is not None else ""


def _same(a: Finding, b: Finding) -> bool:
    return (a.code, a.subject) == (b.code, b.subject)


def behaviour(b: BehaviourChange | None) -> str:
    """What else a fix changes, in one line."""
    if b is None or not b.computed:
        return f"behaviour change not computed: {b.reason if b is not None else 'not measured'}"
    if b.situations == 0:
        said = "no other behaviour changes"
    else:
        n = f"{b.situations}{'' if b.exact else '+'}"
        said = f"changes behaviour in {n} situation{'s' if n != '1' else ''}, {b.outside} outside the finding"
    return said + (f" (up to bound {b.up_to_bound})" if b.up_to_bound is not None else "")


def show_fixes(out: Console, report: RepairReport, f: Finding) -> None:
    """Under finding ``f``: its fixes, best first, or why it has none."""
    rep = report.of(f)
    fixes = rep.fixes if rep is not None else []
    if not fixes:
        out.print(Text(f"    no fix of its own: {own_why(report, f)}"))
        along = _along(report, f)
        if along:
            out.print(
                Text(f"    the patch set repairs it too, with: {along.removeprefix('repaired along with: ')}")
            )
        return
    chosen = report.plan.fixes if report.plan is not None else []
    for fix in fixes:
        p = fix.patch
        mark = ", in the patch set" if any(fix is c for c in chosen) else ""
        out.print(Text(f"    fix {fix.rank} ({p.operator}, {fix.verdict.proof}{mark}): {p.summary}"))
        out.print(Text(f"      {behaviour(fix.behaviour)}"))
        for s in fix.behaviour.scenarios[:SCENARIOS] if fix.behaviour is not None else ():
            out.print(Text(f"      e.g. {s}"))
        for line in fix.diff.splitlines():
            out.print(Text(f"        {line}"))


def show_patch_set(out: Console, report: RepairReport) -> None:
    """A file's patch set: the fixes that verify together, and what stays unrepaired."""
    plan = report.plan
    if plan is None or not report.findings:
        return
    n = len(plan.fixes)
    if n == 0:
        out.print(Text(f"{report.path}: patch set: empty, nothing for --write to apply"))
    else:
        proof = plan.verdict.proof if plan.verdict is not None else "proved"
        out.print(
            Text(f"{report.path}: patch set: {n} fix{'es' if n != 1 else ''}, verified together ({proof})")
        )
        for fix in plan.fixes:
            out.print(Text(f"    {fix.patch.summary} ({fix.patch.operator})"))
    for f, how in plan.along:
        out.print(Text(f"{report.path}: {f.code} {f.subject}: {how}"))
    for f in report.findings:
        why = why_unrepaired(report, f)
        if why:
            out.print(Text(f"{report.path}: unrepaired: {f.code} {f.subject}: {why}"))


def add_fixes(doc: dict[str, Any], reports: list[RepairReport], written: list[RepairReport]) -> None:
    """Add to ``doc`` (``cosleec analyse --json``, one file per report, in order) each
    finding's ``fixes`` and ``why_unrepaired``, and each file's ``patch_set``."""
    for entry, report in zip(doc["files"], reports, strict=True):
        for fj, f in zip(entry["findings"], report.findings, strict=True):
            rep = report.of(f)
            fj["fixes"] = rep.to_json() if rep is not None else []
            fj["why_unrepaired"] = why_unrepaired(report, f) or None
        entry["patch_set"] = _patch_set(report, any(w is report for w in written))


def _patch_set(report: RepairReport, written: bool) -> dict[str, Any] | None:
    plan = report.plan
    if plan is None:
        return None
    return {
        "fixes": [_chosen(report, fix) for fix in plan.fixes],
        "diff": plan.diff,
        "text": plan.text,
        "verified": plan.verdict.verified if plan.verdict is not None else not plan.fixes,
        "proof": plan.verdict.proof if plan.verdict is not None else None,
        "unrepaired": [
            {"code": f.code, "subject": f.subject, "why": why_unrepaired(report, f)}
            for f in report.findings
            if why_unrepaired(report, f)
        ],
        "along": [{"code": f.code, "subject": f.subject, "how": how} for f, how in plan.along],
        "written": written,
    }


def _chosen(report: RepairReport, fix: Fix) -> dict[str, Any]:
    """A fix of the patch set, with the finding it was chosen for."""
    owner: Repairs | None = next((r for r in report.repairs if any(x is fix for x in r.fixes)), None)
    return {
        "finding": None if owner is None else {"code": owner.finding.code, "subject": owner.finding.subject},
        "rank": fix.rank,
        "operator": fix.patch.operator,
        "summary": fix.patch.summary,
        "rules": list(fix.patch.rules),
    }


__all__ = ["add_fixes", "as_file_report", "behaviour", "show_fixes", "show_patch_set", "why_unrepaired"]
