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
import weakref
from collections.abc import Callable
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
    """Time that moves only when told to (``advance``/``set``): deadlines in tests are exact.

    Moving it judges what fell due: every started Manager on this clock watches it
    (:meth:`watch`) and ticks as it moves, so ``clock.advance(61)`` alone runs the
    ``otherwise`` of a 60-second deadline. One big step costs one tick: the deadlines it
    passed are judged in order, each at its own time.
    """

    def __init__(self, start: float = 0.0) -> None:
        _finite(start)
        self._t = start
        self._lock = threading.Lock()
        self._watchers: list[weakref.WeakMethod[Callable[[], object]]] = []
        self._telling = threading.local()  # this thread is telling the watchers: a move now waits

    def now(self) -> float:
        """The time last set or advanced to, in seconds."""
        return self._t

    def advance(self, seconds: float) -> float:
        """Move time forward by ``seconds``, judge what fell due, and return the new time.

        ValueError if negative. Every watching Manager ticks (:meth:`watch`): the deadlines
        and stale values the move passed are processed before this returns.
        """
        _finite(seconds)
        if seconds < 0:
            raise ValueError("time does not go back")
        with self._lock:
            self._t += seconds
            now = self._t
        self._moved()
        return now

    def set(self, t: float) -> None:
        """Jump to time ``t`` (seconds); ValueError if ``t`` is earlier than now or not a finite number.

        The Manager node uses it to follow the ``clock`` topic in simulated time.
        """
        _finite(t)
        with self._lock:
            if t < self._t:
                raise ValueError("time does not go back")
            self._t = t
        self._moved()

    def watch(self, tick: Callable[[], object]) -> Callable[[], None]:
        """Call ``tick`` (a bound method, held weakly) after every move; returns the function
        that stops it. A started Manager watches its virtual clock this way."""
        ref: weakref.WeakMethod[Callable[[], object]] = weakref.WeakMethod(tick)
        with self._lock:
            self._watchers.append(ref)

        def unwatch() -> None:
            with self._lock:
                if ref in self._watchers:
                    self._watchers.remove(ref)

        return unwatch

    def _moved(self) -> None:
        """Tell every watcher that the time moved (outside the lock: a tick reads the clock);
        all are told, then the first failure is raised again. A move made while this thread
        tells them (an implementation run by the tick moves the clock) is not told again:
        the next step of the Manager judges what it passed."""
        if getattr(self._telling, "on", False):
            return
        with self._lock:
            watchers = list(self._watchers)
        failed: BaseException | None = None
        self._telling.on = True
        try:
            for ref in watchers:
                tick = ref()
                if tick is None:
                    continue
                try:
                    tick()
                except Exception as e:
                    failed = failed or e
        finally:
            self._telling.on = False
        if failed is not None:
            raise failed


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
