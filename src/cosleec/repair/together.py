"""A file's patch set: the best fixes that verify *applied together*.

Each fix is verified alone, against the original file; two of them can still undo each other
(for two rules that imply each other, each removal verifies alone, and applying both deletes
both rules) or overlap in the text. The set is built one finding at a time, in the
analysis' order: a finding the fixes chosen so far already repaired needs nothing more; else
its fixes are tried best first, each applied with the ones chosen so far and the whole
verified again -- every finding repaired so far still gone, no finding the original did not
have. What is left unrepaired is named, with why.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cosleec.analysis import Deadline, Finding
from cosleec.lang import ast as A
from cosleec.repair.fixes import Fix, Repairs
from cosleec.repair.patch import Patch, unified_diff
from cosleec.repair.verify import Key, Reading, Verdict, key, verify
from cosleec.repair.writing import joined


@dataclass
class PatchSet:
    """The fixes chosen for one file, the text with all of them applied, its diff and its
    verification; per finding left unrepaired, why; per finding repaired by a fix chosen
    for another, which."""

    fixes: list[Fix] = field(default_factory=list)
    text: str = ""
    diff: str = ""
    verdict: Verdict | None = None
    unrepaired: list[tuple[Finding, str]] = field(default_factory=list)
    along: list[tuple[Finding, str]] = field(default_factory=list)

    @property
    def patch(self) -> Patch:
        """All the chosen fixes' edits as one patch (they never overlap)."""
        edits = joined(tuple(e for f in self.fixes for e in f.patch.edits))
        rules = tuple(r for f in self.fixes for r in f.patch.rules)
        return Patch("set", "; ".join(f.patch.summary for f in self.fixes), rules, edits)


def together(
    source: str,
    spec: A.Specification,
    found: list[Finding],
    repairs: list[Repairs],
    reading: Reading,
    deadline: Deadline | None = None,
) -> PatchSet:
    """The patch set of a file whose findings are ``found``, with their ``repairs`` (once
    ``deadline`` passes, no further fix joins it)."""
    plan = PatchSet(text=source)
    repaired: list[Key] = []
    current: set[Key] = {key(f) for f in found}
    for r in repairs:
        k = key(r.finding)
        if k not in current:
            plan.along.append((r.finding, _by(plan, k)))
            repaired.append(k)
            continue
        chosen = _first_that_holds(source, spec, found, r, plan, [*repaired, k], reading, deadline)
        if chosen is None:
            plan.unrepaired.append(
                (r.finding, r.why_none or "no fix verifies with the fixes chosen before it")
            )
            continue
        fix, verdict = chosen
        plan.fixes.append(fix)
        plan.verdict = verdict
        plan.text = plan.patch.apply(source)
        current = {key(f) for f in verdict.after}
        repaired = [key(f) for f in found if key(f) not in current]  # side effects stay gone too
    settled = [(f, why) for f, why in plan.unrepaired if key(f) not in current]
    for f, _ in settled:  # a later fix repaired it after its own turn
        plan.unrepaired.remove((f, _))
        plan.along.append((f, _by(plan, key(f))))
    plan.diff = unified_diff(source, plan.text, reading.path)
    return plan


def _first_that_holds(
    source: str,
    spec: A.Specification,
    found: list[Finding],
    r: Repairs,
    plan: PatchSet,
    targets: list[Key],
    reading: Reading,
    deadline: Deadline | None,
) -> tuple[Fix, Verdict] | None:
    """The best fix of ``r`` that verifies with the fixes chosen so far."""
    for fix in r.fixes:
        if any(fix.patch.overlaps(other.patch) for other in plan.fixes):
            continue
        if not plan.fixes:
            return fix, fix.verdict
        edits = joined((*plan.patch.edits, *fix.patch.edits))
        text = Patch("set", "", (), edits).apply(source)
        verdict = verify(reading, spec, found, text, targets, deadline)
        if verdict.verified:
            return fix, verdict
    return None


def _by(plan: PatchSet, k: Key) -> str:
    """Which chosen fix made finding ``k`` go."""
    for fix in plan.fixes:
        if k in fix.verdict.repaired or k not in {key(f) for f in fix.verdict.after}:
            return f"repaired along with: {fix.patch.summary}"
    return "repaired along with the fixes chosen before it"


__all__ = ["PatchSet", "together"]
