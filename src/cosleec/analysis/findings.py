"""What ``cosleec analyse`` reports: findings, each with its proof status, rules and witness.

A finding is something a person can act on: a code, where it is in the file, the *minimal*
set of rules (and relations) involved, a witness trace when there is one, and whether it is
**proved** or holds only **up to bound N** (the unfolding of occurrences stopped at N per
event, :mod:`cosleec.analysis.encoding`). Never "likely".
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from cosleec.lang import Diagnostic, Severity
from cosleec.lang import ast as A
from cosleec.semantics import Step

PROVED = "proved"
BOUNDED = "bounded"
MORE = "..."
"""The last subject of a :attr:`FileReport.undecided` list that does not list them all."""

CHECKS: dict[str, str] = {
    "vacuous-conflict": "a rule whose trigger can never occur without some rule being broken (N-Check)",
    "dead-rule": "a rule whose trigger condition can never hold (given measure domains and relations)",
    "situational-conflict": "a legal situation after which a rule's trigger cannot be answered (N-Check)",
    "redundant": "a rule the other rules already imply (N-Check)",
    "concern-raised": "an undesirable situation (concern) the rules allow, with a witness (N-Check)",
    "purpose-blocked": "a desirable situation (purpose) the rules forbid, with the rules that block it (N-Check)",
    "unselectable-clause": "an unless clause that is never selected under the chosen semantics",
    "semantics-differ": "a rule where last-wins and nested choose different clauses, with the situation",
    "runtime-conflict": "rules that can owe an event and forbid it in overlapping windows, no priority settling it",
    "negative-deadline": "a deadline computed from measures that can become negative",
    "unimplemented-clause": "a clause whose response has no implementation (--tasks/--mapping)",
    "unproduced-input": "a measure or event the rules read that the mapping never produces (--mapping)",
}
"""Every check, by the code its findings carry, with what it finds."""


@dataclass(frozen=True)
class Witness:
    """A trace that shows a finding: the steps (a ``cosleec conforms`` trace) and the
    reference semantics' verdicts on it, as a readable timeline.

    ``confirmed`` says whether the reference semantics agrees with what the witness is
    meant to show (it always should: False is a bug to report).
    """

    steps: tuple[Step, ...]
    timeline: tuple[str, ...]
    confirmed: bool

    def jsonl(self) -> str:
        """The steps as a JSON Lines trace that ``cosleec conforms RULES FILE`` reads."""
        out = []
        for s in self.steps:
            d: dict[str, Any] = {"t": s.t}
            if s.values:
                d["set"] = dict(s.values)
            if s.event is not None:
                d["event"] = s.event
            out.append(json.dumps(d))
        return "\n".join(out) + "\n"


@dataclass(frozen=True)
class Finding:
    """One result of one check.

    ``rules`` is the minimal set of rules (and relations, ``relation N``) that causes it,
    in file order; ``subject`` the rule, clause, concern or purpose it is about; ``status``
    :data:`PROVED` or :data:`BOUNDED` (``bound`` then says up to what).
    """

    code: str
    subject: str
    message: str
    path: str
    span: A.Span = A.NO_SPAN
    rules: tuple[str, ...] = ()
    related: tuple[tuple[str, A.Span], ...] = ()
    hint: str = ""
    status: str = PROVED
    bound: int | None = None
    situation: str = ""
    witness: Witness | None = None
    severity: Severity = Severity.WARNING
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def proof(self) -> str:
        """``proved`` or ``up to bound N``, as printed."""
        return PROVED if self.status == PROVED else f"up to bound {self.bound}"

    def diagnostic(self) -> Diagnostic:
        """The finding as a compiler-style diagnostic (file:line:col, caret, notes, hint)."""
        return Diagnostic(
            severity=self.severity,
            code=self.code,
            message=f"{self.message} [{self.proof}]",
            span=self.span,
            path=self.path,
            hint=self.hint or None,
            related=self.related,
        )

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (``cosleec analyse --json``)."""
        return {
            "code": self.code,
            "subject": self.subject,
            "message": self.message,
            "severity": str(self.severity),
            "path": self.path,
            "line": self.span.line,
            "col": self.span.col,
            "end_line": self.span.end_line,
            "end_col": self.span.end_col,
            "rules": list(self.rules),
            "status": self.status,
            "bound": self.bound,
            "situation": self.situation or None,
            "hint": self.hint or None,
            "related": [{"note": n, "line": s.line, "col": s.col} for n, s in self.related],
            "witness": None
            if self.witness is None
            else {
                "trace": [json.loads(line) for line in self.witness.jsonl().splitlines()],
                "timeline": list(self.witness.timeline),
                "confirmed": self.witness.confirmed,
            },
            **self.extra,
        }


@dataclass
class FileReport:
    """The findings for one file, and what the analysis could not settle."""

    path: str
    source: str
    findings: list[Finding] = field(default_factory=list)
    # what the analysis did not settle: questions out of time (or answered up to a smaller
    # bound), a witness the reference did not confirm, and the encoding's known limit where
    # it could matter
    unknown: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)  # per check
    diagnostics: list[Diagnostic] = field(default_factory=list)  # the file's own (from check)
    # what the run's deadline (--deadline) left open: by check, the subjects not decided,
    # or None for a check that did not run (a file not even read: every check None)
    undecided: dict[str, list[str] | None] = field(default_factory=dict)

    @property
    def failed(self) -> bool:
        """The file could not be analysed (it has errors)."""
        return any(d.is_error for d in self.diagnostics)

    @property
    def complete(self) -> bool:
        """Every selected check ran to the end (False: the deadline cut the run short, and
        :attr:`undecided` says where)."""
        return not self.undecided
