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
from cosleec.analysis.deadline import Deadline, OutOfTime
from cosleec.analysis.findings import CHECKS, PROVED, FileReport, Finding
from cosleec.lang import Severity, Specification, deeply, visit
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
    *,
    deadline: Deadline | None = None,
    undecided: dict[str, list[str] | None] | None = None,
) -> tuple[list[Finding], list[str]]:
    """The findings of ``checks`` on a checked ``spec`` (in a stable order), and the questions
    the solver could not settle.

    Once ``deadline`` passes, the check under way stops and the later ones do not run; what
    they leave open is put in ``undecided``: by check, the subjects (rules, clauses, pairs,
    situations) not decided, or None for a check that did not run at all. The findings made
    before are kept: each is as proved as it would have been.
    """
    wanted = set(checks)

    def attempt() -> tuple[list[Finding], list[str], dict[str, float], dict[str, list[str] | None]]:
        times: dict[str, float] = {}
        left: dict[str, list[str] | None] = {}
        findings, unknown = _analyse(spec, constants, settings, wanted, coverage, times, left, deadline)
        return findings, unknown, times, left

    # the encoding recurses once per level of an expression (but along an and/or chain), as
    # the checker's passes do: an expression `cosleec check` accepts is analysed in a deep thread
    findings, unknown, times, left = deeply(attempt)
    if seconds is not None:
        seconds.update(times)
    if undecided is not None:
        undecided.update(left)
    return findings, unknown


def _analyse(
    spec: Specification,
    constants: dict[str, int],
    settings: Settings,
    wanted: set[str],
    coverage: Coverage | None,
    times: dict[str, float],
    left: dict[str, list[str] | None],
    deadline: Deadline | None,
) -> tuple[list[Finding], list[str]]:
    """:func:`analyse_spec`, once."""
    a = Analysis(spec, constants, settings, deadline=deadline)
    plan = [(code, step) for code, step in _steps(a, wanted) if wanted & ANSWERS[code]]
    for n, (code, step) in enumerate(plan):
        try:
            if code in WITNESSED or code == "runtime-conflict":  # a check that shows traces starts afresh
                a.fresh_context()
            _timed(step, times, code)
        except OutOfTime:
            stopped = a.not_decided()
            for answered in _in_order(wanted & ANSWERS[code]):
                left[answered] = stopped[1] if stopped is not None else None
            for later, _ in plan[n + 1 :]:
                left.update(dict.fromkeys(_in_order(wanted & ANSWERS[later])))
            break
    if "runtime-conflict" in times:
        times["runtime-conflict"] -= a.situational_seconds
        times["situational-conflict"] = times.get("situational-conflict", 0.0) + a.situational_seconds
    if coverage is not None and wanted & {"unimplemented-clause", "unproduced-input"}:  # no solver: always
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


ANSWERS: dict[str, frozenset[str]] = {
    "vacuous-conflict": frozenset({"vacuous-conflict", "dead-rule"}),
    "redundant": frozenset({"redundant"}),
    "concern-raised": frozenset({"concern-raised"}),
    "purpose-blocked": frozenset({"purpose-blocked"}),
    "unselectable-clause": frozenset({"unselectable-clause"}),
    "semantics-differ": frozenset({"semantics-differ"}),
    "negative-deadline": frozenset({"negative-deadline"}),
    "runtime-conflict": frozenset({"runtime-conflict", "situational-conflict"}),
}
"""The checks each step of the analysis answers (the vacuous-conflict questions find dead
rules too; the runtime conflicts are where situational conflicts are looked for)."""


def _steps(a: Analysis, wanted: set[str]) -> list[tuple[str, Callable[[], None]]]:
    """Every step of the analysis, in the order they run (see :data:`ANSWERS`)."""
    return [
        ("vacuous-conflict", a.vacuous_conflicts),
        ("redundant", a.redundancies),
        ("concern-raised", lambda: a.situations("concern")),
        ("purpose-blocked", lambda: a.situations("purpose")),
        ("unselectable-clause", lambda: clauses.unselectable(a)),
        ("semantics-differ", lambda: clauses.semantics_differ(a)),
        ("negative-deadline", lambda: clauses.negative_deadlines(a)),
        ("runtime-conflict", lambda: a.runtime_conflicts("situational-conflict" in wanted)),
    ]


def analyse_file(
    path: str | Path,
    settings: Settings,
    checks: Iterable[str] = CHECKS,
    *,
    legos_compat: bool = False,
    infer_defs: bool = False,
    coverage: Coverage | None = None,
    deadline: Deadline | None = None,
) -> FileReport:
    """Check, then analyse, one rule file; once ``deadline`` passes, the report is partial
    (:attr:`FileReport.undecided` names what is left), and a file whose turn comes after it
    is not even read."""
    t0 = time.perf_counter()
    wanted = list(checks)
    if deadline is not None and deadline.passed():
        return FileReport(path=str(path), source="", undecided=dict.fromkeys(_in_order(set(wanted))))
    result = check_file(path, legos_compat=legos_compat, infer_defs=infer_defs)
    report = FileReport(path=str(path), source=result.source, diagnostics=list(result.diagnostics))
    if not result.ok or result.spec is None or result.symbols is None:
        return report
    report.findings, report.unknown = analyse_spec(
        result.spec,
        dict(result.symbols.constant_values),
        settings,
        wanted,
        coverage,
        report.seconds,
        deadline=deadline,
        undecided=report.undecided,
    )
    report.seconds["total"] = time.perf_counter() - t0
    return report


def _in_order(codes: set[str]) -> list[str]:
    return [c for c in CHECKS if c in codes]


def _timed(fn: Callable[[], None], seconds: dict[str, float], key: str) -> None:
    t0 = time.perf_counter()
    try:
        fn()
    finally:  # a step the deadline stopped took its time too
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
