"""The issuer: a response becomes the concrete obligations and prohibitions it puts in force.

Used when a decision is made (a trigger, an ``otherwise`` that starts): the response's
items become :class:`~cosleec.runtime.model.Obligation` values with their windows read on
the context now, a braced inner response chooses among its own clauses now, and an
``else`` alternative becomes the windows that would fulfil the obligation instead.

What it cannot know, it reads fail-closed: an inner choice an unknown value leaves open
issues the prohibitions of every clause that could apply (*undetermined*); a deadline
over an unknown measure is now for an obligation and :data:`MAX_WINDOW_S` for a
prohibition; an alternative an unknown value decides can never fulfil.

Pure functions of the response, the context's values and how clauses are read (clause
semantics and unknowns, from the Layer Manager); the only state is a memo of the
obligations of *fixed* responses (the same every time they start).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cosleec.lang import candidates, choose
from cosleec.runtime.context import Context
from cosleec.runtime.layers import LayerManager, evaluate
from cosleec.runtime.model import MAX_WINDOW_S, CompiledRule, Obligation, ResponseSpec
from cosleec.runtime.obligations import Tracker


@dataclass
class Issued:
    """The obligations of a response, or -- undetermined -- the prohibitions it might impose."""

    obligations: tuple[Obligation, ...]
    missing: tuple[str, ...] = ()
    determined: bool = True


class Issuer:
    """Issues the obligations of responses on ``context`` now, reading clauses as ``layers``
    does, and untimed windows as ``tracker`` does."""

    def __init__(self, context: Context, layers: LayerManager, tracker: Tracker) -> None:
        self.context = context
        self.layers = layers
        self.tracker = tracker
        # the obligations of each fixed response (ResponseSpec.fixed), made on first use:
        # id(spec) -> (spec, obligations); the spec is kept, so its id is not reused meanwhile
        self._fixed: dict[int, tuple[ResponseSpec, tuple[Obligation, ...]]] = {}

    def issue(self, spec: ResponseSpec | None, rule: str) -> Issued:
        """The concrete obligations of a response, starting now (deadlines on this snapshot).

        A braced inner response chooses among its own clauses here; when that choice is
        undetermined, the result is undetermined and holds the prohibitions of every inner
        clause that could apply.
        """
        if spec is None:
            return Issued(())
        if spec.clauses:  # a braced inner response: its own hedges, read when it starts
            semantics = self.layers.semantics
            vals, missing = evaluate(spec.clauses, self.context.values)
            k = choose(vals, semantics, self.layers.unknown)
            if k is None:
                out: list[Obligation] = []
                for j in sorted(candidates(vals, semantics)):
                    sub = self.issue(spec.clauses[j - 1].response, rule) if j else None
                    out += prohibitions(sub.obligations if sub is not None else self.items(spec, rule))
                return Issued(tuple(out), missing, determined=False)
            if k:
                return self.issue(spec.clauses[k - 1].response, rule)
        return Issued(self.items(spec, rule))

    def undetermined(self, rule: CompiledRule, values: tuple[bool | None, ...]) -> Issued:
        """An undetermined decision's obligations: the prohibitions of every clause that could apply."""
        clauses = candidates(values, self.layers.semantics) if values else frozenset({0})
        out: list[Obligation] = []
        for k in sorted(clauses):
            spec = rule.response_of(k)
            if spec is not None:
                out += prohibitions(self.issue(spec, rule.name).obligations)
        return Issued(tuple(out), determined=False)

    def items(self, spec: ResponseSpec, rule: str) -> tuple[Obligation, ...]:
        """The obligations of ``spec``'s own items (no inner choice), windows read now."""
        if spec.fixed:  # the same obligations every time: made once (immutable values, shared)
            made = self._fixed.get(id(spec))
            if made is not None and made[0] is spec:
                return made[1]
            obligations = self._make(spec, rule)
            self._fixed[id(spec)] = (spec, obligations)
            return obligations
        return self._make(spec, rule)

    def _make(self, spec: ResponseSpec, rule: str) -> tuple[Obligation, ...]:
        v = self.context.values
        out = []
        for it in spec.items:
            try:
                hi = it.hi(v) if it.hi is not None else None
            except KeyError:  # unknown (or out of range): an obligation is due now, a prohibition holds on
                hi = MAX_WINDOW_S if it.negated else 0.0
            try:
                lo = it.lo(v) if it.lo is not None else None
            except KeyError:  # a prohibition from the earliest start; an obligation due now
                lo = 0.0
                if not it.negated:
                    hi = 0.0
            alts = self.branch(it.alternative) if it.alternative is not None and not it.negated else None
            out.append(
                Obligation(
                    event=it.event,
                    negated=it.negated,
                    within_s=hi,
                    from_s=lo or 0.0,
                    eventually=it.eventually,
                    alternatives=(alts,) if alts else (),
                    otherwise=it.otherwise,
                    rule=rule,
                    item=it.key,
                )
            )
        return tuple(out)

    def branch(self, spec: ResponseSpec) -> tuple[tuple[str, float, float | None], ...] | None:
        """An ``else`` alternative as windows from now (its own clauses chosen now), or None when
        it can never fulfil: it holds a prohibition, or an unknown value decides it (fail closed)."""
        v = self.context.values
        if spec.clauses:
            vals, _ = evaluate(spec.clauses, v)
            k = choose(vals, self.layers.semantics, self.layers.unknown)
            if k is None:
                return None
            if k:
                sub = spec.clauses[k - 1].response
                return None if sub is None else self.branch(sub)
        out = []
        for it in spec.items:
            if it.negated:
                return None  # reading a prohibition as fulfilment would let the forbidden event count
            try:
                lo = it.lo(v) if it.lo is not None else 0.0
                hi = it.hi(v) if it.hi is not None else None
            except KeyError:
                return None
            if hi is None and not it.eventually:
                u = self.tracker.untimed
                hi = None if u == "none" else self.tracker.tolerance if u == "immediate" else float(u)
            out.append((it.event, lo, hi))
        return tuple(out) or None


