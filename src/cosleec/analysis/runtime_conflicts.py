"""Runtime conflicts: two clauses (of one rule or two) that can owe an event and forbid it in
overlapping windows, with no declared priority ordering their rules (``runtime-conflict``):
the runtime will have to refuse one.

Each :class:`Clash` -- an obligation and a prohibition of the same event -- is asked about in
the smallest traces that can show it: one occurrence triggering both clauses (when the rules
share their trigger), then two. Each :class:`Overlap` found is also where a situational
conflict is looked for (situational.py).
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterator
from typing import Any, NamedTuple

import z3

from cosleec.analysis.encoding import Encoding, Slot, clause_items
from cosleec.analysis.report import finding
from cosleec.analysis.session import Session
from cosleec.analysis.witness import witness
from cosleec.lang import Specification
from cosleec.lang import ast as A
from cosleec.semantics import Judgement


class Clash(NamedTuple):
    """An obligation and a prohibition of the same event: each a rule, its clause (0: the
    default response) and the response item."""

    owing: A.Rule
    owing_clause: int
    owed: A.ResponseItem
    banning: A.Rule
    banning_clause: int
    banned: A.ResponseItem


class Overlap(NamedTuple):
    """A situation where a clash's windows overlap: the encoding whose last answer shows it,
    the slots triggering the obligation (``xo``) and the prohibition (``xp``, ``xo`` itself
    when one occurrence triggers both), what holds there (``base``: both fire with their
    clauses chosen, the relations), and the two windows ``[lo, hi]`` and ``[plo, phi]``.

    A tuple, as it has always been: a tuple lets go of its items last first, and the order
    z3's terms are let go in is part of what the analysis answers (state.py says why)."""

    enc: Encoding
    xo: Slot
    xp: Slot
    base: list[Any]
    lo: Any
    hi: Any
    plo: Any
    phi: Any


Situational = Callable[[Session, Clash, Overlap], None]
"""What is asked of each overlap besides: the situational conflicts it can leave."""


def clause_name(rule: str, k: int) -> str:
    """Clause ``k`` of ``rule`` as a finding names it: ``R1`` (the default response), ``R1.2``."""
    return rule if k == 0 else f"{rule}.{k}"


def clashes(spec: Specification) -> Iterator[Clash]:
    """Every (rule, clause, obligation) and (rule, clause, prohibition) of the same event."""
    owes: dict[str, list[tuple[A.Rule, int, A.ResponseItem]]] = {}
    bans: dict[str, list[tuple[A.Rule, int, A.ResponseItem]]] = {}
    for r in spec.rules:
        for k, it in clause_items(r.response):
            (bans if it.occurrence.negated else owes).setdefault(it.occurrence.event, []).append((r, k, it))
    for event in sorted(owes.keys() & bans.keys()):
        for ro, ko, io in owes[event]:
            for rp, kp, ip in bans[event]:
                yield Clash(ro, ko, io, rp, kp, ip)


def runtime_conflicts(a: Session, situational: Situational | None) -> None:
    """Clauses that can owe and forbid an event in overlapping windows (and, with
    ``situational``, the situations where that leaves a trigger unanswerable; the time that
    takes is :attr:`Session.situational_seconds`)."""
    above = a.above
    for c in a.walk("runtime-conflict", clashes(a.spec), _pair):
        if (c.owing.name, c.banning.name) in above or (c.banning.name, c.owing.name) in above:
            continue  # a declared priority settles it
        found = list(_overlaps(a, c))
        if not found:
            continue
        # The overlap in hand is held in these names until the next clash has its own, and
        # then let go of in this order, as it always has been: when z3 lets go of terms is
        # part of what the analysis answers (state.py says why).
        enc, xo, xp, base, lo, hi, plo, phi = found[0]
        _report(a, c, found[0])
        if situational is not None:  # one occurrence triggering both, and two occurrences
            t0 = time.perf_counter()
            for enc, xo, xp, base, lo, hi, plo, phi in found:
                situational(a, c, Overlap(enc, xo, xp, base, lo, hi, plo, phi))
            a.situational_seconds += time.perf_counter() - t0


