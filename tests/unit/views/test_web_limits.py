"""The live web view bounded under abuse: real sockets against a real uvicorn on 127.0.0.1.

Issue 28, finding 9: half-sent requests were never timed out (1,500 of 1,500 slowloris
connections stayed open), and at the descriptor limit the accept loop spun, logged 270k
lines in 5 s and left the Manager's process unable to open a file. Here: a request must
arrive whole within ``request_timeout`` (silent, partial, dripped a byte at a time, a second
request on a kept-alive connection, a control's body), an idle kept-alive connection closes
after ``idle_timeout``, an answer of 8 MB left unread is dropped after ``request_timeout``,
connections beyond ``max_connections`` wait unaccepted, streams beyond ``max_streams`` get
503, malformed requests are logged once, and -- in a process of its own with a low
RLIMIT_NOFILE -- the view backs off when ``accept`` fails, says so once, and leaves the
Manager descriptors to open its files while a thousand connections knock. Finding 10 (its
web half): a deeply nested control body is a 400 with a reason, not a 500 with a
RecursionError.
"""

from __future__ import annotations

import contextlib
import json
import logging
import resource
import selectors
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx
import pytest

from cosleec.errors import UserError
from cosleec.runtime import ConfigurationError, Manager, RuleSet, VirtualClock
from cosleec.views.web import WebView

from .attached import attach_web, close, web_url, web_view

TEXT = """def_start event E event F event A event B measure m : boolean def_end
rule_start
R1 when E then A within 10 seconds
R2 when F then not B within 30 seconds unless m
rule_end"""
GET = b"GET /state HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
PARTIAL = b"GET /state HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "


@contextmanager
def served(web: Any = 0) -> Iterator[Manager]:
    """A started Manager on a virtual clock, serving its web view; closed afterwards."""
    m = Manager(RuleSet.from_text(TEXT), clock=VirtualClock(), dispatch=False)
    try:
        attach_web(m, web).start(m)
        yield m
    finally:
        close(m)


def view(m: Manager) -> WebView:
    v = web_view(m)
    assert isinstance(v, WebView)
    return v


def port(m: Manager) -> int:
    url = web_url(m)
    assert url is not None
    return urlsplit(url).port or 0


def connect(m: Manager, data: bytes = b"") -> socket.socket:
    s = socket.create_connection(("127.0.0.1", port(m)), timeout=5)
    if data:
        s.sendall(data)
    return s


def ended(
    socks: list[socket.socket], timeout: float, drip: list[socket.socket] | None = None
) -> dict[int, float]:
    """When the server ended each connection (seconds from now), reading what it sent;
    ``drip`` connections are sent one more header byte every 0.2 s meanwhile."""
    sel = selectors.DefaultSelector()
    for s in socks:
        s.setblocking(False)
        sel.register(s, selectors.EVENT_READ)
    start = dripped = time.monotonic()
    done: dict[int, float] = {}
    try:
        while len(done) < len(socks) and time.monotonic() - start < timeout:
            for key, _ in sel.select(0.05):
                got = key.fileobj
                assert isinstance(got, socket.socket)
                try:
                    data = got.recv(1 << 16)
                except ConnectionResetError:
                    data = b""
                if not data:
                    done[got.fileno()] = time.monotonic() - start
                    sel.unregister(got)
            if time.monotonic() - dripped >= 0.2:
                dripped = time.monotonic()
                for s in drip or []:
                    if s.fileno() not in done:
                        with contextlib.suppress(OSError):
                            s.send(b"x")
    finally:
        sel.close()
    return done


def answer(s: socket.socket, timeout: float = 5) -> bytes:
    """Everything the server sends on ``s`` until it closes it (within ``timeout`` seconds)."""
    end = time.monotonic() + timeout
    data = b""
    with contextlib.suppress(ConnectionResetError):
        while (left := end - time.monotonic()) > 0:
            s.settimeout(left)
            try:
                chunk = s.recv(1 << 16)
            except TimeoutError:
                break
            if not chunk:
                return data
            data += chunk
    raise AssertionError(f"still open after {timeout} s, having sent {data[:200]!r}")


# ---------------------------------------------------------------------- timeouts


def test_half_sent_requests_are_closed_within_the_request_timeout() -> None:
    with served({"request_timeout": 1.0}) as m:
        silent = [connect(m) for _ in range(20)]
        partial = [connect(m, PARTIAL) for _ in range(60)]
        drip = [connect(m, PARTIAL) for _ in range(10)]  # a byte every 0.2 s: never idle, never done
        again = []  # a first request answered, then a second one half-sent on the same connection
        for _ in range(10):
            s = connect(m, GET)
            assert s.recv(64).startswith(b"HTTP/1.1 200 ")
            s.sendall(PARTIAL)
            again.append(s)
        socks = silent + partial + drip + again
        try:
            done = ended(socks, timeout=6, drip=drip)
            assert len(done) == len(socks), f"{len(socks) - len(done)} of {len(socks)} still open after 6 s"
            assert max(done.values()) < 3.5, sorted(done.values())[-5:]  # 1 s, and the test's own pace
            # and the view still serves
            assert httpx.get(f"{web_url(m)}state", timeout=5).status_code == 200
        finally:
            for s in socks:
                s.close()


