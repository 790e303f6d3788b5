"""N-Check's situational conflicts, proved: a history the rules allow (it can be continued
without breaking any rule), after which one more trigger cannot be answered without a rule
being broken (``situational-conflict``).

The candidates come from the runtime conflicts (runtime_conflicts.py): an obligation still
pending (its event has not occurred since it was raised) when a prohibition of its event
starts, its whole remaining window forbidden. The candidate's history is pinned (times and
values, from the model that found it); it must be satisfiable without the later trigger and
unsatisfiable with it, at growing bounds, and the minimal set of rules that then leaves the
trigger unanswerable is named.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import z3

from cosleec.analysis.encoding import After, Encoding, Slot, as_float
from cosleec.analysis.report import finding
from cosleec.analysis.runtime_conflicts import Clash, Overlap, clause_name
from cosleec.analysis.session import Session
from cosleec.analysis.witness import reads as read
from cosleec.analysis.witness import show, snapshot, then


class _History(NamedTuple):
    """A pinned history the rules allow (``allowed``: a model of it), after which the later
    trigger (slot ``last`` of ``fixed``) cannot be answered: ``goal`` is unsatisfiable with
    the ``cands`` (rules and relations) of ``fixed``. A tuple, as it has always been (state.py
    says why the order z3's terms are let go in matters)."""

    fixed: Encoding
    last: Slot
    goal: Any
    cands: list[tuple[str, Any]]
    allowed: Any


def situational_conflicts(a: Session, c: Clash, o: Overlap) -> None:
    """The situational conflicts that overlap ``o`` of clash ``c`` can leave: each trigger in
    turn as the one that cannot be answered (one finding per pair and trigger)."""
    enc, xo, xp, lo, hi, plo, phi = o.enc, o.xo, o.xp, o.lo, o.hi, o.plo, o.phi
    if hi is None:
        return  # an obligation without deadline can always wait
    ro, rp = c.owing, c.banning
    event = c.owed.occurrence.event
    remaining = z3.If(lo >= xp.t, lo, xp.t)
    covered = z3.And(remaining <= hi, plo <= remaining, *([hi <= phi] if phi is not None else []))
    pending = (
        z3.Not(enc.windows.occurs(event, lo, xp.t, After(slot=xo)))
        if xo is not xp
        else z3.BoolVal(True, enc.ctx)
    )
    orders = (
        [(z3.BoolVal(True, enc.ctx), ro)]
        if xo is xp
        else [(After(slot=xp)(xo), ro), (After(slot=xo)(xp), rp)]
    )
    for order, later in orders:  # each trigger in turn as the one that cannot be answered
        if any(  # this pair already leaves this trigger unanswerable: one finding says it
            f.code == "situational-conflict"
            and later.name in f.extra["triggers"]
            and {ro.name, rp.name} <= set(f.rules)
            for f in a.findings
        ):
            continue
        if a.solve(enc, [*o.base, covered, pending, order], "situation") == z3.sat:
            _pinned(a, enc.solver.model(), c, o)


def _pinned(a: Session, model: Any, c: Clash, o: Overlap) -> None:
    """The candidate situation of ``model``: the history before the later trigger pinned."""
    event = c.owed.occurrence.event
    probes = list(dict.fromkeys([o.xo, o.xp]))
    probes.sort(key=lambda x: (as_float(model.eval(x.t, True)), as_float(model.eval(x.pos, True))))
    h = _deepest(a, model, probes, event, o.xo, o.xp)
    if h is None:
        return
    # held in these names (and `fixed`, `last` in the closures below), so that the history is
    # let go of in this order when the search ends, as it always has been (state.py says why)
    fixed, last, goal, cands, allowed = h
    later = c.owing if probes[-1] is o.xo else c.banning
    core = a.core(fixed, goal, cands, f"situational conflict of {later.name}")
    if any(f.code == "vacuous-conflict" and f.subject in core for f in a.findings):
        return
    # the rules of the cause that the later occurrence triggers: those it leaves unanswerable
    triggers = [n for n in core if a.spec.rule(n).trigger.event == last.event] or [later.name]
    if later.name not in triggers:
        later = a.spec.rule(triggers[0])
    if any(  # the same cause, and the same triggers unanswerable, already shown
        f.code == "situational-conflict" and f.rules == core and set(triggers) <= set(f.extra["triggers"])
        for f in a.findings
    ):
        return
    reads = read(c.owing) | read(c.banning)
    situation = "; ".join(
        f"{x.event} at t={show(model, x.t)}"
        + (" with " + snapshot(fixed, model, x.snap, reads) if reads & x.snap.keys() else "")
        for x in probes
    )
    if o.xo is not o.xp:
        situation += f"; no `{event}` in between"
    a.findings.append(
        finding(
            a.spec,
            "situational-conflict",
            later.name,
            f"rule {later.name} cannot be answered in a situation the rules allow: "
            f"{clause_name(c.banning.name, c.banning_clause)} forbids `{event}` for the whole window in which "
            f"{clause_name(c.owing.name, c.owing_clause)} owes it (the cause: {', '.join(core)})",
            span=later.span,
            hint="add an unless clause for this situation to one of the rules, or declare which prevails "
            "in a priority block",
            cause=core,
            itself=later.name,
            decided_by=fixed,
            situation=situation,
            witness=then(fixed, allowed, last, a.settings.reading),
            extra={"triggers": triggers},
        )
    )


def _deepest(a: Session, model: Any, probes: list[Slot], event: str, xo: Slot, xp: Slot) -> _History | None:
    """The pinned history of ``model`` at the bounds of :meth:`Session.bounds` in turn, up to
    the first whose unfolding completes; None when the rules do not allow it, or the trigger
    can be answered. When a larger bound runs out of time, the last answer stands (said in
    :attr:`Session.unknown`)."""
    built: _History | None = None
    for b in a.bounds():
        attempt = _history(a, model, probes, event, xo, xp, b)
        if attempt is None:
            return None  # the rules do not allow the history, or the trigger can be answered
        if isinstance(attempt, str):  # out of time: the last answer stands, up to its bound
            if built is not None:
                a.unknown.append(
                    f"situational conflict: answered up to bound {built.fixed.bound} only "
                    f"(bound {b} ran out of time)"
                )
            break
        built = attempt
        if built.fixed.complete:
            break
    return built


def _history(
    a: Session, model: Any, probes: list[Slot], event: str, xo: Slot, xp: Slot, bound: int
) -> _History | str | None:
    """At ``bound``: the pinned history is allowed and the later trigger then cannot be
    answered -> the history; None when not; ``"unknown"`` when the solver ran out of time."""
    fixed = a.new_encoding(bound)
    pinned: dict[int, Slot] = {}
    for n, x in enumerate(probes):
        pinned[x.id] = fixed.probe(x.event) if n + 1 < len(probes) else fixed.free(x.event)
    fixed.unfold()
    last = pinned[probes[-1].id]
    pins = []
    for x in probes:
        s = pinned[x.id]
        pins.append(s.t == model.eval(x.t, model_completion=True))
        pins += [s.snap[m] == model.eval(v, model_completion=True) for m, v in x.snap.items()]
    if len(probes) == 2:
        pins.append(pinned[probes[0].id].pos < last.pos)
    if xo is not xp:  # the obligation is still pending when the later trigger comes
        so = pinned[xo.id]
        between = [
            z3.And(y.present, After(slot=so)(y), z3.Not(After(slot=last)(y)))
            for y in fixed.by_event.get(event, ())
        ]
        pins.append(z3.Not(z3.Or(*between, fixed.ctx)))
    history, situation_goal = fixed.fresh("history"), fixed.fresh("situation")
    fixed.solver.add(z3.Implies(history, z3.And(*pins, z3.Not(last.present))))
    fixed.solver.add(z3.Implies(situation_goal, z3.And(*pins, last.present)))
    cands = a.candidates(fixed)
    lits = [lit for _, lit in cands]
    answer = fixed.check([history, *lits])
    if answer != z3.sat:
        return "unknown" if answer == z3.unknown else None
    allowed = fixed.solver.model()
    answer = fixed.check([situation_goal, *lits])
    if answer != z3.unsat:
        return "unknown" if answer == z3.unknown else None
    return _History(fixed, last, situation_goal, cands, allowed)


__all__ = ["situational_conflicts"]
