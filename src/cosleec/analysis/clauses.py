"""The checks over one snapshot: clauses never selected, semantics that disagree, negative deadlines.

These read only the values a trigger finds (measure domains: booleans, reals, scale
positions; and the measure relations), so each answer is a proof -- no bound is involved.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from typing import Any

import z3

from cosleec.analysis.checks import Analysis
from cosleec.analysis.encoding import Encoding, Slot
from cosleec.analysis.findings import PROVED, Finding
from cosleec.analysis.witness import reads, show, snapshot, witness
from cosleec.lang import HedgeSemantics, Severity, choose
from cosleec.lang import ast as A
from cosleec.semantics import Judgement


def _probe(a: Analysis, rule: A.Rule) -> tuple[Encoding, Slot, list[Any]]:
    """A one-occurrence encoding of ``rule``'s trigger, and what always holds of it."""
    enc = a.new_encoding(1)
    x = enc.probe(rule.trigger.event)
    enc.unfold(children=False)
    return enc, x, [enc.fires(rule, x), enc.assumptions(x.snap), *enc.relation_lit]


def _values(enc: Encoding, model: Any, x: Slot, rule: A.Rule) -> str:
    """The values of the measures ``rule`` reads, as the model has them."""
    return snapshot(enc, model, x.snap, reads(rule))


def unselectable(a: Analysis) -> None:
    """Clauses (the default response included) that no values let apply: one question per
    clause, asked in turn (:meth:`Encoding.each_clause`, linear in the clauses)."""
    sem = a.settings.semantics
    for rule in a.walk("unselectable-clause", a.spec.rules, _named):
        ds = rule.response.defeaters
        if not ds:
            continue
        enc, x, base = _probe(a, rule)
        if a.solve(enc, base, f"clauses of {rule.name}") != z3.sat:
            continue  # the trigger condition itself never holds: every clause would be reported
        for k in _never_selected(a, enc, x, base, rule):
            span = rule.response.span if k == 0 else ds[k - 1].span
            what = "the default response" if k == 0 else f"clause {rule.name}.{k} (unless #{k})"
            a.findings.append(
                Finding(
                    code="unselectable-clause",
                    subject=f"{rule.name}.{k}",
                    message=f"{what} is never selected under {sem} semantics, whatever the measures' values",
                    path=a.spec.path,
                    span=span,
                    rules=(rule.name,),
                    hint="reorder the unless clauses (the last that holds wins)"
                    if sem == HedgeSemantics.LAST_WINS
                    else "reorder the unless clauses (each needs the ones before it)",
                    status=PROVED,
                )
            )


def _never_selected(a: Analysis, enc: Encoding, x: Slot, base: list[Any], rule: A.Rule) -> list[int]:
    """The clauses of ``rule`` (0: the default) that no values of ``x`` let apply."""
    never: list[int] = []

    def ask(k: int, applies: Any) -> None:
        if a.solve(enc, [*base, applies], f"clause {k} of {rule.name}") == z3.unsat:
            never.append(k)

    enc.each_clause(rule.response.defeaters, x.snap, ask)
    return sorted(never)


def semantics_differ(a: Analysis) -> None:
    """Rules where last-wins and nested choose different clauses, with such a situation.

    They choose alike exactly when the conditions that hold are a prefix of the clauses
    (1..p), that is when no condition fails right before one that holds: so one question
    per neighbouring pair, each over two conditions -- linear in the clauses, where one
    question over every pair of choices was quadratic in size and, for z3, worse in time."""
    sem = a.settings.semantics  # the witness is judged under it
    for rule in a.walk("semantics-differ", a.spec.rules, _named):
        ds = rule.response.defeaters
        if len(ds) < 2:
            continue
        enc, x, base = _probe(a, rule)
        c = [enc.truth(d.condition, x.snap) for d in ds]
        answer, gave_up = z3.unsat, 0
        for i in range(len(c) - 1):
            answer = enc.check([*base, z3.Not(c[i]), c[i + 1]])
            if answer == z3.sat:
                break
            gave_up += answer == z3.unknown
        if answer != z3.sat:
            if gave_up:  # said once per rule, not once per pair
                a.unknown.append(
                    f"semantics of {rule.name}: the solver gave up on {gave_up} of {len(c) - 1} questions "
                    f"({enc.solver.reason_unknown()})"
                )
            continue
        model = enc.solver.model()
        held = [z3.is_true(model.eval(ci, model_completion=True)) for ci in c]
        pick_lw = choose(held, HedgeSemantics.LAST_WINS)
        pick_ne = choose(held, HedgeSemantics.NESTED)
        assert pick_lw is not None and pick_ne is not None  # every value is known in a model
        situation = _values(enc, model, x, rule)
        a.findings.append(
            Finding(
                code="semantics-differ",
                subject=rule.name,
                message=f"rule {rule.name} means different things under last-wins and nested: with "
                f"{situation or 'these values'}, last-wins selects {_name(rule.name, pick_lw)} and nested "
                f"selects {_name(rule.name, pick_ne)}",
                path=a.spec.path,
                span=rule.span,
                rules=(rule.name,),
                hint="make the unless conditions exclusive (or nested by construction), or state which "
                "semantics the rules are written for",
                status=PROVED,
                situation=situation,
                witness=witness(
                    enc,
                    model,
                    a.settings.reading,
                    confirm=functools.partial(
                        _picked, clause=pick_lw if sem == HedgeSemantics.LAST_WINS else pick_ne
                    ),
                ),
                severity=Severity.NOTE,
            )
        )


