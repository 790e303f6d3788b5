"""How a transport answers a call of a service it offers: the same on ROS 2 and ROS 1.

The Manager offers ``~/request``, ``~/decide`` and ``~/reload``. Whatever a call holds,
the caller gets an answer: a request that cannot be decoded (a value of an unknown kind, a
measure given twice) is the caller's mistake, told to the node's ``rejected`` callback and
answered with the service's failure form; a handler that raises is a bug, counted by the
transport's :class:`~cosleec.ros.guard.CallbackGuard` and answered so too (never
"permitted": fail closed). Only the middleware's part differs: how the response object is
had, and whether the caller is known (ROS 1 says who called; rclpy does not).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cosleec.nodes import MessageError
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.interfaces import ServiceCodec, failure

#: a node's callback for a call it cannot read: (service name, error, caller or None)
Rejected = Callable[[str, Exception, str | None], None]


@dataclass(frozen=True)
class OfferedService:
    """One service a transport offers: ``name`` of ``kind`` (request, decide, reload).

    ``handler`` takes the request as a dict and returns the answer as a dict;
    ``rejected``, if given, hears of each request that cannot be decoded.
    """

    name: str
    kind: str
    codec: ServiceCodec
    handler: Callable[[dict[str, Any]], dict[str, Any]]
    rejected: Rejected | None
    guard: CallbackGuard

    def answer(self, request: Any, response: Callable[[], Any], caller: str | None = None) -> Any:
        """The filled response to ``request``; ``response()`` gives the middleware's empty one.

        A known ``caller`` joins the request as ``_caller`` (ROS 1; nothing checks it).
        """
        try:
            fields = self.codec.read_request(self.kind, request)
        except MessageError as e:  # the caller's mistake (a kind that is no value): said, not a bug
            self.reject(e, caller)
            return self.codec.fill_response(self.kind, response(), failure(self.kind, e))
        if caller is not None:
            fields["_caller"] = caller
        try:
            answer = self.handler(fields)
        except Exception as e:
            self.guard.failed(self.name, e)
            answer = failure(self.kind, e)
        return self.codec.fill_response(self.kind, response(), answer)

    def reject(self, error: Exception, caller: str | None) -> None:
        """Tell ``rejected`` of a request that cannot be decoded; a bug in it is counted, not raised
        (the caller still gets its answer)."""
        if self.rejected is None:
            return
        try:
            self.rejected(self.name, error, caller)
        except Exception as bug:
            self.guard.failed(self.name, bug)
