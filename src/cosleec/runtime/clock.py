"""Clocks: the monotonic clock in production, a virtual one for tests and scripted demos."""

from __future__ import annotations

import threading
import time
from typing import Protocol


class Clock(Protocol):
    def now(self) -> float: ...


class MonotonicClock:
    """Seconds from ``time.monotonic()``: never jumps, never goes back."""

    def now(self) -> float:
        return time.monotonic()


class VirtualClock:
    """Time that moves only when told to (``advance``/``set``): deadlines in tests are exact."""

    def __init__(self, start: float = 0.0) -> None:
        self._t = start
        self._lock = threading.Lock()

    def now(self) -> float:
        return self._t

    def advance(self, seconds: float) -> float:
        if seconds < 0:
            raise ValueError("time does not go back")
        with self._lock:
            self._t += seconds
            return self._t

    def set(self, t: float) -> None:
        with self._lock:
            if t < self._t:
                raise ValueError("time does not go back")
            self._t = t
