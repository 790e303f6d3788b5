"""Deadline refinement: the largest (or smallest) deadline that removes a finding, found by
the solver.

A concern ``when E then not X within d`` is raised when a rule lets ``X`` come later than
``d``; an obligation ``X within 5 minutes`` clashes with a prohibition ``not X within 10
minutes``. Moving one deadline repairs both, but to what value? Guessing ``d`` is often right
and sometimes not (another rule may delay or refuse ``X``). Here each value tried is one
question to the solver -- "is the finding still reported with this deadline?" -- and the
answer is the boundary: the largest value that works when smaller ones work too (an
obligation's deadline, a prohibition's window: tighter allows fewer traces), or the
smallest when larger ones do (an obligation that must wait out a prohibition). The search
starts at a hint (the value the finding suggests), doubles away from it, then halves the
gap, in steps of one time unit: exact at that step, in a handful of questions.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import replace

from cosleec.lang import ast as A

Works = Callable[[int], bool]
"""Whether the finding is gone with the deadline at this many units (one solver question)."""

DOUBLINGS = 6
"""How far past the hint the search looks when nothing else bounds it: 2**6 times the hint."""


def seconds(d: A.Duration) -> int | None:
    """A literal duration in seconds (None: it reads a constant or a measure)."""
    if isinstance(d.value, A.IntLit) and d.unit in A.TIME_UNITS:
        return d.value.value * A.TIME_UNITS[d.unit]
    return None


def timed(rule: A.Rule, event: str, negated: bool) -> Iterator[tuple[int, int | None]]:
    """``rule``'s default items about ``event`` with that polarity, whose deadline a repair
    can move: ``(position, deadline in seconds)``, None for an obligation without one."""
    for i, it in enumerate(rule.response.items):
        o = it.occurrence
        if o.event != event or o.negated != negated or (o.limit is not None and o.limit.lo is not None):
            continue
        if o.limit is None:
            if not negated:
                yield i, None
            continue
        current = seconds(o.limit.hi)
        if current is not None:
            yield i, current


def timed_obligations(rule: A.Rule) -> Iterator[tuple[int, int]]:
    """``rule``'s default obligations with a literal deadline: ``(position, seconds)``."""
    for i, it in enumerate(rule.response.items):
        o = it.occurrence
        if not o.negated and o.limit is not None and o.limit.lo is None:
            due = seconds(o.limit.hi)
            if due is not None:
                yield i, due


def with_deadline(rule: A.Rule, i: int, steps: int, unit: str) -> A.Rule:
    """``rule`` with item ``i`` due within ``steps`` ``unit``."""
    items = list(rule.response.items)
    o = items[i].occurrence
    limit = A.TimeLimit(A.Duration(A.IntLit(steps), unit))
    items[i] = replace(items[i], occurrence=replace(o, limit=limit, eventually=False))
    return replace(rule, response=replace(rule.response, items=tuple(items)))


def largest(works: Works, hint: int, ceiling: int | None) -> int | None:
    """The largest ``n`` in ``[1, ceiling]`` with ``works(n)``, when every smaller value works
    too (None: not even 1 does). ``ceiling`` None: ``hint`` times 2**:data:`DOUBLINGS`."""
    top = ceiling if ceiling is not None else max(hint, 1) << DOUBLINGS
    n = min(max(hint, 1), top)
    if n < 1:
        return None
    if not works(n):
        good, _ = _halve(works, 0, n, keep_good=True)
        return good or None
    while n < top:
        nxt = min(n * 2, top)
        if not works(nxt):
            return _halve(works, n, nxt, keep_good=True)[0]
        n = nxt
    return n


def smallest(works: Works, hint: int, ceiling: int | None) -> int | None:
    """The smallest ``n`` in ``[1, ceiling]`` with ``works(n)``, when every larger value works
    too (None: not even ``ceiling`` does)."""
    top = ceiling if ceiling is not None else max(hint, 1) << DOUBLINGS
    n = min(max(hint, 1), top)
    if works(n):
        return _halve(works, 0, n, keep_good=False)[1]
    while n < top:
        nxt = min(n * 2, top)
        if works(nxt):
            return _halve(works, n, nxt, keep_good=False)[1]
        n = nxt
    return None


def _halve(works: Works, low: int, high: int, *, keep_good: bool) -> tuple[int, int]:
    """Bisect ``(low, high)`` until they are one apart; ``keep_good``: ``works(low)`` holds
    (or ``low`` is 0) and ``works(high)`` does not, else the other way round."""
    while high - low > 1:
        mid = (low + high) // 2
        if works(mid) == keep_good:
            low = mid
        else:
            high = mid
    return low, high


__all__ = [
    "DOUBLINGS",
    "Works",
    "largest",
    "seconds",
    "smallest",
    "timed",
    "timed_obligations",
    "with_deadline",
]
