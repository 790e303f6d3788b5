"""The checks over whole traces: conflicts, redundancy, concerns, purposes, runtime conflicts.

Each is one satisfiability question per rule (or concern, purpose, pair of clauses) over
the traces of :mod:`cosleec.analysis.encoding`, with N-Check's meanings
(``docs/reference/sleec-language.md`` §9 and docs/cli.md, "Analysing a rule set"):

vacuous conflict
    rule R's trigger (with its condition) can never occur in a trace that meets every rule.
situational conflict
    there is a situation -- an earlier occurrence that fires a rule, and the values R's
    trigger then reads -- in which R's trigger cannot occur without a rule being broken,
    although R is not vacuously conflicting. Candidates are the clauses whose obligation a
    prohibition of the same event can cover whole (the runtime conflicts); each candidate
    situation is fixed and then checked against every rule.
redundancy
    the other rules imply R: no trace meets them all and breaks R.
concern raised
    some trace meets every rule and shows the concern (the rules are too weak).
purpose blocked
    no trace that meets every rule shows the purpose (the rules are too strict); the
    minimal set of rules that blocks it is named.
runtime conflict
    two clauses (of one rule or two) can owe an event and forbid it in overlapping windows,
    and no declared priority orders their rules: the runtime will have to refuse one.

Relations (the LEGOS ``relation`` block) are assumptions about the world and hold in every
question; cores may name them.

Each family of checks is a module of functions of a :class:`~cosleec.analysis.session.Session`
(what every check shares): vacuous.py (vacuous conflicts and dead rules), redundant.py,
situations.py (concerns and purposes), runtime_conflicts.py and situational.py; clauses.py
has the checks over one snapshot. Every finding is built by :func:`cosleec.analysis.report.finding`.
:class:`Analysis` is a session with the entry point of each family over whole traces: the
steps run.py runs.
"""

from __future__ import annotations

from cosleec.analysis import redundant, runtime_conflicts, situations, vacuous
from cosleec.analysis.session import DEFAULT_BOUND, LISTED, Session, Settings
from cosleec.analysis.situational import situational_conflicts


class Analysis(Session):
    """The questions about one checked specification (a :class:`Session`), with the checks
    over whole traces; findings accumulate in ``findings``."""

    def vacuous_conflicts(self) -> None:
        """Rules whose trigger can never occur while every rule holds, and dead rules (vacuous.py)."""
        vacuous.vacuous_conflicts(self)

    def redundancies(self) -> None:
        """Rules the other rules already imply (redundant.py)."""
        redundant.redundancies(self)

    def situations(self, kind: str) -> None:
        """Concerns the rules allow (``concern``) and purposes they block (``purpose``) (situations.py)."""
        situations.situations(self, kind)

    def runtime_conflicts(self, situational: bool) -> None:
        """Clauses that can owe and forbid an event in overlapping windows (runtime_conflicts.py)
        and, with ``situational``, the situations where that leaves a trigger unanswerable
        (situational.py)."""
        runtime_conflicts.runtime_conflicts(self, situational_conflicts if situational else None)


__all__ = ["DEFAULT_BOUND", "LISTED", "Analysis", "Settings"]