def test_a_half_sent_request_is_told_408_and_an_early_one_is_not_cut() -> None:
    with served({"request_timeout": 1.5}) as m:
        with connect(m, PARTIAL) as s:
            started = time.monotonic()
            head = answer(s)
            took = time.monotonic() - started
        assert head.startswith(b"HTTP/1.1 408 "), head
        assert b"within 1.5 seconds" in head
        assert 1.2 < took < 3.5, took
        with connect(m, PARTIAL) as s:  # finished in time: answered
            time.sleep(0.8)
            s.sendall(b"1\r\nConnection: close\r\n\r\n")
            assert answer(s).startswith(b"HTTP/1.1 200 ")


def test_an_idle_kept_alive_connection_is_closed_after_the_idle_timeout() -> None:
    with served({"idle_timeout": 0.5, "request_timeout": 30}) as m, connect(m, GET) as s:
        assert s.recv(64).startswith(b"HTTP/1.1 200 ")
        done = ended([s], timeout=5)
        assert len(done) == 1 and 0.3 < max(done.values()) < 2.5, done


def test_an_answer_left_unread_is_dropped_after_the_request_timeout() -> None:
    n = 40_000  # a state of about 8 MB: more than the kernel's buffers hold for a reader that never reads
    text = (
        "def_start event E "
        + " ".join(f"event A{i}" for i in range(n))
        + " def_end rule_start "
        + " ".join(f"R{i} when E then A{i} within {i + 1} seconds" for i in range(n))
        + " rule_end"
    )
    m = Manager(RuleSet.from_text(text), clock=VirtualClock(), dispatch=False)
    try:
        attach_web(m, {"request_timeout": 1.0}).start(m)
        server = view(m)._server
        with socket.socket() as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1024)
            s.connect(("127.0.0.1", port(m)))
            s.sendall(GET)
            end = time.monotonic() + 10
            while not any(c.transport.get_write_buffer_size() for c in server.server_state.connections):
                assert time.monotonic() < end, "the answer never filled the buffers"
                time.sleep(0.05)
            started = time.monotonic()
            while server.server_state.connections:
                assert time.monotonic() - started < 3, "a reader that never reads still holds its connection"
                time.sleep(0.05)
    finally:
        close(m)


def test_a_half_sent_control_body_is_408_within_the_request_timeout() -> None:
    with served({"controls": True, "request_timeout": 1.0}) as m:
        with connect(
            m,
            b"POST /control/event HTTP/1.1\r\nHost: 127.0.0.1\r\ncontent-type: application/json\r\n"
            b"content-length: 100\r\n\r\n{",
        ) as s:
            started = time.monotonic()
            reply = answer(s)
            took = time.monotonic() - started
        assert reply.startswith(b"HTTP/1.1 408 "), reply
        assert b"the request's body did not arrive within 1 second" in reply
        assert took < 3.5, took
        assert m.stats["events"] == 0


# ---------------------------------------------------------------------- caps


def test_connections_beyond_max_connections_wait_unaccepted() -> None:
    with served({"max_connections": 10, "max_streams": 2, "request_timeout": 1.5}) as m:
        server = view(m)._server
        knocking = [connect(m, PARTIAL) for _ in range(40)]  # the kernel queues the rest
        try:
            time.sleep(0.5)
            assert len(server.server_state.connections) == 10
            late = connect(m, GET)  # served once the first ones have timed out
            started = time.monotonic()
            reply = answer(late, timeout=10)
            assert reply.startswith(b"HTTP/1.1 200 "), reply
            assert time.monotonic() - started > 1.0  # it waited: nothing was accepted meanwhile
            assert len(server.server_state.connections) <= 10
        finally:
            for s in knocking:
                s.close()


