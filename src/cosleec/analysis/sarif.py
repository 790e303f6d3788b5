"""SARIF 2.1.0: the findings in the format editors and code-review tools read.

One run, tool ``cosleec analyse`` with one rule per check; one result per finding with its
location (file, line, column), the rules involved as related locations, the proof status
and witness in ``properties``. A file with errors becomes a notification, not a result; so
does each check the deadline cut short, and the run is then not ``executionSuccessful``.
"""

from __future__ import annotations

from collections.abc import Iterable
from importlib import metadata
from pathlib import Path
from typing import Any

from cosleec.analysis.findings import CHECKS, FileReport, Finding
from cosleec.lang import ast as A

SCHEMA = "https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/sarif-schema-2.1.0.json"
LEVEL = {"error": "error", "warning": "warning", "note": "note"}


def sarif(reports: Iterable[FileReport], checks: Iterable[str] = CHECKS) -> dict[str, Any]:
    """The SARIF log (a JSON-ready dict) of ``reports``."""
    codes = list(CHECKS)
    results: list[dict[str, Any]] = []
    notes: list[dict[str, Any]] = []
    reports = list(reports)
    complete = all(r.complete for r in reports)  # False: a partial run (--deadline)
    for r in reports:
        uri = Path(r.path).as_posix()
        if r.failed:
            for d in r.diagnostics:
                if d.is_error:
                    notes.append(
                        {
                            "level": "error",
                            "message": {"text": f"not analysed: {d.message}"},
                            "locations": [_location(uri, d.span)],
                        }
                    )
        for code, subjects in r.undecided.items():  # the deadline cut the run short
            left = "not run" if subjects is None else f"not decided for {', '.join(subjects)}"
            notes.append(
                {
                    "level": "warning",
                    "message": {"text": f"{code}: {left} (the deadline passed)"},
                    "locations": [_location(uri, A.NO_SPAN)],
                }
            )
        for f in r.findings:
            results.append(_result(uri, f, codes))
    return {
        "$schema": SCHEMA,
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "cosleec analyse",
                        "version": _version(),
                        "informationUri": "https://github.com/cosleec/cosleec",
                        "rules": [
                            {"id": c, "name": c, "shortDescription": {"text": CHECKS[c]}} for c in codes
                        ],
                    }
                },
                "invocations": [{"executionSuccessful": complete, "toolExecutionNotifications": notes}],
                "results": results,
            }
        ],
    }


def _version() -> str:
    try:
        return metadata.version("cosleec")
    except metadata.PackageNotFoundError:  # run from a source tree without installing
        return "0"


def _location(uri: str, span: A.Span) -> dict[str, Any]:
    loc: dict[str, Any] = {"physicalLocation": {"artifactLocation": {"uri": uri}}}
    if span.line:
        region: dict[str, Any] = {"startLine": span.line, "startColumn": max(span.col, 1)}
        if span.end_line >= span.line and span.end_line:
            region["endLine"] = span.end_line
            if span.end_col > 0 and (span.end_line > span.line or span.end_col > span.col):
                region["endColumn"] = span.end_col
        loc["physicalLocation"]["region"] = region
    return loc


def _result(uri: str, f: Finding, codes: list[str]) -> dict[str, Any]:
    text = f"{f.message} [{f.proof}]"
    if f.hint:
        text += f" -- {f.hint}"
    out: dict[str, Any] = {
        "ruleId": f.code,
        "ruleIndex": codes.index(f.code),
        "level": LEVEL[str(f.severity)],
        "message": {"text": text},
        "locations": [_location(uri, f.span)],
        "partialFingerprints": {"cosleec/v1": f"{f.code}:{f.subject}:{','.join(f.rules)}"},
        "properties": {
            "status": f.status,
            "bound": f.bound,
            "rules": list(f.rules),
            "subject": f.subject,
        },
    }
    related = [
        {"id": i, "message": {"text": note}, **_location(uri, span)}
        for i, (note, span) in enumerate(f.related)
        if span.line
    ]
    if related:
        out["relatedLocations"] = related
    if f.situation:
        out["properties"]["situation"] = f.situation
    if f.witness is not None:
        out["properties"]["witness"] = f.witness.jsonl().splitlines()
        out["properties"]["witnessConfirmed"] = f.witness.confirmed
    return out
