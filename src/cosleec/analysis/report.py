"""One builder of findings: what every check's :class:`~cosleec.analysis.findings.Finding` has in
common, said once.

A check knows what it found: its code, its subject, the message, where it is and what to do
about it, and what caused it. :func:`finding` adds the rest the same way for every check: the
file; the rules of the cause (rules and relations, ``relation N``, in file order) with a note
pointing at each -- but at the subject itself, when it is part of its own cause; and whether
the finding is proved or holds up to a bound, from the encoding that decided it.
"""

from __future__ import annotations

from typing import Any

from cosleec.analysis.encoding import Encoding
from cosleec.analysis.findings import BOUNDED, PROVED, Finding, Witness
from cosleec.lang import Severity, Specification
from cosleec.lang import ast as A

Notes = tuple[tuple[str, A.Span], ...]


def finding(
    spec: Specification,
    code: str,
    subject: str,
    message: str,
    *,
    span: A.Span,
    hint: str,
    cause: tuple[str, ...] = (),
    itself: str = "",
    rules: tuple[str, ...] | None = None,
    related: Notes | None = None,
    decided_by: Encoding | None = None,
    severity: Severity = Severity.WARNING,
    situation: str = "",
    witness: Witness | None = None,
    extra: dict[str, Any] | None = None,
) -> Finding:
    """A finding of ``code`` about ``subject`` in ``spec``.

    ``cause``: the rules and relations that cause it, which the finding names (``rules``
    overrides that) and points at (``related`` overrides the notes; ``itself``, the subject's
    own name when it is part of its cause, gets none). ``decided_by``: the encoding whose
    "unsatisfiable" proved it -- proved if its unfolding completed, else up to its bound;
    None: proved outright (a witness, a satisfiable question, no bound involved).
    """
    proved = decided_by is None or decided_by.complete
    return Finding(
        code=code,
        subject=subject,
        message=message,
        path=spec.path,
        span=span,
        rules=cause if rules is None else rules,
        related=notes(spec, cause, itself) if related is None else related,
        hint=hint,
        status=PROVED if proved else BOUNDED,
        bound=None if proved or decided_by is None else decided_by.bound,
        situation=situation,
        witness=witness,
        severity=severity,
        extra={} if extra is None else extra,
    )


def notes(spec: Specification, names: tuple[str, ...], skip: str = "") -> Notes:
    """A note pointing at each named rule or relation of ``spec`` (but ``skip``)."""
    return tuple((f"{n} is part of the cause", span_of(spec, n)) for n in names if n != skip)


def span_of(spec: Specification, name: str) -> A.Span:
    """Where a rule or relation of ``spec`` is (relations are ``relation N``)."""
    if name.startswith("relation "):
        return spec.relations[int(name.split()[1]) - 1].span
    for r in spec.rules:
        if r.name == name:
            return r.span
    return A.NO_SPAN


__all__ = ["Notes", "finding", "notes", "span_of"]