def prohibitions(obligations: tuple[Obligation, ...]) -> list[Obligation]:
    """What an undetermined decision enforces of ``obligations``: their prohibitions, and the
    prohibitions their ``otherwise`` would start (nothing runs, so every obligation may be
    missed), shifted to start at that deadline."""
    out = [o for o in obligations if o.negated]
    for o in obligations:
        if not o.negated and o.otherwise is not None:
            at = o.within_s or 0.0
            out += after(o.otherwise, at, at, o.rule)
    return out


def after(spec: ResponseSpec, first: float, last: float, rule: str) -> list[Obligation]:
    """The prohibitions ``spec`` (an ``otherwise``) could impose when it starts between ``first``
    and ``last`` seconds from now, down its own ``otherwise`` chain and across its inner
    clauses, read fail-closed: a bound that depends on an unknown value makes the window as
    wide as it could be."""
    out: list[Obligation] = []
    for it in spec.items:
        known = _seconds(it.hi)
        if it.negated:
            lo = _seconds(it.lo) if it.lo is not None else 0.0
            hi = MAX_WINDOW_S if known is None and it.hi is not None else (known or 0.0)
            out.append(
                Obligation(
                    event=it.event,
                    negated=True,
                    from_s=first + (lo or 0.0),
                    within_s=min(MAX_WINDOW_S, last + hi),
                    rule=rule,
                    item=it.key,
                )
            )
        elif it.otherwise is not None:
            unknown = it.hi is not None and known is None
            out += after(
                it.otherwise,
                first + (known or 0.0),
                MAX_WINDOW_S if unknown else min(MAX_WINDOW_S, last + (known or 0.0)),
                rule,
            )
    for c in spec.clauses:
        if c.response is not None:
            out += after(c.response, first, last, rule)
    return out


def _seconds(fn: Callable[[dict[str, Any]], float] | None) -> float | None:
    """A window bound with no context to read (an ``otherwise`` not started yet): its constant
    value, or None when it depends on a measure (the caller reads that fail-closed)."""
    if fn is None:
        return None
    try:
        return fn({})
    except KeyError:
        return None
