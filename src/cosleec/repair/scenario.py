"""A situation in which a patch changes behaviour, told as a sentence a SLEEC expert reads
(for :mod:`cosleec.repair.behaviour`).

The solver's trace is judged by the reference semantics (:func:`cosleec.semantics.judge`)
under both versions of the rules; the obligation or prohibition one version breaks at the
probe is what the sentence names: "PreparingDrone with damages=true: before, DeployDrone was
forbidden (R13); after, it is allowed". The trace is read as complete, as the analysis reads
it: an obligation still pending when it ends was not met.
"""

from __future__ import annotations

from collections.abc import Sequence

from cosleec.analysis import final_breaches
from cosleec.lang import Reading, Specification
from cosleec.semantics import Step, Verdict, judge

UNCONFIRMED = " (not confirmed by the reference semantics)"
"""Said after a scenario whose trace the reference semantics does not judge differently."""


def breaks(spec: Specification, trace: Sequence[Step], reading: Reading) -> list[Verdict]:
    """What ``spec``'s rules hold against a complete ``trace``: the breaches nothing makes up
    for, and the obligations still pending at its end."""
    j = judge(spec, trace, reading)
    return [*final_breaches(spec, j), *(v for v in j.pending if not v.negated)]


def tell(
    before: Specification,
    after: Specification,
    trace: Sequence[Step],
    reading: Reading,
    *,
    forbidden: bool,
    event: str,
    where: str,
    rule: str,
    at: float,
) -> str:
    """The sentence for a trace that ``after`` newly forbids (``forbidden``) or newly allows,
    at the occurrence of ``event`` at time ``at`` with the values ``where`` (``m=v, ...``),
    where ``rule`` (of the stricter version) is broken."""
    strict, lenient = (after, before) if forbidden else (before, after)
    j = judge(strict, trace, reading)
    held = [*final_breaches(strict, j), *(v for v in j.pending if not v.negated)]
    confirmed = bool(held) and not breaks(lenient, trace, reading)
    fired_at = {(f.rule, f.instance): f.time for f in j.firings if f.fired}
    mine = [v for v in held if v.rule == rule]
    here = [v for v in mine if fired_at.get((v.rule, v.instance)) == at] or mine
    head = f"{event} with {where}" if where else event
    if not here:
        body = (
            f"before, the rules allowed this trace; after, {rule} forbids it"
            if forbidden
            else f"before, {rule} forbade this trace; after, the rules allow it"
        )
    else:
        body = _what(here[0], forbidden)
    return f"{head}: {body}" + ("" if confirmed else UNCONFIRMED)


def _what(v: Verdict, forbidden: bool) -> str:
    """What changes for the obligation or prohibition ``v`` (which the stricter version breaks)."""
    lo, hi = v.window
    if hi is None:
        span = ""
    elif hi == v.start:
        span = " at the same moment"
    elif lo <= v.start:
        span = f" within {duration(hi - v.start)}"
    else:
        span = f" between {duration(lo - v.start)} and {duration(hi - v.start)}"
    if forbidden:
        if v.negated:
            return f"before, {v.event}{span} was allowed; after, it is forbidden ({v.rule})"
        return f"before, going without {v.event}{span} was allowed; after, it is required ({v.rule})"
    if v.negated:
        return f"before, {v.event}{span} was forbidden ({v.rule}); after, it is allowed"
    return f"before, {v.event}{span} was required ({v.rule}); after, going without it is allowed"


def duration(seconds: float) -> str:
    """``180`` as ``3 minutes``, ``1`` as ``1 second``, ``0.5`` as ``0.5 seconds``."""
    for unit, size in (("day", 86400), ("hour", 3600), ("minute", 60)):
        if seconds >= size and seconds % size == 0:
            n = seconds / size
            return f"{n:g} {unit}{'' if n == 1 else 's'}"
    return f"{seconds:g} second{'' if seconds == 1 else 's'}"


__all__ = ["UNCONFIRMED", "breaks", "duration", "tell"]
