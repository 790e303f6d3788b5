"""``cosleec analyse --fix`` on N-Check's nine case studies, initial versions (issue 30).

Each initial file (ALMI, ASPEN, Autocar, BSN, CSI, DAISY, DPA, DressAssist, SafeSCAD; the
non-corrected ``NickF0211__LEGOS-SLEEC__*`` files) is read as LEGOS reads it
(``legos_compat``), with the default ``Settings()`` and the repair ``Budget()`` the command
line uses (``cosleec analyse --fix``: findings repaired side by side, one worker per core),
one file after another. For every finding of the four kinds N-Check reports
(``vacuous-conflict`` and ``situational-conflict``, ``redundant``, ``concern-raised``,
``purpose-blocked``) it reports:

- **repaired**: whether :func:`cosleec.repair.repair_file` found at least one verified fix;
  every finding it does not repair is listed with its reason (``Repairs.why_none``), and the
  reasons are grouped by kind (:func:`reason_kind`);
- **time per finding**: ``Repairs.seconds`` (the candidates, their verification and the
  behavioural diff), median and worst; and the total per file: the wall time of
  ``repair_file``, which includes the file's analysis and its patch set;
- **applied together**: the file's patch set (``RepairReport.plan``) is verified by the
  engine, and its text is analysed again here, independently
  (:func:`cosleec.analysis.analyse_spec`, same settings), to count the findings it has that
  the original file does not have (same code and subject): the target is 0 for every file.
  The findings of the four kinds still there after the set, and the ones the set leaves
  unrepaired (``PatchSet.unrepaired``, with why), are listed too; a file with no fix has an
  empty set (counted apart, neither verified nor refused);
- **expert agreement**: how often the top-ranked fix touches a rule the experts changed.
  The rules the experts changed (:func:`expert_changes`) are the names, after reading both
  files with ``legos_compat``, of the rules of the initial file that the corrected file
  (``*-corrected.sleec`` / ``*-Corrected.sleec``) does not have, of the rules it has that
  the initial file does not, and of the rules both have whose ASTs differ (trigger or
  response; positions and comments do not count). A top fix **agrees**
  (:func:`agrees`) when a rule it names (``Patch.rules``) is one of them, or, for an
  ``add-rule`` fix, when a rule it adds (a rule name in the fixed text that the initial
  file lacks) is triggered by an event that triggers one of the changed rules (in either
  version). ``expert_agreement`` is the agreeing findings over the findings (of the four
  kinds) that have a top fix. Concerns and purposes the experts edited are not rules and
  do not count.

Findings of other kinds (dead rules, unselectable clauses, ...) are repaired too and counted
apart (``other_findings``); the targets are about the four kinds. Targets (issue 30, on 2
cores): ``repaired_percent`` >= 90 (SLEEC-PATCH: 75 %, with an LLM), median <= 5 s and worst
<= 60 s per finding (SLEEC-PATCH: 35.7 s and 277 s), 0 new findings with each file's set
applied. The baseline measured in the same run: the plain analysis of the same files
(:func:`cosleec.analysis.analyse_file`); ``repair_over_analysis`` is the repair's total as a
multiple of it.

``--quick`` runs three of the nine files (ALMI, BSN, DAISY: a situational conflict,
redundancies and concerns; about a minute on two cores) so that CI can smoke it; the
targets are then judged on those three. The JSON also lists, per file, every finding with
its time, its top fix and the candidates refused for it, the patch set's fixes, what the
set leaves, and the rules the experts changed; ``rejections_by_operator`` counts, for the
findings left unrepaired, why each operator's candidates were refused.
"""

from __future__ import annotations

import os
import re
import statistics
import sys
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from _common import CORPUS, args, report
from cosleec.analysis import Finding, Settings, analyse_file, analyse_spec
from cosleec.lang import analyse as check_text
from cosleec.lang import ast as A
from cosleec.repair import Budget, Fix, Patch, RepairReport, Repairs, repair_file

