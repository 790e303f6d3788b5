"""Clocks: the monotonic clock in production, a virtual one for tests and scripted demos.

The runtime never reads the time itself: the Manager asks its :class:`Clock`, so deadlines
and stale values can be tested to the exact second, and the ROS Manager node can follow
simulated time (``--sim-time``).
"""

from __future__ import annotations

import functools
import math
import threading
import time
from pathlib import Path
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
        _finite(start)
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
        _finite(seconds)
        if seconds < 0:
            raise ValueError("time does not go back")
        with self._lock:
            self._t += seconds
            return self._t

    def set(self, t: float) -> None:
        """Jump to time ``t`` (seconds); ValueError if ``t`` is earlier than now or not a finite number.

        The Manager node uses it to follow the ``clock`` topic in simulated time.
        """
        _finite(t)
        with self._lock:
            if t < self._t:
                raise ValueError("time does not go back")
            self._t = t


#: the latest time a clock may show (about 31,700 years of seconds): past it ``t + 60 == t``
#: is near (a float's precision), and nanoseconds sent as seconds are caught
MAX_TIME = 1e12


def _finite(t: object) -> None:
    """ValueError unless ``t`` is a finite real number (NaN and infinity would stop every deadline)."""
    if isinstance(t, bool) or not isinstance(t, int | float):
        raise ValueError(f"a time is a number of seconds, not {type(t).__name__}")
    try:
        ok = math.isfinite(t)
    except OverflowError:
        ok = False
    if not ok or abs(t) > MAX_TIME:
        raise ValueError(f"a time must be a finite number of seconds, at most {MAX_TIME:g}")


@functools.cache
def boot() -> str:
    """This boot of the machine (Linux's boot id; a monotonic clock counts from it), or "" where it cannot be told."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return ""