def test_streams_beyond_max_streams_are_refused_with_503_and_the_state_still_served() -> None:
    with served({"max_connections": 10, "max_streams": 3}) as m:
        streams = [connect(m, b"GET /events HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n") for _ in range(3)]
        try:
            for s in streams:
                assert s.recv(64).startswith(b"HTTP/1.1 200 ")
            extra = connect(m, b"GET /events HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
            reply = answer(extra)
            assert reply.startswith(b"HTTP/1.1 503 "), reply
            assert b"retry-after: " in reply.lower()
            assert "at most 3 live pages" in json.loads(reply.split(b"\r\n\r\n", 1)[1])["error"]
            assert httpx.get(f"{web_url(m)}state", timeout=5).status_code == 200
            streams.pop().close()  # one page closes: another may stream
            deadline = time.monotonic() + 5
            while True:
                again = connect(m, b"GET /events HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
                head = again.recv(64)
                if head.startswith(b"HTTP/1.1 200 ") or time.monotonic() > deadline:
                    break
                again.close()
                time.sleep(0.05)
            streams.append(again)
            assert head.startswith(b"HTTP/1.1 200 "), head
        finally:
            for s in streams:
                s.close()


@pytest.mark.parametrize(
    ("web", "message"),
    [
        ({"request_timeout": 0}, "request_timeout must be a number of seconds"),
        ({"request_timeout": float("nan")}, "request_timeout must be a number of seconds"),
        ({"request_timeout": True}, "request_timeout must be a number of seconds"),
        ({"idle_timeout": "5"}, "idle_timeout must be a number of seconds"),
        ({"idle_timeout": 1e9}, "idle_timeout must be a number of seconds"),
        ({"max_connections": 1}, "max_connections must be a whole number from 2"),
        ({"max_connections": 2.5}, "max_connections must be a whole number from 2"),
        ({"max_streams": 0}, "max_streams must be a whole number from 1"),
        ({"max_connections": 10, "max_streams": 10}, "max_streams must be less than max_connections"),
    ],
)
def test_bad_limits_are_a_user_error(web: Any, message: str) -> None:
    m = Manager.from_text(TEXT, dispatch=False)
    attached = attach_web(m, web)
    with pytest.raises(ConfigurationError, match=message):
        attached.start(m)
    close(m)


def test_more_connections_than_the_descriptor_limit_allows_is_refused_at_start() -> None:
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    m = Manager.from_text(TEXT, dispatch=False)
    attached = attach_web(m, {"max_connections": 1_000_000})
    with pytest.raises(UserError, match="file descriptors") as e:
        attached.start(m)
    assert e.value.hint is not None and "ulimit -n" in e.value.hint
    assert web_url(m) is None
    close(m)
    assert resource.getrlimit(resource.RLIMIT_NOFILE) == (soft, hard)


# ---------------------------------------------------------------------- the descriptor limit

SERVER = r"""
import json, logging, os, resource, sys
resource.setrlimit(resource.RLIMIT_NOFILE, (int(sys.argv[1]), resource.getrlimit(resource.RLIMIT_NOFILE)[1]))
logging.basicConfig(level=logging.WARNING, stream=sys.stderr, format="%(name)s: %(message)s")
from cosleec.runtime import Manager, RuleSet, VirtualClock
from cosleec.views import AttachedView
rules = sys.argv[2]
m = Manager(RuleSet.from_file(rules), clock=VirtualClock(), dispatch=False)
web = AttachedView(0)
web.start(m)
print(json.dumps({"url": web.url, "cap": getattr(web.view, "max_connections", None)}), flush=True)
held = []


def sockets():
    return sum(os.readlink(f"/proc/self/fd/{fd}").startswith("socket:")
               for fd in os.listdir("/proc/self/fd") if os.path.exists(f"/proc/self/fd/{fd}"))


for line in sys.stdin:
    cmd = line.strip()
    try:
        if cmd == "fill":  # the Manager's process uses up its descriptors (a leak, other work)
            while True:
                held.append(os.open("/dev/null", os.O_RDONLY))
        elif cmd == "free":
            for fd in held:
                os.close(fd)
            held.clear()
            print("freed", flush=True)
        elif cmd == "cpu":
            r = resource.getrusage(resource.RUSAGE_SELF)
            print(r.ru_utime + r.ru_stime, flush=True)
        elif cmd == "sockets":
            print(sockets(), flush=True)
        elif cmd == "reload":  # the Manager opens its files while the view is flooded
            m.reload(RuleSet.from_file(rules))
            files = [open(rules) for _ in range(20)]
            for f in files:
                f.close()
            print("reloaded", flush=True)
        elif cmd == "quit":
            break
    except OSError as e:
        if cmd == "fill":
            print(len(held), flush=True)
        else:
            print(f"error: {e}", flush=True)
web.close()
m.close()
"""


def knock(address: tuple[str, int], n: int, request: bytes) -> list[socket.socket]:
    """Open ``n`` connections without waiting for the server (it may not accept them), and
    send ``request`` on each one the kernel completed."""
    socks = []
    for _ in range(n):
        s = socket.socket()
        s.setblocking(False)
        s.connect_ex(address)
        socks.append(s)
    sel = selectors.DefaultSelector()
    for s in socks:
        sel.register(s, selectors.EVENT_WRITE)
    end = time.monotonic() + 2
    pending = len(socks)
    while pending and time.monotonic() < end:
        for key, _ in sel.select(0.1):
            ready = key.fileobj
            assert isinstance(ready, socket.socket)
            sel.unregister(ready)
            pending -= 1
            with contextlib.suppress(OSError):
                ready.send(request)
    sel.close()
    return socks


@pytest.fixture
def descriptors() -> Iterator[int]:
    """Room in this (the clients') process for a thousand sockets."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    want = 1000 + 200
    if hard != resource.RLIM_INFINITY and hard < want:
        pytest.skip(f"this process may open only {hard} files")
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, want), hard))
    try:
        yield 1000
    finally:
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))


def test_at_the_descriptor_limit_the_view_backs_off_says_so_once_and_leaves_the_manager_room(
    tmp_path: Path, descriptors: int
) -> None:
    rules = tmp_path / "rules.sleec"
    rules.write_text(TEXT)
    err = tmp_path / "stderr.txt"
    with err.open("wb") as stderr:
        proc = subprocess.Popen(
            [sys.executable, "-c", SERVER, "256", str(rules)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=stderr,
            text=True,
        )
    assert proc.stdin is not None and proc.stdout is not None
    socks: list[socket.socket] = []

    def ask(cmd: str) -> str:
        assert proc.stdin is not None and proc.stdout is not None
        proc.stdin.write(cmd + "\n")
        proc.stdin.flush()
        return proc.stdout.readline().strip()

    try:
        started = json.loads(proc.stdout.readline())
        address = ("127.0.0.1", urlsplit(started["url"]).port)
        cap = started["cap"]
        assert isinstance(cap, int) and 2 <= cap <= (256 - 10) // 2, cap

        # 1. the process has no descriptor left: the view cannot accept, and must not spin
        assert int(ask("fill")) > 200
        cpu = float(ask("cpu"))
        waiting = knock(address, 20, b"GET /state HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
        socks += waiting
        time.sleep(2)
        spent = float(ask("cpu")) - cpu
        assert spent < 0.5, f"{spent:.2f} s of CPU in 2 s while it could not accept"
        # 2. descriptors free again: the waiting browsers are served (the back-off is short)
        assert ask("free") == "freed"
        for s in waiting:
            s.setblocking(True)
            assert answer(s, timeout=10).startswith(b"HTTP/1.1 200 ")
        # 3. a thousand slowloris connections: the view holds at most its cap, the Manager opens files
        before = int(ask("sockets"))
        socks += knock(address, descriptors, PARTIAL)
        time.sleep(1)
        held = int(ask("sockets")) - before
        assert held <= cap, (held, cap)
        assert ask("reload") == "reloaded"
        assert ask("quit") == "" and proc.wait(30) == 0
    finally:
        for s in socks:
            s.close()
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    log = err.read_text(errors="replace").splitlines()
    accept = [line for line in log if "cannot accept" in line]
    assert len(accept) == 1, log[:20]
    assert "Too many open files" in accept[0]
    assert len(log) <= 5, f"{len(log)} lines logged: {log[:10]}"


def test_malformed_requests_are_logged_once_per_kind(caplog: pytest.LogCaptureFixture) -> None:
    with served() as m:
        caplog.set_level(logging.WARNING)
        for _ in range(30):
            with connect(m, b"NOT HTTP AT ALL\r\n\r\n") as s:
                assert answer(s).startswith(b"HTTP/1.1 400 ")
        invalid = [r for r in caplog.records if "Invalid HTTP request" in r.getMessage()]
        assert len(invalid) == 1, len(invalid)


# ---------------------------------------------------------------------- finding 10: deep bodies


def test_a_deeply_nested_control_body_is_a_400_with_the_reason() -> None:
    with served({"controls": True}) as m:
        deep = b'{"event": "E", "x": ' + b"[" * 20_000 + b"]" * 20_000 + b"}"  # 40 KB
        assert len(deep) < 64 * 1024
        r = httpx.post(
            f"{web_url(m)}control/event", content=deep, headers={"content-type": "application/json"}
        )
        assert r.status_code == 400, r.text
        assert "nested" in r.json()["error"] and "at most" in r.json()["error"]
        for depth, status in ((4, 200), (5, 400)):  # the bound: 4 levels, {"event": ..., "x": [[[1]]]}
            body = b'{"event": "E", "x": ' + b"[" * (depth - 1) + b"1" + b"]" * (depth - 1) + b"}"
            r = httpx.post(
                f"{web_url(m)}control/event", content=body, headers={"content-type": "application/json"}
            )
            assert r.status_code == status, (depth, r.text)
        # a string full of brackets is not nesting
        flat = json.dumps({"event": "E", "note": "[" * 20_000}).encode()
        r = httpx.post(
            f"{web_url(m)}control/event", content=flat, headers={"content-type": "application/json"}
        )
        assert r.status_code == 200, r.text
        assert m.stats["events"] == 2
