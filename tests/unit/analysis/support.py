"""Helpers for the analysis tests: rule files written inline, analysed with chosen settings."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from cosleec.analysis import CHECKS, FileReport, Finding, Settings, analyse_file
from cosleec.lang import HedgeSemantics

HEADER = (
    "def_start event A event B event C event D event E "
    "measure x : boolean measure y : boolean measure m : boolean "
    "measure t : numeric measure d : numeric def_end\n"
)


def sleec(rules: str, extra: str = "", header: str = HEADER) -> str:
    """A rule file: the header, one rule per line of ``rules``, then ``extra`` (LEGOS blocks)."""
    return f"{header}rule_start\n{rules.strip()}\nrule_end\n{extra.strip()}\n"


def write(tmp_path: Path, rules: str, extra: str = "", name: str = "rules.sleec") -> Path:
    path = tmp_path / name
    path.write_text(sleec(rules, extra), encoding="utf-8")
    return path


def analyse(
    path: Path,
    checks: Iterable[str] | str = CHECKS,
    *,
    nested: bool = False,
    legos_compat: bool = False,
    allow_unknown: bool = False,
    **settings: object,
) -> FileReport:
    """``analyse_file`` with ``Settings(**settings)``; a file with errors fails the test."""
    if isinstance(checks, str):
        checks = [checks]
    if nested:
        settings["semantics"] = HedgeSemantics.NESTED
    report = analyse_file(path, Settings(**settings), list(checks), legos_compat=legos_compat)  # type: ignore[arg-type]
    assert not report.failed, [d.message for d in report.diagnostics]
    assert allow_unknown or not report.unknown, report.unknown
    return report


def run(
    tmp_path: Path, rules: str, extra: str = "", checks: Iterable[str] | str = CHECKS, **kw: object
) -> FileReport:
    """Write ``rules`` and analyse them."""
    return analyse(write(tmp_path, rules, extra), checks, **kw)  # type: ignore[arg-type]


def of(report: FileReport, code: str) -> dict[str, Finding]:
    """The findings of one check, by subject (each subject at most once)."""
    found = [f for f in report.findings if f.code == code]
    by = {f.subject: f for f in found}
    assert len(by) == len(found), [f.subject for f in found]
    return by


def subjects(report: FileReport, code: str) -> set[str]:
    return {f.subject for f in report.findings if f.code == code}


def values(situation: str) -> dict[str, object]:
    """``x=true, t=36`` (or z3's ``x=True``) as a dict of Python values."""
    out: dict[str, object] = {}
    for name, raw in re.findall(r"(\w+)=([^,;\s]+)", situation):
        low = raw.lower()
        if low in ("true", "false"):
            out[name] = low == "true"
        elif "/" in raw:
            num, den = raw.split("/")
            out[name] = float(num) / float(den)
        else:
            out[name] = float(raw.rstrip("?"))
    return out


def cli(*args: str, hashseed: str = "0") -> subprocess.CompletedProcess[str]:
    """``cosleec ARGS`` in a fresh process (z3's global state starts empty there)."""
    env = {**os.environ, "PYTHONHASHSEED": hashseed}
    return subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


def cli_json(*args: str, hashseed: str = "0") -> dict[str, Any]:
    """``cosleec analyse --json ARGS`` in a fresh process, without the timings."""
    p = cli("analyse", "--json", *args, hashseed=hashseed)
    assert p.returncode in (0, 1), p.stderr
    doc: dict[str, Any] = json.loads(p.stdout)
    for f in doc["files"]:
        f.pop("seconds")
    return doc
