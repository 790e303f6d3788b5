"""When a response item's window opens and closes, and whether its event occurs in it (for
:mod:`cosleec.analysis.encoding`).

Windows are closed, and absolute: an item raised at ``start`` with ``within T`` is
``[start, start + T]``; ``between A and B``, ``[start + A, start + B]``; ``eventually`` has no
end; a prohibition or an obligation with an ``otherwise`` and no deadline is the instant
itself; an untimed obligation has the reading's deadline (none, or some seconds). An
occurrence counts only after the step that raised the item (:class:`~cosleec.analysis.slots.After`).
"""

from __future__ import annotations

from collections.abc import Callable

import z3

from cosleec.analysis.slots import Z3, Slot
from cosleec.analysis.state import State
from cosleec.analysis.terms import Terms, as_float
from cosleec.lang import ast as A

MAX_SECONDS = 1e10
"""The longest deadline the reference semantics reads (about 317 years); a longer one is
unknown there, and the response that has it imposes nothing (``semantics.reference``)."""


class Windows:
    """The windows of one encoding's response items, over its slots."""

    def __init__(self, state: State, terms: Terms) -> None:
        self.state = state  # with the other parts, all it holds (state.py says why)
        self.terms = terms

    def window(
        self, occ: A.Occurrence, has_otherwise: bool, start: Z3, snap: dict[str, Z3], untimed: float | None
    ) -> tuple[Z3, Z3 | None]:
        """The absolute window ``[lo, hi]`` of an occurrence started at ``start`` (hi None: none)."""
        if occ.limit is not None:
            hi = start + self.terms.seconds(occ.limit.hi, snap)
            lo = start + self.terms.seconds(occ.limit.lo, snap) if occ.limit.lo is not None else start
            return lo, hi
        if occ.eventually:
            return start, None
        if occ.negated or has_otherwise:
            return start, start
        return start, None if untimed is None else start + untimed

    def occurs(self, event: str, lo: Z3, hi: Z3 | None, after: Callable[[Slot], Z3]) -> Z3:
        """Some present occurrence of ``event`` in ``[lo, hi]`` after the raising step."""
        return z3.Or(
            *(
                z3.And(y.present, lo <= y.t, *([y.t <= hi] if hi is not None else []), after(y))
                for y in self.state.by_event.get(event, ())
            ),
            self.state.ctx,
        )

    def in_range(self, resp: A.Response, snap: dict[str, Z3]) -> Z3 | None:
        """The deadlines of ``resp``'s items are at most :data:`MAX_SECONDS` long (None: they
        always are). A longer one is unknown to the reference semantics, and a response that
        has one imposes nothing."""
        parts = []
        for it in resp.items:
            lim = it.occurrence.limit
            for d in () if lim is None else (lim.hi, lim.lo):
                if d is None:
                    continue
                v = self.terms.seconds(d, snap)
                simple = z3.simplify(v)
                if (z3.is_rational_value(simple) or z3.is_int_value(simple)) and abs(
                    as_float(simple)
                ) <= MAX_SECONDS:
                    continue
                parts.append(z3.And(v >= -MAX_SECONDS, v <= MAX_SECONDS))
        return z3.And(*parts) if parts else None


__all__ = ["MAX_SECONDS", "Windows"]
