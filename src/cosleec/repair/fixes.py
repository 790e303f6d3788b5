"""A finding's verified repairs, ranked: what ``cosleec analyse --fix`` shows under it.

A :class:`Fix` is a patch that verification accepted, with the whole patched text, its
unified diff and what else it changes in the robot's behaviour. Fixes are ranked by that
change: a patch that changes behaviour only where the finding lives comes first, then the
one that changes fewest situations, then the smallest edit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from cosleec.analysis import Finding
from cosleec.repair.behaviour import BehaviourChange
from cosleec.repair.patch import Patch
from cosleec.repair.verify import Verdict

UNCOUNTED = 1 << 30
"""The rank weight of a behaviour change the solver could not count (after every counted one)."""


@dataclass(frozen=True)
class Fix:
    """One verified repair of one finding (``rank`` 1 is the best)."""

    patch: Patch
    text: str
    diff: str
    verdict: Verdict
    behaviour: BehaviourChange | None = None
    rank: int = 0

    def order(self) -> tuple[int, int, int]:
        """The ranking key: situations changed outside the finding, all situations changed,
        the size of the edit (smaller first)."""
        b = self.behaviour
        if b is None or not b.computed:
            return UNCOUNTED, UNCOUNTED, self.patch.size
        return b.outside, b.situations, self.patch.size

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (``cosleec analyse --fix --json``, a finding's ``fixes``)."""
        b = self.behaviour
        return {
            "rank": self.rank,
            "operator": self.patch.operator,
            "summary": self.patch.summary,
            "rules": list(self.patch.rules),
            "diff": self.diff,
            "text": self.text,
            "verified": self.verdict.verified,
            "proof": self.verdict.proof,
            "behaviour": None
            if b is None
            else {
                "computed": b.computed,
                "situations": b.situations,
                "outside": b.outside,
                "exact": b.exact,
                "scenarios": list(b.scenarios),
                "reason": b.reason or None,
            },
        }


def ranked(fixes: list[Fix]) -> list[Fix]:
    """``fixes`` best first, numbered from 1."""
    ordered = sorted(fixes, key=Fix.order)
    return [Fix(f.patch, f.text, f.diff, f.verdict, f.behaviour, rank=i) for i, f in enumerate(ordered, 1)]


@dataclass
class Repairs:
    """What repair found for one finding: its verified fixes (ranked), the candidates that
    failed verification with why, and the time it took."""

    finding: Finding
    fixes: list[Fix] = field(default_factory=list)
    rejected: list[tuple[Patch, tuple[str, ...]]] = field(default_factory=list)
    seconds: float = 0.0
    skipped: str = ""  # why it was not tried at all (the run's deadline)
    cannot: str = ""  # why no rule edit can repair it (the finding's own form)

    @property
    def why_none(self) -> str:
        """Why there is no fix (empty when there is one)."""
        if self.fixes:
            return ""
        if self.skipped or self.cannot:
            return self.skipped or self.cannot
        if not self.rejected:
            return f"no repair operator applies to a {self.finding.code} finding of this form"
        reasons = sorted({r for _, rs in self.rejected for r in rs[:1]})
        return f"{len(self.rejected)} candidates, none verified: " + "; ".join(reasons[:3])

    def to_json(self) -> list[dict[str, Any]]:
        """The fixes as JSON."""
        return [f.to_json() for f in self.fixes]


__all__ = ["UNCOUNTED", "Fix", "Repairs", "ranked"]
