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
from collections.abc import Callable
from typing import Any

from cosleec.nodes import LogLimiter

log = logging.getLogger("cosleec.ros")


class CallbackGuard:
    """Wraps a transport's callbacks so that an exception is counted and logged, never raised.

    One per transport; thread-safe (rospy runs callbacks on several threads). Logging is
    rate-limited per topic by the nodes' :class:`~cosleec.nodes.LogLimiter`.
    """

    def __init__(self, every: float = 10.0) -> None:
        self.errors = 0
        self.limiter = LogLimiter(log, every)
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
        self.limiter.log(
            logging.ERROR,
            topic,
            "a callback for %s raised %s; the node goes on",
            topic,
            type(error).__name__,
            exc_info=error,
        )
