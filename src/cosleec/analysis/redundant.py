"""N-Check's redundancy: a rule the other rules already imply (``redundant``).

One question per rule: does some trace meet every other rule (and the relations) and break
this one? None means the others imply it, and the minimal set of them that does is named. A
dead rule, already reported, is not asked about.
"""

from __future__ import annotations

import functools
from typing import Any

import z3

from cosleec.analysis.encoding import Encoding
from cosleec.analysis.report import finding
from cosleec.analysis.session import Session, named
from cosleec.lang import ast as A


def redundancies(a: Session) -> None:
    """Rules the other rules already imply (a dead rule, already reported, is not repeated)."""
    dead = {f.subject for f in a.findings if f.code == "dead-rule"}
    for rule in a.walk("redundant", a.spec.rules, named):
        if rule.name in dead:
            continue
        asked = a.deepen(functools.partial(_broken, a, rule), rule.name, f"redundancy of {rule.name}")
        if asked is None or asked[0] != z3.unsat:
            continue
        _, enc, goal, cands = asked
        core = a.core(enc, goal, cands, f"redundancy of {rule.name}")
        why = (
            f"the other rules already imply it: {', '.join(core)}"
            if core
            else "it can never be broken (its trigger cannot occur with its condition, or its response "
            "always holds)"
        )
        a.findings.append(
            finding(
                a.spec,
                "redundant",
                rule.name,
                f"rule {rule.name} is redundant: {why}",
                span=rule.span,
                hint="remove the rule, or check that the rules it names say what was meant",
                cause=core,
                decided_by=enc,
            )
        )


def _broken(a: Session, rule: A.Rule, bound: int) -> tuple[Encoding, Any]:
    """The shared encoding of ``rule``'s trigger at ``bound``, and a goal: it fires and its
    response does not hold."""
    enc, x = a.encoding(rule.trigger.event, bound)
    goal = enc.fresh("broken")
    enc.solver.add(
        z3.Implies(goal, z3.And(enc.fires(rule, x), z3.Not(enc.obligations.holds(rule.response, x))))
    )
    return enc, goal


__all__ = ["redundancies"]
