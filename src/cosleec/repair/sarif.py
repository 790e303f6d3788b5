"""SARIF 2.1.0 fixes: the verified repairs of each finding, in the log ``cosleec analyse`` writes.

:func:`cosleec.analysis.sarif` builds the log (the analysis knows nothing of repair);
:func:`with_fixes` adds to each result the fixes of its finding (SARIF 2.1.0, section 3.55),
best first: a ``description``, and one ``artifactChange`` whose replacements are the patch's
edits, each a region of the *original* file (``charOffset``/``charLength`` in Unicode code
points, ``byteOffset``/``byteLength`` in UTF-8 bytes) and the text that takes its place. A
code-review tool that applies them to the file as analysed gets exactly the fix's patched
text. Each run also gets, in its ``properties``, every file's patch set: the fixes that
verify applied together, and the findings it leaves unrepaired with why.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from cosleec.repair.fixes import Fix, Repairs
from cosleec.repair.patch import Edit, Patch
from cosleec.repair.run import RepairReport


def with_fixes(log: dict[str, Any], reports: list[RepairReport]) -> dict[str, Any]:
    """A copy of the SARIF ``log`` of ``reports``' findings with each result's ``fixes``.

    A result is matched to its finding by file, check and subject (``ruleId`` and
    ``properties.subject``, as :func:`cosleec.analysis.sarif` writes them); a result with no
    matching finding, or a finding without a fix, gets no ``fixes``.
    """
    out = copy.deepcopy(log)
    pending: dict[tuple[str, str, str], list[tuple[RepairReport, Repairs]]] = {}
    for report in reports:
        uri = Path(report.path).as_posix()
        for rep in report.repairs:
            pending.setdefault((uri, rep.finding.code, rep.finding.subject), []).append((report, rep))
    for run in out.get("runs", []):
        for result in run.get("results", []):
            matches = pending.get(_identity(result))
            if not matches:
                continue
            report, rep = matches.pop(0)
            if rep.fixes:
                uri = Path(report.path).as_posix()
                result["fixes"] = [fix_object(uri, report.source, fix) for fix in rep.fixes]
        run.setdefault("properties", {})["patchSets"] = [_patch_set(r) for r in reports if r.plan is not None]
    return out


def fix_object(uri: str, source: str, fix: Fix) -> dict[str, Any]:
    """The SARIF ``fix`` of one verified repair of the file at ``uri`` whose text is ``source``."""
    patch = fix.patch
    return {
        "description": {"text": f"{patch.summary} ({patch.operator}, {fix.verdict.proof})"},
        "artifactChanges": [
            {
                "artifactLocation": {"uri": uri},
                "replacements": [_replacement(source, e) for e in replacements(source, patch)],
            }
        ],
        "properties": {
            "rank": fix.rank,
            "operator": patch.operator,
            "rules": list(patch.rules),
            "verified": fix.verdict.verified,
            "proof": fix.verdict.proof,
            "behaviour": fix.to_json()["behaviour"],
        },
    }


def replacements(source: str, patch: Patch) -> list[Edit]:
    """``patch``'s edits in file order, as SARIF replacements must be: regions of the original
    that do not overlap. Edits that start at one place (two insertions there) become one,
    written as :meth:`Patch.apply` writes them."""
    groups: list[list[Edit]] = []
    for e in sorted(patch.edits, key=lambda e: (e.start, e.end)):
        if groups and groups[-1][0].start == e.start:
            groups[-1].append(e)
        else:
            groups.append([e])
    out = []
    for group in groups:
        start, end = group[0].start, max(e.end for e in group)
        shifted = tuple(Edit(e.start - start, e.end - start, e.text) for e in group)
        out.append(Edit(start, end, Patch("", "", (), shifted).apply(source[start:end])))
    return out


def _replacement(source: str, e: Edit) -> dict[str, Any]:
    byte_start = len(source[: e.start].encode("utf-8"))
    byte_length = len(source[e.start : e.end].encode("utf-8"))
    return {
        "deletedRegion": {
            "charOffset": e.start,
            "charLength": e.end - e.start,
            "byteOffset": byte_start,
            "byteLength": byte_length,
        },
        "insertedContent": {"text": e.text},
    }


def _identity(result: dict[str, Any]) -> tuple[str, str, str]:
    """A result's file, check and subject: what it shares with its finding."""
    locations = result.get("locations") or [{}]
    uri = locations[0].get("physicalLocation", {}).get("artifactLocation", {}).get("uri", "")
    return uri, result.get("ruleId", ""), result.get("properties", {}).get("subject", "")


def _patch_set(report: RepairReport) -> dict[str, Any]:
    """A file's patch set as a run property: which fixes, whether they verify together, and
    what stays unrepaired."""
    plan = report.plan
    assert plan is not None
    return {
        "uri": Path(report.path).as_posix(),
        "fixes": [{"operator": f.patch.operator, "summary": f.patch.summary} for f in plan.fixes],
        "verified": plan.verdict.verified if plan.verdict is not None else not plan.fixes,
        "proof": plan.verdict.proof if plan.verdict is not None else None,
        "unrepaired": [{"ruleId": f.code, "subject": f.subject, "why": why} for f, why in plan.unrepaired],
    }


__all__ = ["fix_object", "replacements", "with_fixes"]