STUDIES = ("ALMI", "ASPEN", "Autocar", "BSN", "CSI", "DAISY", "gdpr", "dressingAssist", "safescade")
QUICK = ("ALMI", "BSN", "DAISY")
KINDS = ("vacuous-conflict", "situational-conflict", "redundant", "concern-raised", "purpose-blocked")
"""The codes of the findings N-Check reports: conflicts, redundancies, concerns, purposes."""
REPAIRED_TARGET = 90.0  # percent of the findings of KINDS
MEDIAN_TARGET = 5.0  # seconds per finding
WORST_TARGET = 60.0
SLEEC_PATCH = {"repaired_percent": 75.0, "median_s": 35.7, "mean_s": 47.1, "worst_s": 277.0}
"""SLEEC-PATCH's published run on the same nine files (issue 30)."""


# ------------------------------------------------------------------------------ the corpus


def initial_files(studies: tuple[str, ...] = STUDIES) -> list[Path]:
    """The initial (not corrected) case-study files of ``studies``, in a stable order."""
    return sorted(
        f
        for f in CORPUS.glob("NickF0211__LEGOS-SLEEC__*__*.sleec")
        if f.name.split("__")[2] in studies and "corrected" not in f.name.lower()
    )


def corrected_of(initial: Path) -> Path | None:
    """The experts' corrected version of ``initial`` (``X-corrected`` or ``X-Corrected``)."""
    for suffix in ("-corrected", "-Corrected"):
        candidate = initial.with_name(f"{initial.stem}{suffix}{initial.suffix}")
        if candidate.exists():
            return candidate
    return None


# ------------------------------------------------------------------------- expert agreement


@dataclass(frozen=True)
class Changes:
    """What the experts changed between a file and its corrected version: the rule names
    removed, added or edited, and the events that trigger those rules (in either version)."""

    rules: frozenset[str]
    events: frozenset[str]


def spec_of(text: str, path: str) -> A.Specification:
    """``text`` read as LEGOS reads it; a file that does not check is an error here."""
    result = check_text(text, path, legos_compat=True)
    if not result.ok or result.spec is None:
        raise ValueError(f"{path} does not check: {result.render()}")
    return result.spec


def _cpu() -> float:
    """CPU seconds of this process and of its finished children (the repair's workers)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def expert_changes(initial: str, corrected: str, path: str = "<initial>") -> Changes:
    """The rules the experts changed: in one version only, or in both with different ASTs."""
    before = {r.name: r for r in spec_of(initial, path).rules}
    after = {r.name: r for r in spec_of(corrected, f"{path} (corrected)").rules}
    changed = {n for n in before.keys() | after.keys() if before.get(n) != after.get(n)}
    events = {r.trigger.event for side in (before, after) for n, r in side.items() if n in changed}
    return Changes(frozenset(changed), frozenset(events))


def added_triggers(before: A.Specification, after: A.Specification) -> frozenset[str]:
    """The trigger events of the rules ``after`` has and ``before`` has not (by name)."""
    known = {r.name for r in before.rules}
    return frozenset(r.trigger.event for r in after.rules if r.name not in known)


def agrees(patch: Patch, added: frozenset[str], changes: Changes) -> bool:
    """Whether a top fix touches what the experts changed: a rule it names is a changed
    rule, or (``add-rule`` only) a rule it adds has a changed rule's trigger event."""
    if set(patch.rules) & changes.rules:
        return True
    return patch.operator == "add-rule" and bool(added & changes.events)


# ------------------------------------------------------------------------------ reasons


_PATTERNS = (
    (re.compile(r"^\d+ candidates?, none verified: "), ""),
    (re.compile(r"^new finding: (\S+) .*$"), r"new finding: \1"),
    (re.compile(r"^(\S+) .* is still reported$"), r"the finding is still reported"),
    (re.compile(r"^not settled: .*$"), "not settled by the solver"),
    (re.compile(r"^the patched file does not check: .*$"), "the patched file does not check"),
)


def reason_kind(why: str) -> str:
    """``why`` (``Repairs.why_none`` or a patch set's reason) without the rule names and
    counts that make each one different, so that reasons of one kind group together:
    ``"3 candidates, none verified: new finding: redundant R5; redundant R2 is still
    reported"`` is ``"none verified: new finding: redundant; the finding is still reported"``."""
    head = "none verified: " if _PATTERNS[0][0].match(why) else ""
    body = _PATTERNS[0][0].sub("", why)
    if not head:
        return body
    parts = []
    for part in body.split("; "):
        for pattern, repl in _PATTERNS[1:]:
            part = pattern.sub(repl, part)
        parts.append(part)
    return head + "; ".join(sorted(set(parts)))


