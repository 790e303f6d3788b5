"""The language server's framing: messages read from stdin, bounded, and every bad one answered.

pygls's own reader (``pygls.io_.run_async``) reads a ``Content-Length`` in one call: a client
that announced 99,999,999,999 bytes made it allocate them, and the server died of a
``MemoryError``; a message nested thousands of levels deep, not JSON, or of the wrong shape
was logged and left unanswered, so the editor waited for its answer forever. This reader
(used by :meth:`SleecServer.start_io <cosleec.lsp.server.SleecServer.start_io>`) reads the
same frames with bounds and answers every message it cannot use by the protocol: a JSON-RPC
error with the request's id (``null`` when no id can be read; nothing for a notification)
and one line in the log, and then reads the next message.

- A header line is at most :data:`MAX_HEADER_LINE` bytes; a longer one, a missing or
  malformed ``Content-Length``: Invalid Request (-32600), the headers skipped.
- A body longer than ``max_message`` bytes (:data:`MAX_MESSAGE`; ``cosleec lsp
  --max-message``): Invalid Request, answered before a byte of it is read; its bytes are
  then read and dropped in pieces of :data:`SKIP_CHUNK`, so the next message is in step.
- A body nested deeper than ``max_depth`` (:data:`MAX_DEPTH`; ``--max-depth``): Invalid
  Request. The depth is counted without parsing (:func:`nesting`: linear, no recursion).
- Not JSON: Parse Error (-32700); not a JSON-RPC message: Invalid Request; params of the
  wrong shape: pygls's Invalid Params (-32602), now with the request's id.
"""

from __future__ import annotations

import asyncio
import json
import logging
import threading
from collections.abc import Awaitable, Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from itertools import accumulate
from typing import BinaryIO

import cattrs
from pygls.exceptions import JsonRpcException
from pygls.protocol import JsonRPCProtocol

from cosleec.errors import ConfigurationError, show

log = logging.getLogger("cosleec.lsp")

#: the largest message body read (bytes): 16 MiB, 200 times the largest file of the SLEEC corpus;
#: the worst body of that size (all brackets) takes about 2.5 s to measure (:func:`nesting`)
MAX_MESSAGE = 16 * 1024 * 1024
#: how deep a message may nest arrays and objects (LSP's own messages nest about ten levels)
MAX_DEPTH = 100
#: the longest header line (bytes); LSP has two headers, each a few dozen bytes
MAX_HEADER_LINE = 4096
#: a refused body is read and dropped this many bytes at a time
SKIP_CHUNK = 1 << 20

PARSE_ERROR = -32700
INVALID_REQUEST = -32600

_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")
_STEP = [0] * 256
_STEP[ord("[")] = _STEP[ord("{")] = 1
_STEP[ord("]")] = _STEP[ord("}")] = -1