def _report(a: Session, c: Clash, o: Overlap) -> None:
    """The runtime conflict ``c``, with the witness of its first overlap ``o``."""
    ro, ko, io, rp, kp, ip = c
    event = io.occurrence.event
    w = witness(
        o.enc,
        o.enc.solver.model(),
        a.settings.reading,
        confirm=functools.partial(_overlapping, event=event, owing=ro.name, banning=rp.name),
    )
    same = ro.name == rp.name
    a.findings.append(
        finding(
            a.spec,
            "runtime-conflict",
            f"{clause_name(ro.name, ko)}/{clause_name(rp.name, kp)}",
            f"{clause_name(ro.name, ko)} can owe `{event}` while {clause_name(rp.name, kp)} forbids it, "
            "in overlapping windows"
            + (" (two activations of the rule)" if same and o.xo is not o.xp else ""),
            span=io.occurrence.span or ro.span,
            hint=(
                f"declare which prevails (priority_start {ro.name} > {rp.name} priority_end), or "
                "separate the clauses' conditions"
                if not same
                else "separate the clauses' conditions, or shorten the prohibition so that a later "
                "activation can still be answered"
            ),
            cause=a.in_order({ro.name, rp.name}),
            related=((f"{clause_name(rp.name, kp)} forbids `{event}` here", ip.occurrence.span),),
            witness=w,
        )
    )


def _overlaps(a: Session, c: Clash) -> Iterator[Overlap]:
    """Situations where the obligation and the prohibition overlap: one occurrence
    triggering both (when the rules share their trigger), then two; with no other
    occurrence when that is possible (the smallest witness)."""
    ro, ko, io, rp, kp, ip = c
    shared = ro.trigger.event == rp.trigger.event
    for one in [True, False] if shared else [False]:
        if one and ro is rp and ko != kp:
            continue  # two clauses of one rule never apply to one occurrence
        enc = a.new_encoding(min(2, a.settings.bound))  # the two triggers, and what relations need
        xo = enc.probe(ro.trigger.event, "obligation")
        xp = xo if one else enc.probe(rp.trigger.event, "prohibition")
        enc.unfold()
        lo, hi = _window(a, enc, io, xo)
        plo, phi = _window(a, enc, ip, xp)
        probes = {xo.id, xp.id}
        readable = [  # windows the reference can read (at most 1e10 s): the witness must be judged
            r
            for it, x in ((io, xo), (ip, xp))
            if (r := enc.windows.in_range(A.Response((it,)), x.snap)) is not None
        ]
        base = _base(a, enc, c, xo, xp, readable)
        overlap = z3.And(
            *([lo <= phi] if phi is not None else []), *([plo <= hi] if hi is not None else []), enc.ctx
        )
        alone = z3.And(*(z3.Not(s.present) for s in enc.slots if s.id not in probes), enc.ctx)
        what = f"runtime conflict {clause_name(ro.name, ko)} / {clause_name(rp.name, kp)}"
        if (
            a.solve(enc, [*base, overlap, alone], what) == z3.sat
            or a.solve(enc, [*base, overlap], what) == z3.sat
        ):
            yield Overlap(enc, xo, xp, base, lo, hi, plo, phi)


def _window(a: Session, enc: Encoding, it: A.ResponseItem, x: Slot) -> tuple[Any, Any]:
    """The window of item ``it`` raised at slot ``x``."""
    return enc.windows.window(
        it.occurrence, it.otherwise is not None, x.t, x.snap, a.settings.reading.untimed_seconds
    )


def _base(a: Session, enc: Encoding, c: Clash, xo: Slot, xp: Slot, readable: list[Any]) -> list[Any]:
    """What holds of an overlap: both windows ``readable`` by the reference semantics, both
    clauses fire and are chosen, the relations."""
    return [
        *readable,
        enc.fires(c.owing, xo),
        enc.chosen_at(c.owing.response, c.owing_clause, xo.snap),
        enc.fires(c.banning, xp),
        enc.chosen_at(c.banning.response, c.banning_clause, xp.snap),
        *[z3.Implies(lit, enc.relations.holds(rel)) for lit, rel in zip(enc.relation_lit, a.spec.relations)],
        *enc.relation_lit,
    ]


def _overlapping(j: Judgement, event: str, owing: str, banning: str) -> bool:
    """The judgement has an obligation of ``owing`` and a prohibition of ``banning`` on
    ``event`` whose windows overlap."""
    inf = float("inf")
    for o in j.verdicts:
        if o.rule != owing or o.negated or o.event != event:
            continue
        for p in j.verdicts:
            if p.rule == banning and p.negated and p.event == event and p is not o:
                olo, ohi = o.window
                plo, phi = p.window
                if olo <= (inf if phi is None else phi) and plo <= (inf if ohi is None else ohi):
                    return True
    return False


def _pair(c: Clash) -> str:
    return f"{clause_name(c.owing.name, c.owing_clause)}/{clause_name(c.banning.name, c.banning_clause)}"


__all__ = ["Clash", "Overlap", "Situational", "clashes", "clause_name", "runtime_conflicts"]
