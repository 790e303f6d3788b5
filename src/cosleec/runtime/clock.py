"""Clocks: the monotonic clock in production, a virtual one for tests and scripted demos.

The runtime never reads the time itself: the Manager asks its :class:`Clock`, so deadlines
and stale values can be tested to the exact second, and the ROS Manager node can follow
simulated time (``--sim-time``).
"""

from __future__ import annotations

import threading
import time
from typing import Protocol


class Clock(Protocol):
    """What the runtime needs of time: pass any object with ``now()`` as ``Manager(clock=...)``.

    Deadlines and ``max_age`` use only differences of ``now()``, so the origin is free (a
    simulator's clock fits); the value must never decrease.
    """

    def now(self) -> float:
        """The current time, in seconds."""
        ...


class MonotonicClock:
    """Seconds from ``time.monotonic()``: never jumps, never goes back."""

    def now(self) -> float:
        """Seconds since an arbitrary origin (``time.monotonic()``)."""
        return time.monotonic()


class VirtualClock:
    """Time that moves only when told to (``advance``/``set``): deadlines in tests are exact."""

    def __init__(self, start: float = 0.0) -> None:
        self._t = start
        self._lock = threading.Lock()

    def now(self) -> float:
        """The time last set or advanced to, in seconds."""
        return self._t

    def advance(self, seconds: float) -> float:
        """Move time forward by ``seconds`` and return the new time; ValueError if negative.

        Moving the clock judges nothing by itself: call ``Manager.tick()`` afterwards so
        the deadlines and stale values it passed are processed.
        """
        if seconds < 0:
            raise ValueError("time does not go back")
        with self._lock:
            self._t += seconds
            return self._t

    def set(self, t: float) -> None:
        """Jump to time ``t`` (seconds); ValueError if ``t`` is earlier than now.

        The Manager node uses it to follow the ``clock`` topic in simulated time.
        """
        with self._lock:
            if t < self._t:
                raise ValueError("time does not go back")
            self._t = t