# ---------------------------------------------------------------------------- one file


def keys(findings: list[Finding]) -> set[tuple[str, str]]:
    return {(f.code, f.subject) for f in findings}


def reanalyse(text: str, path: str, settings: Settings) -> list[Finding]:
    """The findings of ``text`` (a patch set applied), analysed afresh with ``settings``."""
    result = check_text(text, path, legos_compat=True)
    if not result.ok or result.spec is None or result.symbols is None:
        raise ValueError(f"the patch set of {path} does not check: {result.render()}")
    found, _ = analyse_spec(result.spec, dict(result.symbols.constant_values), settings)
    return found


def top_of(r: Repairs, original: A.Specification, changes: Changes | None) -> dict[str, Any] | None:
    """The top-ranked fix of ``r`` as JSON, with whether it agrees with the experts."""
    if not r.fixes:
        return None
    fix: Fix = r.fixes[0]
    after = fix.verdict.checked.spec if fix.verdict.checked is not None else None
    if after is None:
        after = spec_of(fix.text, "<fix>")
    added = added_triggers(original, after)
    b = fix.behaviour
    return {
        "operator": fix.patch.operator,
        "summary": fix.patch.summary,
        "rules": list(fix.patch.rules),
        "added_triggers": sorted(added),
        "proof": fix.verdict.proof,
        "situations_changed": None if b is None or not b.computed else b.situations,
        "agrees": None if changes is None else agrees(fix.patch, added, changes),
    }


def finding_row(r: Repairs, original: A.Specification, changes: Changes | None) -> dict[str, Any]:
    f = r.finding
    return {
        "code": f.code,
        "subject": f.subject,
        "rules": list(f.rules),
        "repaired": bool(r.fixes),
        "fixes": len(r.fixes),
        "rejected": len(r.rejected),
        "seconds": round(r.seconds, 3),
        "why": r.why_none,
        "top": top_of(r, original, changes),
        "candidates_rejected": []
        if r.fixes
        else [{"operator": p.operator, "summary": p.summary, "reasons": list(rs)} for p, rs in r.rejected],
    }


def set_row(rep: RepairReport, settings: Settings) -> dict[str, Any]:
    """The patch set: the engine's verdict, and an independent analysis of its text."""
    plan = rep.plan
    if plan is None:
        return {"fixes": 0, "verified": None, "new_findings": [], "left_of_kinds": [], "unrepaired": []}
    after = reanalyse(plan.text, rep.path, settings) if plan.fixes else list(rep.findings)
    new = sorted(keys(after) - keys(rep.findings))
    return {
        "fixes": len(plan.fixes),
        "operators": [f.patch.operator for f in plan.fixes],
        "verified": None if plan.verdict is None else plan.verdict.verified,
        "engine_reasons": [] if plan.verdict is None else list(plan.verdict.reasons),
        "new_findings": [f"{c} {s}" for c, s in new],
        "left_of_kinds": sorted(f"{f.code} {f.subject}" for f in after if f.code in KINDS),
        "unrepaired": [{"code": f.code, "subject": f.subject, "why": why} for f, why in plan.unrepaired],
        "along": [{"code": f.code, "subject": f.subject, "how": how} for f, how in plan.along],
    }


def run_file(path: Path, settings: Settings) -> dict[str, Any]:
    """Analyse, then repair, ``path``; everything the benchmark reports about it."""
    t = time.perf_counter()
    plain = analyse_file(path, settings, legos_compat=True)
    analysis_s = time.perf_counter() - t
    t, cpu = time.perf_counter(), _cpu()
    rep = repair_file(path, settings, legos_compat=True, budget=Budget(workers=os.cpu_count() or 1))
    repair_s, repair_cpu_s = time.perf_counter() - t, _cpu() - cpu
    if rep.failed or plain.failed:
        raise ValueError(f"{path.name} does not check")
    if keys(plain.findings) != keys(rep.findings):
        print(
            f"repair_case_studies: {path.name}: repair and analysis report different findings",
            file=sys.stderr,
        )
    corrected = corrected_of(path)
    changes = None
    if corrected is not None:
        changes = expert_changes(rep.source, corrected.read_text(encoding="utf-8"), path.name)
    original = spec_of(rep.source, path.name)
    rows = [finding_row(r, original, changes) for r in rep.repairs]
    return {
        "file": path.name,
        "analysis_s": round(analysis_s, 3),
        "repair_s": round(repair_s, 3),
        "repair_cpu_s": round(repair_cpu_s, 3),
        # the findings' repairs summed: more than the wall time when they run side by side
        "findings_s": round(sum(r.seconds for r in rep.repairs), 3),
        "findings": [x for x in rows if x["code"] in KINDS],
        "other_findings": [x for x in rows if x["code"] not in KINDS],
        "undecided": len(rep.unknown),
        "set": set_row(rep, settings),
        "expert_changed": None if changes is None else sorted(changes.rules),
    }


