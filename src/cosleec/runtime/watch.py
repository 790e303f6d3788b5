"""A virtual clock's moves judge what fell due: the Manager's watch on its :class:`VirtualClock`.

A test or a simulation moves a :class:`~cosleec.runtime.clock.VirtualClock` by hand. Before
this watch, moving it judged nothing until someone called ``Manager.tick()``: a deadline
passed by ``clock.advance(61)`` alone started no ``otherwise`` -- silent misuse. A started
Manager now watches its virtual clock: every move judges what fell due before ``advance``
returns. The ``otherwise`` decisions a move started are kept (the latest
:data:`UNCLAIMED`) for the next ``tick()`` to return, so ``clock.advance(61); m.tick()``
still sees them.

The clock holds the watch weakly (a dropped Manager is not kept alive by its clock), and
``close()`` stops it.
"""

from __future__ import annotations

from collections.abc import Callable

from cosleec.runtime.clock import Clock, VirtualClock
from cosleec.runtime.decision import Decision
from cosleec.runtime.steps import Steps

__all__ = ["UNCLAIMED", "ClockWatch"]

UNCLAIMED = 10_000
"""How many ``otherwise`` decisions started by a virtual clock's moves are kept for the next
``Manager.tick`` to return (the latest; a run that never calls ``tick`` keeps no more)."""


class ClockWatch:
    """Judges what fell due whenever a virtual clock moves, and keeps what that started.

    ``judge`` is the Manager's judging of deadlines (it returns the ``otherwise`` decisions
    started; give it weakly, :func:`~cosleec.runtime.steps.weakly`, or the watch keeps the
    Manager alive); ``steps`` are the Manager's: a broken or closed Manager judges nothing,
    and their lock guards what is kept.
    """

    def __init__(self, judge: Callable[[], list[Decision]], steps: Steps) -> None:
        self._judge = judge
        self._steps = steps
        self._unwatch: Callable[[], None] | None = None
        self._unclaimed: list[Decision] = []

    def begin(self, clock: Clock) -> None:
        """Watch ``clock`` if it is a virtual one (a real clock moves by itself: the timer
        thread or ``tick()`` judge it); once."""
        if isinstance(clock, VirtualClock) and self._unwatch is None:
            self._unwatch = clock.watch(self.moved)

    def moved(self) -> None:
        """The clock moved: judge what fell due, and keep the ``otherwise`` decisions started."""
        if self._steps.broken is not None or self._steps.closed:
            return
        started = self._judge()
        if started:
            with self._steps.lock:
                self._unclaimed = (self._unclaimed + started)[-UNCLAIMED:]

    def claim(self) -> list[Decision]:
        """The ``otherwise`` decisions the moves started since the last claim, oldest first."""
        with self._steps.lock:
            earlier, self._unclaimed = self._unclaimed, []
        return earlier

    def stop(self) -> None:
        """Stop watching (``close()``); a second call does nothing."""
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
