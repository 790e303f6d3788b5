"""Running the checks on a file: which checks, in which order, with what they need.

:func:`analyse_file` reads and checks the file (``legos_compat`` reads the LEGOS case studies
as LEGOS does), then runs each selected check and times it; a file with errors is reported
with its diagnostics and not analysed.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from cosleec.analysis import clauses
from cosleec.analysis.checks import Analysis, Settings
from cosleec.analysis.findings import CHECKS, PROVED, FileReport, Finding
from cosleec.lang import Severity, Specification, visit
from cosleec.lang import analyse_file as check_file
from cosleec.lang import ast as A

WITNESSED = frozenset({"concern-raised", "unselectable-clause", "semantics-differ", "negative-deadline"})
"""Checks whose findings show a trace or values: each runs in a z3 context of its own, so that
what it shows does not depend on which other checks ran (those without witnesses share the
per-event encodings, which is faster; their causes do not depend on the solver's state)."""


@dataclass(frozen=True)
class Coverage:
    """What the robot's side provides, for the coverage checks (None: not given).

    ``unimplemented``: the completeness check's messages for clauses without an
    implementation (``R1.1: ...``, from ``--tasks``); ``measures`` and ``events``: what the
    Context Listener mapping produces (``--mapping``).
    """

    unimplemented: tuple[str, ...] | None = None
    measures: frozenset[str] | None = None
    events: frozenset[str] | None = None


def analyse_spec(
    spec: Specification,
    constants: dict[str, int],
    settings: Settings,
    checks: Iterable[str] = CHECKS,
    coverage: Coverage | None = None,
    seconds: dict[str, float] | None = None,
) -> tuple[list[Finding], list[str]]:
    """The findings of ``checks`` on a checked ``spec`` (in a stable order), and the questions
    the solver could not settle."""
    wanted = set(checks)
    a = Analysis(spec, constants, settings)
    times = seconds if seconds is not None else {}
    steps: list[tuple[str, Callable[[], None]]] = [
        ("vacuous-conflict", a.vacuous_conflicts),
        ("redundant", a.redundancies),
        ("concern-raised", lambda: a.situations("concern")),
        ("purpose-blocked", lambda: a.situations("purpose")),
        ("unselectable-clause", lambda: clauses.unselectable(a)),
        ("semantics-differ", lambda: clauses.semantics_differ(a)),
        ("negative-deadline", lambda: clauses.negative_deadlines(a)),
    ]
    for code, step in steps:
        if code in wanted or (code == "vacuous-conflict" and "dead-rule" in wanted):
            if code in WITNESSED:  # a check that shows traces or values starts afresh
                a.fresh_context()
            _timed(step, times, code)
    if wanted & {"runtime-conflict", "situational-conflict"}:
        a.fresh_context()
        _timed(lambda: a.runtime_conflicts("situational-conflict" in wanted), times, "runtime-conflict")
        times["runtime-conflict"] -= a.situational_seconds
        times["situational-conflict"] = times.get("situational-conflict", 0.0) + a.situational_seconds
    if coverage is not None and wanted & {"unimplemented-clause", "unproduced-input"}:
        _timed(lambda: a.findings.extend(_coverage(spec, coverage, wanted)), times, "coverage")
    order = {c: i for i, c in enumerate(CHECKS)}
    kept = [f for f in a.findings if f.code in wanted]  # a question can answer several checks
    for f in [f for f in kept if f.witness is not None and not f.witness.confirmed]:
        # the independent oracle disagrees with the encoding: never shown as proved
        kept.remove(f)
        a.unknown.append(
            f"{f.code} {f.subject}: the analysis found a witness that the reference semantics does "
            "not confirm, so it is not reported (please report this, with the rule file)"
        )
    findings = sorted(kept, key=lambda f: (f.span.line, f.span.col, order.get(f.code, 99), f.subject))
    return findings, a.unknown


def analyse_file(
    path: str | Path,
    settings: Settings,
    checks: Iterable[str] = CHECKS,
    *,
    legos_compat: bool = False,
    infer_defs: bool = False,
    coverage: Coverage | None = None,
) -> FileReport:
    """Check, then analyse, one rule file."""
    t0 = time.perf_counter()
    result = check_file(path, legos_compat=legos_compat, infer_defs=infer_defs)
    report = FileReport(path=str(path), source=result.source, diagnostics=list(result.diagnostics))
    if not result.ok or result.spec is None or result.symbols is None:
        return report
    report.findings, report.unknown = analyse_spec(
        result.spec, dict(result.symbols.constant_values), settings, checks, coverage, report.seconds
    )
    report.seconds["total"] = time.perf_counter() - t0
    return report


def _timed(fn: Callable[[], None], seconds: dict[str, float], key: str) -> None:
    t0 = time.perf_counter()
    fn()
    seconds[key] = seconds.get(key, 0.0) + time.perf_counter() - t0


def _coverage(spec: Specification, cov: Coverage, wanted: set[str]) -> list[Finding]:
    out: list[Finding] = []
    rules = {r.name: r for r in spec.rules}
    if cov.unimplemented is not None and "unimplemented-clause" in wanted:
        for msg in cov.unimplemented:
            head = msg.split(":", 1)[0]
            rule = rules.get(head.split(".", 1)[0])
            span = rule.span if rule is not None else A.NO_SPAN
            if rule is not None and "." in head:
                k = head.split(".", 1)[1]
                if k.isdigit() and 0 < int(k) <= len(rule.response.defeaters):
                    span = rule.response.defeaters[int(k) - 1].span
            out.append(
                Finding(
                    code="unimplemented-clause",
                    subject=head,
                    message=msg,
                    path=spec.path,
                    span=span,
                    rules=(rule.name,) if rule is not None else (),
                    hint="bind a task with this clause's @hedge implementation, or a capability for the event",
                    status=PROVED,
                    severity=Severity.ERROR,
                )
            )
    if "unproduced-input" not in wanted:
        return out
    if cov.events is not None:
        # an event some response owes is the robot's own action, produced by its tasks
        produced = {o.event for r in spec.rules for o in visit.occurrences(r.response) if not o.negated}
        seen: set[str] = set()
        for r in spec.rules:
            e = r.trigger.event
            if e not in cov.events and e not in produced and e not in seen:
                seen.add(e)
                out.append(_unproduced("event", e, r, spec.path, r.trigger.span))
    if cov.measures is not None:
        seen = set()
        for r in spec.rules:
            for m, span in _measures_read(r, {d.name for d in spec.measures}):
                if m not in cov.measures and m not in seen:
                    seen.add(m)
                    out.append(_unproduced("measure", m, r, spec.path, span))
    return out


def _unproduced(kind: str, name: str, rule: A.Rule, path: str, span: A.Span) -> Finding:
    return Finding(
        code="unproduced-input",
        subject=name,
        message=f"{kind} `{name}` is read by {rule.name} but the mapping never produces it: "
        + ("the rule can never fire" if kind == "event" else "its value stays unknown (fail closed)"),
        path=path,
        span=span,
        rules=(rule.name,),
        hint=f"add `{name}` to the mapping's `{kind}s` section with its topic and type",
        status=PROVED,
        severity=Severity.WARNING,
    )


def _measures_read(rule: A.Rule, measures: set[str]) -> list[tuple[str, A.Span]]:
    """The measures ``rule`` reads, each where it is read."""
    return [
        (n.name, n.span) for e in visit.rule_expressions(rule) for n in visit.names(e) if n.name in measures
    ]


__all__ = ["PROVED", "Coverage", "analyse_file", "analyse_spec"]