def _named(rule: A.Rule) -> str:
    return rule.name


def _picked(j: Judgement, clause: int) -> bool:
    return any(f.fired and f.clause == clause for f in j.firings)


def _name(rule: str, k: int) -> str:
    return f"the default response of {rule}" if k == 0 else f"{rule}.{k}"


def negative_deadlines(a: Analysis) -> None:
    """Deadlines computed from measures that some values make negative (or end before they start)."""
    for rule in a.walk("negative-deadline", a.spec.rules, _named):
        for clause, depth, it in _items(rule.response, 0, 0):
            lim = it.occurrence.limit
            measures = {m.name for m in a.spec.measures}
            if lim is None or not (
                _reads(lim.hi.value, measures) or (lim.lo is not None and _reads(lim.lo.value, measures))
            ):
                continue
            enc, x, base = _probe(a, rule)
            if depth == 0:
                base.append(enc.chosen_at(rule.response, clause, x.snap))
            else:  # an otherwise reads the values at its own start: any values
                base = [enc.assumptions(x.snap), *enc.relation_lit]
            hi = enc.seconds(lim.hi, x.snap)
            bad = hi < 0  # the window ends before the step that raised it: closed at once
            if lim.lo is not None:
                bad = z3.Or(bad, hi < enc.seconds(lim.lo, x.snap))  # ends before it starts
            if a.solve(enc, [*base, bad], f"deadline in {rule.name}") != z3.sat:
                continue
            model = enc.solver.model()
            situation = _values(enc, model, x, rule)
            what = "prohibition" if it.occurrence.negated else "obligation"
            then = "respected" if it.occurrence.negated else "violated"
            if lim.lo is None:
                window = f"its deadline is {show(model, hi)} seconds"
            else:
                window = (
                    f"its window is [{show(model, enc.seconds(lim.lo, x.snap))}, {show(model, hi)}] seconds"
                )
            a.findings.append(
                Finding(
                    code="negative-deadline",
                    subject=rule.name,
                    message=f"the window of `{it.occurrence.event}` in {rule.name} can close before it opens: with "
                    f"{situation}, {window} (the {what} is then {then} at once)",
                    path=a.spec.path,
                    span=lim.span or it.occurrence.span,
                    rules=(rule.name,),
                    hint="bound the measure with an unless clause or a relation (measure invariant), or use a "
                    "constant deadline",
                    status=PROVED,
                    situation=situation,
                    severity=Severity.WARNING,
                )
            )


def _reads(e: A.Expr, measures: set[str]) -> bool:
    """``e`` reads a measure."""
    if isinstance(e, A.Name):
        return e.name in measures
    if isinstance(e, A.BinOp):
        return _reads(e.left, measures) or _reads(e.right, measures)
    return False


def _items(resp: A.Response | None, clause: int, depth: int) -> Iterator[tuple[int, int, A.ResponseItem]]:
    if resp is None:
        return
    for it in resp.items:
        yield clause, depth, it
        yield from _items(it.otherwise, clause, depth + 1)
    for k, d in enumerate(resp.defeaters, 1):
        yield from _items(d.response, k if depth == 0 and clause == 0 else clause, depth)
