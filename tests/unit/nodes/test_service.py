"""How both ROS transports answer a call of a service they offer
(:class:`cosleec.ros.service.OfferedService`), alone: the handler's answer, the failure form
when the handler raises or the request cannot be decoded, the node told of the latter, and
the caller (ROS 1) joining the request. Never a call without an answer."""

from __future__ import annotations

from typing import Any

import pytest

from cosleec.nodes import MessageError
from cosleec.ros.guard import CallbackGuard
from cosleec.ros.service import OfferedService


class Codec:
    """A service codec stand-in: a request is a dict (``bad`` in it: undecodable); a response is a dict."""

    def read_request(self, kind: str, req: Any) -> dict[str, Any]:
        if "bad" in req:
            raise MessageError(f"cannot read the {kind}: {req['bad']}")
        return dict(req)

    def fill_response(self, kind: str, resp: dict[str, Any], answer: dict[str, Any]) -> dict[str, Any]:
        resp.update(answer)
        return resp


CODEC: Any = Codec()  # as the wire's ServiceCodec


class Calls:
    """Records what the service does: handler calls, rejections, empty responses handed out."""

    def __init__(
        self, answer: dict[str, Any] | Exception | None = None, rejected: Exception | None = None
    ) -> None:
        self.answer = answer if answer is not None else {"permitted": True, "rules": [], "reason": "ok"}
        self.reject_with = rejected
        self.handled: list[dict[str, Any]] = []
        self.rejected: list[tuple[str, str, str | None]] = []
        self.responses = 0

    def handler(self, fields: dict[str, Any]) -> dict[str, Any]:
        self.handled.append(fields)
        if isinstance(self.answer, Exception):
            raise self.answer
        return self.answer

    def on_rejected(self, name: str, error: Exception, caller: str | None) -> None:
        self.rejected.append((name, str(error), caller))
        if self.reject_with is not None:
            raise self.reject_with

    def response(self) -> dict[str, Any]:
        self.responses += 1
        return {}


def service(calls: Calls, guard: CallbackGuard, *, rejected: bool = True) -> OfferedService:
    return OfferedService(
        "~/request",
        "request",
        CODEC,
        calls.handler,
        calls.on_rejected if rejected else None,
        guard,
    )


def test_a_request_is_answered_by_the_handler_into_one_response() -> None:
    calls, guard = Calls(), CallbackGuard()
    got = service(calls, guard).answer({"event": "Open", "source": "t"}, calls.response)
    assert got == {"permitted": True, "rules": [], "reason": "ok"}
    assert calls.handled == [{"event": "Open", "source": "t"}]  # no _caller: none is known
    assert calls.responses == 1 and guard.errors == 0 and calls.rejected == []


def test_a_known_caller_joins_the_request() -> None:
    calls = Calls()
    service(calls, CallbackGuard()).answer({"event": "Open"}, calls.response, "/robot1_task")
    assert calls.handled == [{"event": "Open", "_caller": "/robot1_task"}]


def test_a_handler_that_raises_is_counted_and_the_caller_is_refused() -> None:
    calls, guard = Calls(answer=RuntimeError("boom")), CallbackGuard()
    got = service(calls, guard).answer({"event": "Open"}, calls.response)
    assert got == {
        "permitted": False,
        "rules": [],
        "reason": "the Manager could not decide: RuntimeError: boom",
    }
    assert guard.errors == 1 and calls.responses == 1 and calls.rejected == []


@pytest.mark.parametrize("caller", [None, "/intruder"])
def test_a_request_that_cannot_be_decoded_is_rejected_refused_and_not_handled(caller: str | None) -> None:
    calls, guard = Calls(), CallbackGuard()
    got = service(calls, guard).answer({"bad": "kind 9"}, calls.response, caller)
    assert got["permitted"] is False and got["reason"].endswith(
        "MessageError: cannot read the request: kind 9"
    )
    assert calls.rejected == [("~/request", "cannot read the request: kind 9", caller)]
    assert calls.handled == [] and guard.errors == 0 and calls.responses == 1


def test_without_a_rejected_callback_an_undecodable_request_is_still_answered() -> None:
    calls, guard = Calls(), CallbackGuard()
    got = service(calls, guard, rejected=False).answer({"bad": "x"}, calls.response)
    assert got["permitted"] is False and calls.rejected == [] and guard.errors == 0


def test_a_rejected_callback_that_raises_is_counted_and_the_caller_still_answered() -> None:
    calls, guard = Calls(rejected=ValueError("bug")), CallbackGuard()
    got = service(calls, guard).answer({"bad": "x"}, calls.response)
    assert got["permitted"] is False and len(calls.rejected) == 1 and guard.errors == 1


@pytest.mark.parametrize(
    ("kind", "failed"),
    [
        ("decide", {"accepted": False, "error": "RuntimeError: boom", "decisions": []}),
        ("reload", {"success": False, "message": "RuntimeError: boom"}),
    ],
)
def test_each_kind_fails_in_its_own_form(kind: str, failed: dict[str, Any]) -> None:
    calls, guard = Calls(answer=RuntimeError("boom")), CallbackGuard()
    s = OfferedService("~/" + kind, kind, CODEC, calls.handler, None, guard)
    assert s.answer({}, calls.response) == failed
