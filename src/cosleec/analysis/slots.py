"""The occurrences a trace is encoded with (:mod:`cosleec.analysis.encoding`): slots, the
snapshot an ``otherwise`` reads, the prohibitions a slot can raise, which occurrences come
after a step, and when a declared priority cancels a firing (:class:`Cut`).

A :class:`Slot` is one possible occurrence: present or not, its time, causal position and
snapshot free. Every question about a response asks which present slots fall in a window
*after* the step that raised it (:class:`After`, :func:`before`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import z3

Z3 = Any  # z3's Python API is untyped


@dataclass(eq=False)
class Slot:
    """One possible occurrence of ``event``: present or not, with its time and snapshot."""

    id: int
    event: str
    depth: int
    t: Z3
    pos: Z3
    present: Z3
    snap: dict[str, Z3]
    why: str = ""  # what it may fulfil, for a witness's timeline


@dataclass(eq=False)
class Fallback:
    """The snapshot an ``otherwise`` that starts at a deadline reads, and when it starts."""

    at: Z3
    started: Z3
    snap: dict[str, Z3]


@dataclass(frozen=True)
class After:
    """Which occurrences come after the step that raised an obligation: after slot ``slot``
    in causal order, or strictly after time ``at`` (an ``otherwise`` started by a deadline)."""

    slot: Slot | None = None
    at: Z3 = None

    def __call__(self, y: Slot) -> Z3:
        """``y`` comes after the raising step."""
        if self.slot is not None:
            x = self.slot
            if y is x:
                return z3.BoolVal(False, y.present.ctx)
            return z3.Or(y.t > x.t, z3.And(y.t == x.t, y.pos > x.pos))
        return y.t > self.at


@dataclass(frozen=True)
class Cut:
    """When a declared priority cancels one firing (an *instance*) of a lower rule: whether it
    is ``cancelled``, at time ``at`` and -- cancel semantics -- at the step of position ``pos``
    (the firing that cancels it, after everything that step's occurrence settles); under
    conflict-aware semantics (``pos`` None), before anything else happens at ``at``. A
    cancelled instance imposes nothing more (:mod:`cosleec.analysis.priorities`)."""

    cancelled: Z3
    at: Z3
    pos: Z3 | None

    def spares(self, y: Slot) -> Z3:
        """``y`` comes after the cancellation: it no longer breaks the instance's prohibitions."""
        if self.pos is None:
            later = y.t >= self.at
        else:
            later = z3.Or(y.t > self.at, z3.And(y.t == self.at, y.pos > self.pos))
        return z3.And(self.cancelled, later)

    def saves(self, lo: Z3, hi: Z3 | None) -> Z3:
        """An obligation of window ``[lo, hi]`` is not broken: the cancellation comes while its
        window is still open (a window closes once time passes its end; one that closes
        before it opens is broken at once)."""
        if hi is None:
            return self.cancelled
        return z3.And(self.cancelled, lo <= hi, self.at <= hi)

    def by(self, t: Z3, pos: Z3 | None = None) -> Z3:
        """The instance is cancelled at or before time ``t`` (the step of position ``pos``)."""
        if pos is None or self.pos is None:
            return z3.And(self.cancelled, self.at <= t)
        return z3.And(self.cancelled, z3.Or(self.at < t, z3.And(self.at == t, self.pos <= pos)))


@dataclass(frozen=True)
class Ban:
    """A prohibition a rule can raise at ``slot``: in force when ``active``, over ``[lo, hi]``;
    ``rule`` is the rule's name, ``cut`` when a declared priority cancels that firing."""

    slot: Slot
    active: Z3
    lo: Z3
    hi: Z3 | None
    rule: str = ""
    cut: Cut | None = None


@dataclass(frozen=True)
class Raised:
    """An obligation or prohibition (``occurrence``) a firing of a rule that a priority orders
    raises, at any depth: its window ``[lo, hi]``, the time its response started, which
    occurrences come after the step that raised it (``after``), and when it is raised
    (``guard``: the rule fires, its clause is chosen, an ``otherwise`` has started)."""

    occurrence: Any
    lo: Z3
    hi: Z3 | None
    start: Z3
    after: Any
    guard: Z3
    plain: bool  # no `else`: the reference judges it by its own window alone


def before(z: Slot, y: Slot) -> Z3:
    """``z`` comes before ``y`` in the trace."""
    return z3.Or(z.t < y.t, z3.And(z.t == y.t, z.pos < y.pos))


__all__ = ["Z3", "After", "Ban", "Cut", "Fallback", "Raised", "Slot", "before"]