# ------------------------------------------------------------------------------ summary


def ratio(part: int, whole: int) -> float | None:
    return round(part / whole, 3) if whole else None


def unrepaired_of(files: list[dict[str, Any]]) -> tuple[list[dict[str, str]], dict[str, list[str]]]:
    """Every finding of the four kinds without a verified fix, and them grouped by reason."""
    flat = [
        {"file": f["file"], "code": x["code"], "subject": x["subject"], "why": x["why"]}
        for f in files
        for x in f["findings"]
        if not x["repaired"]
    ]
    grouped: dict[str, list[str]] = defaultdict(list)
    for u in flat:
        grouped[reason_kind(u["why"])].append(f"{u['file'].split('__')[2]}: {u['code']} {u['subject']}")
    return flat, dict(sorted(grouped.items(), key=lambda kv: (-len(kv[1]), kv[0])))


def summary(files: list[dict[str, Any]]) -> dict[str, Any]:
    """The figures over all files, with the targets and whether they are met."""
    found = [x for f in files for x in f["findings"]]
    seconds = [x["seconds"] for x in found]
    repaired = sum(1 for x in found if x["repaired"])
    tops = [x["top"] for x in found if x["top"] is not None and x["top"]["agrees"] is not None]
    agree = sum(1 for t in tops if t["agrees"])
    analysis = sum(f["analysis_s"] for f in files)
    total = sum(f["repair_s"] for f in files)
    flat, grouped = unrepaired_of(files)
    s = {
        "findings": len(found),
        "findings_by_kind": dict(Counter(x["code"] for x in found)),
        "repaired": repaired,
        "repaired_percent": round(100 * repaired / len(found), 1) if found else None,
        "median_s_per_finding": round(statistics.median(seconds), 3) if seconds else None,
        "mean_s_per_finding": round(statistics.fmean(seconds), 3) if seconds else None,
        "worst_s_per_finding": round(max(seconds), 3) if seconds else None,
        "total_s": round(total, 3),
        "total_cpu_s": round(sum(f.get("repair_cpu_s", 0.0) for f in files), 3),
        "analysis_s": round(analysis, 3),
        "repair_over_analysis": round(total / analysis, 1) if analysis else None,
        "sets_verified": sum(1 for f in files if f["set"]["verified"] is True),
        "sets_empty": sum(1 for f in files if f["set"]["verified"] is None),
        "sets_refused": sum(1 for f in files if f["set"]["verified"] is False),
        "new_findings_with_sets": sum(len(f["set"]["new_findings"]) for f in files),
        "left_by_sets": sum(len(f["set"]["left_of_kinds"]) for f in files),
        "expert_agreement": ratio(agree, len(tops)),
        "expert_agreement_counts": {"agree": agree, "top_fixes": len(tops)},
        "top_operators": dict(Counter(x["top"]["operator"] for x in found if x["top"] is not None)),
        "other_findings": sum(len(f["other_findings"]) for f in files),
        "other_repaired": sum(1 for f in files for x in f["other_findings"] if x["repaired"]),
        "unrepaired": flat,
        "unrepaired_by_reason": grouped,
        "rejections_by_operator": rejections(found),
    }
    s["meets_targets"] = meets(s)
    return s


def rejections(found: list[dict[str, Any]]) -> dict[str, dict[str, int]]:
    """For the findings left unrepaired: per operator, how often each kind of reason
    (:func:`reason_kind`) refused one of its candidates (every reason, not only the first)."""
    out: dict[str, Counter[str]] = defaultdict(Counter)
    for x in found:
        for c in x.get("candidates_rejected", []):
            for why in c["reasons"]:
                out[c["operator"]][
                    reason_kind(f"1 candidate, none verified: {why}")[len("none verified: ") :]
                ] += 1
    return {op: dict(c.most_common()) for op, c in sorted(out.items())}


