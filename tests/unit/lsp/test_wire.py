"""``cosleec lsp``'s framing under abuse: the real server as a subprocess, bytes written by hand.

Issue 28, finding 10: ``Content-Length: 99999999999`` made the server allocate the body at
once and exit 70 with ``internal error: MemoryError``. Here every bad message gets a
JSON-RPC error (with the request's id when it can be read, ``null`` when not) and the server
keeps serving: a length over ``--max-message`` (refused unread, its bytes skipped), a
message nested deeper than ``--max-depth``, a body that is not JSON, a request whose params
are of the wrong shape, a header line without end or a message without ``Content-Length``.
"""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import pytest

from cosleec.lsp.wire import nesting

INITIALIZE = {"jsonrpc": "2.0", "id": 100, "method": "initialize", "params": {"capabilities": {}}}


def frame(body: bytes, length: int | None = None) -> bytes:
    n = len(body) if length is None else length
    return b"Content-Length: %d\r\n\r\n" % n + body


class Raw:
    """``cosleec lsp`` in a subprocess; messages written and read as bytes."""

    def __init__(self, tmp: Path, *args: str) -> None:
        self.err_path = tmp / "stderr.txt"
        self._err = self.err_path.open("wb")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "cosleec.cli.main", "lsp", *args],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._err,
        )
        self.messages: queue.Queue[dict[str, Any] | None] = queue.Queue()
        assert self.proc.stdout is not None
        self._reader = threading.Thread(target=self._read, args=(self.proc.stdout,), daemon=True)
        self._reader.start()

    def _read(self, out: IO[bytes]) -> None:
        while True:
            length = None
            while (line := out.readline()) not in (b"\r\n", b""):
                if line.lower().startswith(b"content-length:"):
                    length = int(line.split(b":")[1])
            if not line or length is None:
                self.messages.put(None)
                return
            self.messages.put(json.loads(out.read(length)))

    def send(self, data: bytes) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(data)
        self.proc.stdin.flush()

    def request(self, message: dict[str, Any]) -> None:
        self.send(frame(json.dumps(message).encode()))

    def next(self, timeout: float = 10) -> dict[str, Any]:
        """The next message the server sends (a notification or an answer)."""
        message = self.messages.get(timeout=timeout)
        assert message is not None, f"the server closed its output; stderr: {self.stderr()}"
        return message

    def answer(self, timeout: float = 10) -> dict[str, Any]:
        """The next answer (notifications the server sends meanwhile are skipped)."""
        while True:
            message = self.next(timeout)
            if "method" not in message:
                return message

    def stop(self) -> int:
        """Shut the server down as an editor does; its exit status."""
        self.request({"jsonrpc": "2.0", "id": 999, "method": "shutdown"})
        assert self.answer()["id"] == 999
        self.request({"jsonrpc": "2.0", "method": "exit"})
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        return self.proc.wait(20)

    def stderr(self) -> str:
        self._err.flush()
        return self.err_path.read_text(errors="replace")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self._err.close()


@pytest.fixture
def raw(tmp_path: Path) -> Iterator[Any]:
    made: list[Raw] = []

    def start(*args: str) -> Raw:
        made.append(Raw(tmp_path, *args))
        return made[-1]

    yield start
    for r in made:
        r.close()


def invalid(answer: dict[str, Any], msg_id: int | None, code: int, *words: str) -> None:
    assert answer.get("jsonrpc") == "2.0" and "id" in answer and answer["id"] == msg_id, answer
    assert answer["error"]["code"] == code, answer
    for word in words:
        assert word in answer["error"]["message"], answer


def test_an_absurd_content_length_is_refused_unread_answered_and_the_server_exits_cleanly(raw: Any) -> None:
    server = raw()
    server.send(b"Content-Length: 99999999999\r\n\r\n{}")
    invalid(server.answer(), None, -32600, "99999999999 bytes", "at most 16777216", "--max-message")
    assert server.proc.stdin is not None
    server.proc.stdin.close()  # the editor goes away in the middle of the message it announced
    assert server.proc.wait(20) == 0
    log = server.stderr().splitlines()
    assert len(log) == 1 and "99999999999" in log[0], log
    assert "MemoryError" not in server.stderr() and "internal error" not in server.stderr()


def test_a_message_over_max_message_is_skipped_and_the_next_one_served(raw: Any) -> None:
    server = raw("--max-message", "1000")
    junk = json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize", "pad": "x" * 4000}).encode()
    server.send(frame(junk))
    invalid(server.answer(), None, -32600, f"{len(junk)} bytes", "at most 1000")
    server.request(INITIALIZE)  # the bytes of the refused message were skipped: in step again
    assert server.answer()["result"]["serverInfo"]["name"] == "cosleec"
    hover = {"jsonrpc": "2.0", "id": 2, "method": "textDocument/hover", "pad": ""}
    padded = json.dumps(hover).encode()
    exactly = json.dumps({**hover, "pad": "x" * (1000 - len(padded))}).encode()
    assert len(exactly) == 1000
    server.send(frame(exactly))  # at the bound: read (and refused by pygls for its missing params)
    invalid(server.answer(), 2, -32602)
    server.send(frame(exactly.replace(b'"pad": "', b'"pad": "x')))  # one byte over
    invalid(server.answer(), None, -32600, "1001 bytes", "at most 1000")
    assert server.stop() == 0


