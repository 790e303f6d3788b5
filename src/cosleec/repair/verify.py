"""Whether a patched file is a repair: SLEEC-PATCH's meaning of "verified", proved.

A patched text is verified for a set of findings when

1. it parses and checks (no error);
2. its declarations, concerns, purposes and relations are those of the original (a repair
   changes rules and priorities, never what the rules are judged against);
3. the analysis, run whole on it with the same settings, no longer reports any of the
   findings it was meant to repair, and the solver settled each of their questions;
4. it reports no finding that the original did not (same code, same subject).

"No longer reported" is as strong as the analysis: proved, or up to the bound it states
(:attr:`Verdict.bound`), never "likely".
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cosleec.analysis import Coverage, Deadline, Finding, Settings, analyse_spec
from cosleec.lang import CheckResult, analyse
from cosleec.lang import ast as A

Key = tuple[str, str]
"""A finding as verification compares it: its code and its subject."""


def key(f: Finding) -> Key:
    """``f``'s identity across two versions of a file."""
    return f.code, f.subject


@dataclass(frozen=True)
class Reading:
    """How a file is read and analysed: the same for the original and every patched text."""

    path: str
    settings: Settings
    legos_compat: bool = False
    infer_defs: bool = False
    coverage: Coverage | None = None

    def check(self, text: str) -> CheckResult:
        """Parse and check ``text`` as the file."""
        return analyse(text, self.path, legos_compat=self.legos_compat, infer_defs=self.infer_defs)

    def analyse(
        self, result: CheckResult, deadline: Deadline | None = None
    ) -> tuple[list[Finding], list[str], dict[str, list[str] | None]]:
        """The findings of a checked text, what the solver did not settle, and what
        ``deadline`` left undecided (as :attr:`~cosleec.analysis.FileReport.undecided`)."""
        assert result.spec is not None and result.symbols is not None
        left: dict[str, list[str] | None] = {}
        found, unknown = analyse_spec(
            result.spec,
            dict(result.symbols.constant_values),
            self.settings,
            coverage=self.coverage,
            deadline=deadline,
            undecided=left,
        )
        return found, unknown, left


@dataclass(frozen=True)
class Verdict:
    """What verification found: ``verified``, or the reasons it is not; the findings the
    patched text reports (``after``) and what its analysis left unsettled."""

    verified: bool
    reasons: tuple[str, ...] = ()
    repaired: tuple[Key, ...] = ()
    new: tuple[Key, ...] = ()
    bound: int | None = None
    after: tuple[Finding, ...] = field(default=(), repr=False)
    unknown: tuple[str, ...] = field(default=(), repr=False)
    checked: CheckResult | None = field(default=None, repr=False, compare=False)

    @property
    def proof(self) -> str:
        """``proved``, or ``up to bound N`` when a repaired finding's absence holds only up to
        the analysis' bound."""
        return "proved" if self.bound is None else f"up to bound {self.bound}"


def verify(
    reading: Reading,
    before: A.Specification,
    found: list[Finding],
    text: str,
    targets: list[Key],
    deadline: Deadline | None = None,
) -> Verdict:
    """Whether ``text`` repairs ``targets`` (findings of the original, ``found``) and breaks
    nothing the analysis can see; once ``deadline`` passes, not verified (a partial analysis
    cannot say "no new finding")."""
    result = reading.check(text)
    if not result.ok or result.spec is None:
        first = result.errors[0] if result.errors else None
        said = f"{first.span}: {first.message}" if first is not None else "it does not parse"
        return Verdict(False, (f"the patched file does not check: {said}",), checked=result)
    changed = untouched(before, result.spec)
    if changed:
        return Verdict(False, (f"it changes the {', '.join(changed)}",), checked=result)
    after, unknown, left = reading.analyse(result, deadline)
    if left:  # a partial analysis proves nothing about what it did not reach
        return Verdict(False, (f"the deadline passed during verification ({', '.join(left)} not decided)",))
    now = {key(f) for f in after}
    was = {key(f) for f in found}
    reasons = [f"{code} {subject} is still reported" for code, subject in targets if (code, subject) in now]
    new = sorted(now - was)
    reasons += [f"new finding: {code} {subject}" for code, subject in new]
    about = [u for u in unknown if any(_about(u, t) for t in targets)]
    bounds = [_bound(u) for u in about]
    reasons += [f"not settled: {u}" for u, b in zip(about, bounds, strict=True) if b is None]
    known = [b for b in bounds if b is not None]
    return Verdict(
        not reasons,
        tuple(reasons),
        repaired=tuple(t for t in targets if t not in now),
        new=tuple(new),
        bound=_bound_of(reading.settings, targets, known),
        after=tuple(after),
        unknown=tuple(unknown),
        checked=result,
    )


def untouched(before: A.Specification, after: A.Specification) -> list[str]:
    """What a repair may not change and this one does: declarations, concerns, purposes,
    relations (ASTs compare by meaning, not by position)."""
    parts = (
        ("declarations", before.definitions, after.definitions),
        ("concerns", before.concerns, after.concerns),
        ("purposes", before.purposes, after.purposes),
        ("relations", before.relations, after.relations),
    )
    return [name for name, a, b in parts if a != b]


REPAIRED_BY_UNSAT = frozenset({"concern-raised", "semantics-differ", "negative-deadline", "runtime-conflict"})
"""Findings that go when a question becomes unsatisfiable ("no trace shows it"): their
absence holds up to the analysis' bound (the others go when a trace is found: a proof)."""


def _bound_of(settings: Settings, targets: list[Key], known: list[int]) -> int | None:
    """The bound up to which the repaired findings' absence holds (None: proved)."""
    if known:
        return min(known)
    return settings.bound if any(code in REPAIRED_BY_UNSAT for code, _ in targets) else None


def _bound(note: str) -> int | None:
    """The bound an "answered up to bound N only" note gives (None: any other note)."""
    _, found, tail = note.partition("up to bound ")
    digits = tail.split(" ", 1)[0]
    return int(digits) if found and digits.isdigit() else None


def _about(note: str, target: Key) -> bool:
    """Whether an unsettled question (a line of ``FileReport.unknown``) is the one behind
    ``target``: it names the subject as a word."""
    subject = target[1]
    words = note.replace(":", " ").replace(",", " ").split()
    return subject in words


__all__ = ["Key", "Reading", "Verdict", "key", "untouched", "verify"]