@dataclass(frozen=True)
class Limits:
    """The bounds of what the server reads (``cosleec lsp --max-message``, ``--max-depth``)."""

    max_message: int = MAX_MESSAGE
    max_depth: int = MAX_DEPTH

    def __post_init__(self) -> None:
        for name in ("max_message", "max_depth"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigurationError(
                    f"the language server's {name} must be a whole number from 1, not {show(value)}"
                )


def nesting(body: bytes, at_most: int = 0) -> int:
    """How deep the JSON text ``body`` nests arrays and objects; brackets in strings are text.

    Linear and without recursion, whatever the depth (a parser recurses). With ``at_most``,
    a body with at most that many opening brackets (so no deeper) is answered at once with
    their count, an upper bound of its depth. Escapes are removed first (``\\\\``, then
    ``\\"``), so every quote left delimits a string; a body that is not JSON gets some count,
    and the parser then refuses it.
    """
    opening = body.count(b"[") + body.count(b"{")
    if opening <= at_most:
        return opening
    plain = body.replace(b"\\\\", b"").replace(b'\\"', b"")
    brackets = b"".join(plain.split(b'"')[::2]).translate(None, _NOT_BRACKETS)
    return max(accumulate(map(_STEP.__getitem__, brackets)), default=0)


class StdinReader:
    """Reads the client's stdin on ``executor``'s threads (a blocking pipe), a bounded amount a call."""

    def __init__(self, stdin: BinaryIO, executor: Executor | None) -> None:
        self.stdin = stdin
        self.executor = executor

    def readline(self, limit: int) -> Awaitable[bytes]:
        """A line, or its first ``limit`` bytes (no newline at the end then); b'' at the end."""
        return asyncio.get_running_loop().run_in_executor(self.executor, self.stdin.readline, limit)

    def read(self, n: int) -> Awaitable[bytes]:
        """``n`` bytes, fewer only at the end of the input."""
        return asyncio.get_running_loop().run_in_executor(self.executor, self.stdin.read, n)

    async def skip(self, n: int) -> bool:
        """Read and drop ``n`` bytes, :data:`SKIP_CHUNK` at a time; False if the input ended first."""
        while n > 0:
            chunk = await self.read(min(n, SKIP_CHUNK))
            if not chunk:
                return False
            n -= len(chunk)
        return True


async def serve(
    reader: StdinReader, protocol: JsonRPCProtocol, stop: threading.Event, limits: Limits
) -> None:
    """Read messages and hand them to ``protocol`` until the input ends or ``stop`` is set."""
    while not stop.is_set():
        length = await _headers(reader)
        if length is None:
            return  # the client closed its end
        if isinstance(length, str):
            refuse(protocol, None, INVALID_REQUEST, length)
            continue
        if length > limits.max_message:
            refuse(
                protocol,
                None,
                INVALID_REQUEST,
                f"a message of {length} bytes: cosleec lsp reads messages of at most "
                f"{limits.max_message} bytes (--max-message); its bytes are skipped",
            )
            if not await reader.skip(length):
                return
            continue
        body = await reader.read(length)
        if len(body) < length:
            return  # the input ended inside the message
        handle(protocol, body, limits)


async def _headers(reader: StdinReader) -> int | str | None:
    """The next message's ``Content-Length``; what is wrong with its headers; None at the end."""
    length: int | None = None
    problem: str | None = None
    seen = False
    while True:
        line = await reader.readline(MAX_HEADER_LINE)
        if not line:
            return None
        if not line.endswith(b"\n"):  # too long: drop the rest of it
            problem = problem or f"a header line longer than {MAX_HEADER_LINE} bytes"
            while line and not line.endswith(b"\n"):
                line = await reader.readline(MAX_HEADER_LINE)
            seen = True
            continue
        text = line.strip()
        if not text:
            if problem is not None:
                return problem
            if length is not None:
                return length
            if seen:
                return "a message with no Content-Length header"
            continue  # a blank line between messages
        seen = True
        name, _, value = text.partition(b":")
        if name.strip().lower() == b"content-length":
            value = value.strip()
            if value.isdigit() and len(value) <= 20:
                length = int(value)
            else:
                problem = problem or f"a Content-Length that is not a number of bytes: {value[:40]!r}"


def handle(protocol: JsonRPCProtocol, body: bytes, limits: Limits) -> None:
    """Hand one message to ``protocol``, or answer why it cannot be used (never raises)."""
    depth = nesting(body, limits.max_depth)
    if depth > limits.max_depth:
        refuse_body(
            protocol,
            body,
            INVALID_REQUEST,
            f"the message is nested {depth} levels deep: cosleec lsp reads at most "
            f"{limits.max_depth} (--max-depth)",
        )
        return
    try:
        message = json.loads(body, object_hook=protocol.structure_message)
    except JsonRpcException as e:  # the shape of a known method's params is wrong
        refuse_body(protocol, body, e.code, _why(e))
        return
    except (ValueError, RecursionError) as e:  # not UTF-8, not JSON
        refuse(protocol, None, PARSE_ERROR, f"the message is not JSON: {e}")
        return
    if not hasattr(message, "jsonrpc"):
        refuse_body(protocol, body, INVALID_REQUEST, 'a message is a JSON object with "jsonrpc": "2.0"')
        return
    _guarded(protocol, body, lambda: protocol.handle_message(message))


def _why(e: JsonRpcException) -> str:
    """pygls's refusal, with what cattrs found wrong (``... @ $.params.position``) when it says."""
    cause = e.__cause__
    if isinstance(cause, cattrs.BaseValidationError):
        found = cattrs.transform_error(cause, path="$")
        return (
            f"{e.message}: "
            + "; ".join(found[:3])
            + (f" (and {len(found) - 3} more)" if len(found) > 3 else "")
        )
    return e.message


def _guarded(protocol: JsonRPCProtocol, body: bytes, run: Callable[[], object]) -> None:
    """Run ``run``; an error escaping pygls is logged and, for a request, answered."""
    try:
        run()
    except Exception as e:  # pygls answers a handler's errors itself: this is pygls's own bug
        log.exception("cannot handle a message")
        refuse_body(protocol, body, -32603, f"internal error: {type(e).__name__}: {e}")


def refuse_body(protocol: JsonRPCProtocol, body: bytes, code: int, message: str) -> None:
    """Answer the message ``body`` with an error: with its id; not at all if it is a notification."""
    is_request, msg_id = identify(body)
    if is_request:
        refuse(protocol, msg_id, code, message)
    else:
        log.warning("ignored a notification: %s", message)


def identify(body: bytes) -> tuple[bool, int | str | None]:
    """Whether ``body`` is a request (not a notification), and its id (None if it cannot be read)."""
    try:
        data = json.loads(body)
    except (ValueError, RecursionError, MemoryError):
        return True, None
    if not isinstance(data, dict):
        return True, None
    msg_id = data.get("id")
    if "id" not in data and "method" in data:
        return False, None
    if isinstance(msg_id, bool) or not isinstance(msg_id, int | str):
        return True, None
    return True, msg_id


def refuse(protocol: JsonRPCProtocol, msg_id: int | str | None, code: int, message: str) -> None:
    """Send the JSON-RPC error ``code`` for ``msg_id`` (``null`` when it is not known), and log it."""
    log.warning("refused a message: %s", message)
    body = json.dumps({"jsonrpc": "2.0", "id": msg_id, "error": {"code": code, "message": message}})
    head = f"Content-Length: {len(body)}\r\nContent-Type: {protocol.CONTENT_TYPE}; charset={protocol.CHARSET}\r\n\r\n"
    if protocol.writer is not None:  # stdout: pygls's StdoutWriter writes and flushes at once
        protocol.writer.write((head + body).encode(protocol.CHARSET))
