"""N-Check's vacuous conflicts, and dead rules: a rule whose trigger can never occur while every
rule holds (``vacuous-conflict``), or whose trigger condition never holds at all, given the
measures' domains and the relations (``dead-rule``).

One question per rule: can its trigger occur, with its condition, in a trace that meets
every rule? A trace that says yes shows every rule it triggers possible too, so their own
questions are not asked.
"""

from __future__ import annotations

import functools
from typing import Any

import z3

from cosleec.analysis.encoding import Encoding
from cosleec.analysis.report import finding
from cosleec.analysis.session import Session, named
from cosleec.lang import Severity
from cosleec.lang import ast as A


def vacuous_conflicts(a: Session) -> None:
    """Rules whose trigger can never occur while every rule holds (a rule no rule is needed
    for is a dead rule)."""
    possible: set[str] = set()  # rules a trace already showed triggered with every rule met
    for rule in a.walk("vacuous-conflict", a.spec.rules, named):
        if rule.name in possible:
            continue
        asked = a.deepen(functools.partial(_fires, a, rule), None, f"vacuous conflict of {rule.name}")
        if asked is None:
            continue
        if asked[0] == z3.sat:
            # the model stays until the next one, as it always has (state.py: why it matters)
            enc, model = asked[1], asked[1].solver.model()
            possible.update(_triggered(enc, model))
            continue
        _, enc, goal, cands = asked
        _report(a, rule, enc, a.core(enc, goal, cands, f"vacuous conflict of {rule.name}"))


def _fires(a: Session, rule: A.Rule, bound: int) -> tuple[Encoding, Any]:
    """The shared encoding of ``rule``'s trigger at ``bound``, and a goal: it fires."""
    enc, x = a.encoding(rule.trigger.event, bound)
    goal = enc.fresh("goal")
    enc.solver.add(z3.Implies(goal, enc.fires(rule, x)))
    return enc, goal


def _triggered(enc: Encoding, model: Any) -> list[str]:
    """The rules the trace of ``model`` (of ``enc``, meeting every rule) triggers."""
    out: list[str] = []
    for s in enc.slots:
        if z3.is_true(model.eval(s.present, model_completion=True)):
            out.extend(
                r.name
                for r in enc.rules_by_event.get(s.event, ())
                if z3.is_true(model.eval(enc.fires(r, s), model_completion=True))
            )
    return out


def _report(a: Session, rule: A.Rule, enc: Encoding, core: tuple[str, ...]) -> None:
    """``rule`` cannot fire, because of ``core`` (minimal): a dead rule when only relations
    are needed, else a vacuous conflict (a declared priority that settles it is in the encoding)."""
    if all(n.startswith("relation ") for n in core):  # no rule needed: the condition never holds
        a.findings.append(
            finding(
                a.spec,
                "dead-rule",
                rule.name,
                f"rule {rule.name} can never fire: its trigger condition never holds"
                + (f" (given {', '.join(core)})" if core else ""),
                span=rule.trigger.condition.span if rule.trigger.condition is not None else rule.span,
                hint="correct the condition (a comparison the wrong way round, a constant, a literal of "
                "another scale), or remove the rule",
                cause=core,
                rules=(rule.name, *core),
            )
        )
        return
    others = [n for n in core if n != rule.name]
    cause = f"because of {', '.join(others)}" if others else "because of its own response"
    a.findings.append(
        finding(
            a.spec,
            "vacuous-conflict",
            rule.name,
            f"rule {rule.name} conflicts whenever it is triggered: `{rule.trigger.event}` "
            f"can never occur{' with its condition' if rule.trigger.condition else ''} without "
            f"breaking a rule, {cause}",
            span=rule.span,
            hint="weaken one of these rules (a deadline, an unless clause) or declare which prevails "
            "in a priority block",
            cause=core,
            itself=rule.name,
            decided_by=enc,
            severity=Severity.ERROR,
        )
    )


__all__ = ["vacuous_conflicts"]