def test_a_message_nested_too_deeply_is_answered_by_the_protocol(raw: Any) -> None:
    server = raw()
    server.request(INITIALIZE)
    assert "result" in server.answer()
    deep = {"jsonrpc": "2.0", "id": 5, "method": "textDocument/hover", "params": {"x": []}}
    body = json.dumps(deep).replace("[]", "[" * 200 + "]" * 200).encode()
    server.send(frame(body))  # deeper than the bound, shallow enough to find its id
    invalid(server.answer(), 5, -32600, "nested 202 levels deep", "at most 100", "--max-depth")
    at_bound = json.dumps(deep).replace("[]", "[" * 98 + "]" * 98).encode()
    server.send(frame(at_bound))  # 100 levels: read (then refused for params that are no hover's)
    invalid(server.answer(), 5, -32602, "Invalid Params", "@ $.params.position")
    server.send(frame(at_bound.replace(b"[", b"[[", 1).replace(b"]", b"]]", 1)))  # 101
    invalid(server.answer(), 5, -32600, "nested 101 levels deep")
    server.send(frame(b"[" * 100_000 + b"]" * 100_000))  # deeper than Python's parser goes
    invalid(server.answer(), None, -32600, "nested 100000 levels deep")
    # brackets in strings are text, not nesting
    text = "[" * 5000
    server.request(
        {
            "jsonrpc": "2.0",
            "method": "textDocument/didOpen",
            "params": {
                "textDocument": {"uri": "file:///a.sleec", "languageId": "sleec", "version": 1, "text": text}
            },
        }
    )
    published = server.next()
    assert published["method"] == "textDocument/publishDiagnostics", published
    assert published["params"]["uri"] == "file:///a.sleec"
    assert server.stop() == 0


def test_a_deeper_limit_can_be_given(raw: Any) -> None:
    server = raw("--max-depth", "300")
    body = json.dumps(
        {"jsonrpc": "2.0", "id": 5, "method": "initialize", "params": {"capabilities": {}, "x": []}}
    )
    server.send(frame(body.replace("[]", "[" * 200 + "]" * 200).encode()))
    assert "result" in server.answer()
    assert server.stop() == 0


def test_bad_json_and_bad_params_are_answered_with_the_protocols_codes(raw: Any) -> None:
    server = raw()
    server.send(frame(b'{"jsonrpc": "2.0", "id": 1, "method": '))
    invalid(server.answer(), None, -32700, "not JSON")
    server.request({"jsonrpc": "2.0", "id": 3, "method": "textDocument/hover", "params": {"textDocument": 5}})
    invalid(server.answer(), 3, -32602)
    server.send(frame(b"[1, 2]"))
    invalid(server.answer(), None, -32600, "a JSON object")
    server.request(INITIALIZE)
    assert "result" in server.answer()
    assert server.stop() == 0


def test_a_header_line_without_end_or_a_message_without_length_is_answered_and_skipped(raw: Any) -> None:
    server = raw()
    server.send(b"X-Junk: " + b"x" * 100_000 + b"\r\n\r\n")  # a header line of 100 KB
    invalid(server.answer(), None, -32600, "header line longer than")
    server.send(b"Content-Type: application/json\r\n\r\n")  # no Content-Length
    invalid(server.answer(), None, -32600, "no Content-Length")
    server.send(b"Content-Length: 12x\r\n\r\n")
    invalid(server.answer(), None, -32600, "Content-Length")
    server.request(INITIALIZE)
    assert "result" in server.answer()
    assert server.stop() == 0
    assert "Traceback" not in server.stderr()


def depth(value: Any) -> int:
    """The nesting of a parsed JSON value (the reference :func:`nesting` must agree with)."""
    if isinstance(value, dict):
        return 1 + max(map(depth, value.values()), default=0)
    if isinstance(value, list):
        return 1 + max(map(depth, value), default=0)
    return 0


@pytest.mark.parametrize(
    "value",
    [
        {},
        [],
        "[[[",
        {"a": '\\"[[[', "b": [["]]"]]},  # a backslash, then a quote, inside a string
        ["\\", [[[{}]]]],  # a string that ends in a backslash
        {"x": '\\\\"{{{'},
        [[1, [2, [3, {"k": [4]}]]], "}}}"],
        {"text": "[" * 500, "deep": [[[[[]]]]]},
    ],
)
def test_nesting_counts_brackets_outside_strings(value: Any) -> None:
    body = json.dumps(value).encode()
    assert nesting(body) == depth(value), body
    assert nesting(body, at_most=100) <= 100 or depth(value) > 100