def meets(s: dict[str, Any]) -> bool:
    """Whether the summary ``s`` meets issue 30's targets (a set the engine refused fails)."""
    percent, median, worst = s["repaired_percent"], s["median_s_per_finding"], s["worst_s_per_finding"]
    return (
        percent is not None
        and percent >= REPAIRED_TARGET
        and median <= MEDIAN_TARGET
        and worst <= WORST_TARGET
        and s["new_findings_with_sets"] == 0
        and s["sets_refused"] == 0
    )


def rows_of(s: dict[str, Any], files: list[dict[str, Any]]) -> list[tuple[str, str, str]]:
    """The printed table."""
    sp = SLEEC_PATCH
    rows = [
        (
            "findings repaired (4 kinds)",
            f"{s['repaired']}/{s['findings']} ({s['repaired_percent']} %)",
            f"target >= {REPAIRED_TARGET:g} %; SLEEC-PATCH {sp['repaired_percent']:g} % with an LLM",
        ),
        (
            "per finding, median",
            f"{s['median_s_per_finding']} s",
            f"target <= {MEDIAN_TARGET:g} s; SLEEC-PATCH {sp['median_s']} s",
        ),
        (
            "per finding, worst",
            f"{s['worst_s_per_finding']} s",
            f"target <= {WORST_TARGET:g} s; SLEEC-PATCH {sp['worst_s']:g} s",
        ),
        (
            "total (analysis, fixes, sets)",
            f"{s['total_s']:.1f} s",
            f"{s['repair_over_analysis']}x the analysis; {s['total_cpu_s']:.0f} s of CPU",
        ),
        ("plain analysis, same files", f"{s['analysis_s']:.2f} s", "baseline, same run"),
        (
            "sets applied together",
            f"{s['sets_verified']} verified, {s['sets_empty']} empty, {s['sets_refused']} refused",
            f"{s['new_findings_with_sets']} new findings (target 0); {s['left_by_sets']} left",
        ),
        (
            "top fix agrees with the experts",
            f"{s['expert_agreement_counts']['agree']}/{s['expert_agreement_counts']['top_fixes']}",
            "a rule the corrected file changes",
        ),
        (
            "other findings repaired",
            f"{s['other_repaired']}/{s['other_findings']}",
            "dead rules, clauses, ...",
        ),
    ]
    for f in files:
        n = len(f["findings"])
        ok = sum(1 for x in f["findings"] if x["repaired"])
        worst = max((x["seconds"] for x in f["findings"]), default=0.0)
        rows.append(
            (
                f["file"].split("__")[2],
                f"{ok}/{n} in {f['repair_s']:.1f} s",
                f"worst {worst:.1f} s; set: {f['set']['fixes']} fixes, {len(f['set']['new_findings'])} new",
            )
        )
    return rows


def main() -> int:
    a = args(__doc__ or "")
    studies = QUICK if a.quick else STUDIES
    files = initial_files(studies)
    if len(files) != len(studies):
        print(
            f"repair_case_studies: expected {len(studies)} initial files in {CORPUS}, found {len(files)}",
            file=sys.stderr,
        )
        return 2
    settings = Settings()
    per_file = [run_file(f, settings) for f in files]
    s = summary(per_file)
    result: dict[str, Any] = {
        "benchmark": "repair_case_studies",
        "quick": a.quick,
        "files": [f.name for f in files],
        **s,
        "targets": {
            "repaired_percent": f">= {REPAIRED_TARGET:g}",
            "median_s_per_finding": f"<= {MEDIAN_TARGET:g}",
            "worst_s_per_finding": f"<= {WORST_TARGET:g}",
            "new_findings_with_sets": "== 0",
        },
        "sleec_patch": SLEEC_PATCH,
        "bound": settings.bound,
        "per_file": per_file,
    }
    title = (
        f"cosleec analyse --fix: N-Check's {'three (--quick)' if a.quick else 'nine'} initial case studies"
    )
    report(title, rows_of(s, per_file), result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
