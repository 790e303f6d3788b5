"""The transports' last line of defence: no exception leaves a middleware callback.

An exception raised into rclpy's executor ends ``spin()``: the node goes deaf while its
heartbeat still says it is alive. rospy survives it but logs every one, unbounded. The
nodes reject bad messages themselves (:meth:`cosleec.nodes.Node.on`); whatever still
escapes a handler is caught here, counted in :attr:`CallbackGuard.errors` (node status
reports it as ``transport_errors``) and logged at most once per topic every ``every``
seconds, with the number held back.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

log = logging.getLogger("cosleec.ros")


class CallbackGuard:
    """Wraps a transport's callbacks so that an exception is counted and logged, never raised.

    One per transport; thread-safe (rospy runs callbacks on several threads).
    """

    def __init__(self, every: float = 10.0) -> None:
        self.every = every
        self.errors = 0
        self._last: dict[str, tuple[float, int]] = {}  # topic -> (last logged at, held back since)
        self._lock = threading.Lock()

    def wrap(self, topic: str, callback: Callable[[Any], None]) -> Callable[[Any], None]:
        """``callback``, made safe to hand to the middleware for messages on ``topic``."""

        def guarded(message: Any) -> None:
            try:
                callback(message)
            except Exception as e:
                self.failed(topic, e)

        return guarded

    def failed(self, topic: str, error: Exception) -> None:
        """Count ``error``, raised by a callback for ``topic``; log it unless that topic logged lately."""
        with self._lock:
            self.errors += 1
            now = time.monotonic()
            last = self._last.get(topic)
            if last is not None and now - last[0] < self.every:
                self._last[topic] = (last[0], last[1] + 1)
                return
            self._last[topic] = (now, 0)
            held = last[1] if last is not None else 0
        log.error(
            "a callback for %s raised %s (%d more in the last %.0f s not logged); the node goes on",
            topic,
            type(error).__name__,
            held,
            self.every,
            exc_info=error,
        )
