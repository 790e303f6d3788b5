"""N-Check's concerns and purposes: an undesirable situation the rules allow
(``concern-raised``, with a witness) and a desirable one they forbid (``purpose-blocked``, with
the minimal set of rules that blocks it).

A situation is a trigger with its condition and the responses that then occur, and a
``meanwhile`` situation under it; one question per concern or purpose: can it occur in a trace
that meets every rule (and the relations)?
"""

from __future__ import annotations

import functools
from typing import Any

import z3

from cosleec.analysis.encoding import Encoding, Slot
from cosleec.analysis.report import finding
from cosleec.analysis.session import Session, named
from cosleec.analysis.witness import smallest, witness
from cosleec.lang import Severity
from cosleec.lang import ast as A


def situations(a: Session, kind: str) -> None:
    """Concerns the rules allow (``concern``) and purposes they block (``purpose``)."""
    items = a.spec.concerns if kind == "concern" else a.spec.purposes
    for s in a.walk("concern-raised" if kind == "concern" else "purpose-blocked", items, named):
        asked = a.deepen(functools.partial(_situation, a, s), None, f"{kind} {s.name}")
        if asked is None:
            continue
        answer, enc, goal, cands = asked
        if kind == "concern" and answer == z3.sat:
            model = smallest(enc, [goal, *(lit for _, lit in cands)])
            w = witness(enc, model, a.settings.reading, shows=[_as_rule(s)])
            a.findings.append(
                finding(
                    a.spec,
                    "concern-raised",
                    s.name,
                    f"concern {s.name} is raised: the rules allow this undesirable situation",
                    span=s.span,
                    hint="strengthen the rules so that the situation cannot happen (the witness shows how it can)",
                    witness=w,
                )
            )
        elif kind == "purpose" and answer == z3.unsat:
            core = a.core(enc, goal, cands, f"purpose {s.name}")
            a.findings.append(
                finding(
                    a.spec,
                    "purpose-blocked",
                    s.name,
                    f"purpose {s.name} is blocked by {', '.join(core) or 'the relations'}: no trace "
                    "that meets the rules achieves it",
                    span=s.span,
                    hint="relax one of these rules (an unless clause for this situation) so the purpose "
                    "stays possible",
                    cause=core,
                    decided_by=enc,
                    severity=Severity.ERROR,
                )
            )


def _situation(a: Session, s: A.Situation, bound: int) -> tuple[Encoding, Any]:
    """An encoding and goal literal for ``s`` (the situation occurs)."""
    if s.meanwhile is None:
        enc, x = a.encoding(s.trigger.event, bound)
    else:
        enc = a.new_encoding(bound)
        chain: list[tuple[A.Situation, Slot]] = []
        cur: A.Situation | None = s
        while cur is not None:
            slot = enc.probe(cur.trigger.event)
            for r in cur.responses:
                enc.demand(slot, r)
            chain.append((cur, slot))
            cur = cur.meanwhile
        enc.unfold()
        x = chain[0][1]
    goal = enc.fresh("situation")
    parts = []
    cur = s
    slots = [x] if s.meanwhile is None else [slot for _, slot in chain]
    for slot in slots:
        assert cur is not None
        parts.append(enc.truth(cur.trigger.condition, slot.snap))
        parts += [enc.obligations.holds(r, slot, untimed=0.0, situation=True) for r in cur.responses]
        cur = cur.meanwhile
    enc.solver.add(z3.Implies(goal, z3.And(*parts, enc.ctx)))
    return enc, goal


def _as_rule(s: A.Situation) -> A.Rule:
    """A concern or purpose read as a rule (to judge a witness by the reference semantics)."""
    items: list[A.ResponseItem] = []
    for r in s.responses:
        items.extend(r.items)
    return A.Rule(s.name, s.trigger, A.Response(tuple(items)) if items else A.Response(()))


__all__ = ["situations"]
