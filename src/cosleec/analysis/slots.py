"""The occurrences a trace is encoded with (:mod:`cosleec.analysis.encoding`): slots, the
snapshot an ``otherwise`` reads, the prohibitions a slot can raise, and which occurrences come
after a step.

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
class Ban:
    """A prohibition a rule can raise at ``slot``: in force when ``active``, over ``[lo, hi]``."""

    slot: Slot
    active: Z3
    lo: Z3
    hi: Z3 | None


def before(z: Slot, y: Slot) -> Z3:
    """``z`` comes before ``y`` in the trace."""
    return z3.Or(z.t < y.t, z3.And(z.t == y.t, z.pos < y.pos))


__all__ = ["Z3", "After", "Ban", "Fallback", "Slot", "before"]
