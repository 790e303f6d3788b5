"""The verified repairs of the on-save analysis, as the editor offers them: quick fixes.

The repair engine (:mod:`cosleec.repair`) runs in the on-save process (onsave.py); what
crosses back to the server is only what a code action needs, in plain picklable records:
per finding (its diagnostic, as the editor shows it) its ranked fixes -- operator, summary,
the edits as character offsets into the analysed text, not the patched file, which can be
large -- and the patch set that verifies applied together. The offsets hold for that text only, so :class:`Repaired` keeps it, and
the server offers nothing once the document's text is another.

:func:`text_edits` turns a fix's edits into LSP ``TextEdit``\\s that give exactly the
patched text when a client applies them as LSP says (the order of two insertions at one
place is the array's order).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from lsprotocol import types as T

from cosleec.lang import Diagnostic
from cosleec.lsp.positions import LineIndex
from cosleec.repair import Edit, Fix, PatchSet, RepairReport


@dataclass(frozen=True, slots=True)
class Offer:
    """One verified fix as a code action offers it (``rank`` 0: the patch set)."""

    rank: int
    operator: str
    summary: str
    edits: tuple[Edit, ...]  # character offsets into the analysed text

    @classmethod
    def of(cls, fix: Fix) -> Offer:
        """The offer of a ranked fix."""
        p = fix.patch
        return cls(fix.rank, p.operator, p.summary, p.edits)

    @classmethod
    def of_set(cls, plan: PatchSet) -> Offer:
        """The offer of a patch set (every fix in it, applied together)."""
        p = plan.patch
        return cls(0, p.operator, p.summary, p.edits)

    @property
    def title(self) -> str:
        """The code action's title: ``Fix (rank 1, remove-rule): remove R2 (implied by R1)``."""
        return f"Fix (rank {self.rank}, {self.operator}): {self.summary}"


@dataclass(frozen=True, slots=True)
class Repaired:
    """The repairs of one analysed ``text``: per finding's diagnostic its offers (best
    first; findings without a verified fix are left out), and the patch set, if any."""

    text: str
    fixes: tuple[tuple[Diagnostic, tuple[Offer, ...]], ...] = ()
    together: Offer | None = None


def repaired(report: RepairReport) -> Repaired:
    """What the editor is offered from a repair report (made in the on-save process)."""
    fixes = tuple(
        (r.finding.diagnostic(), tuple(Offer.of(f) for f in r.fixes)) for r in report.repairs if r.fixes
    )
    plan = report.plan
    together = Offer.of_set(plan) if plan is not None and plan.fixes else None
    return Repaired(report.source, fixes, together)


def text_edits(lines: LineIndex, edits: Sequence[Edit]) -> list[T.TextEdit]:
    """LSP edits that turn ``lines.text`` into what :meth:`cosleec.repair.Patch.apply` makes.

    ``Patch.apply`` applies edits last offset first, and two insertions at one offset in
    list order, so the second lands before the first; LSP puts insertions at one place in
    array order. Hence: file order, with edits at one place in reverse.
    """
    applied = sorted(edits, key=lambda e: (e.start, e.end), reverse=True)
    return [T.TextEdit(range=lines.range(e.start, e.end), new_text=e.text) for e in reversed(applied)]
