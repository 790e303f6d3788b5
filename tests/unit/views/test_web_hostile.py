"""The live web view under attack: real requests against a real uvicorn on 127.0.0.1.

Security: a forwarded-for header cannot make a client local, a ``Host`` header must be
an address with a port and nothing after it, methods other than GET (and the controls'
POST) are refused, another origin's form or fetch cannot send an event even in the real
Chromium, markup in a file name is shown as text, a control request's body is bounded.
Robustness: the Manager wakes the server only when a browser waits for a change, 200
browsers share one state per change, a view closed twice or before its Manager closes,
stalled and half-open clients do not hold ``close()`` up, 50 starts and closes leak no
thread or socket, a port in use leaves nothing behind, a browser that drops mid-stream is
forgotten, a view that raises cannot stop enforcement. Correctness: fulfilled obligations
go, a refused obligation is a listed violation, a reload shows the new rules.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import json
import os
import re
import selectors
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx
import pytest

from cosleec.demo import rules_path
from cosleec.errors import UserError
from cosleec.runtime import Manager, RuleSet, VirtualClock
from cosleec.testing import CHROMIUM, CHROMIUM_ARGS
from cosleec.views import live as live_module
from cosleec.views.web import MAX_BODY, SHUTDOWN_S, WebView

from .attached import attach_web, close, web_url, web_view

ARGS = list(CHROMIUM_ARGS)
TEXT = """def_start event E event F event A event B measure m : boolean def_end
rule_start
R1 when E then A within 10 seconds
R2 when F then not B within 30 seconds unless m
rule_end"""


JSON = {"content-type": "application/json"}


@contextmanager
def served(rules: str | Path = TEXT, web: Any = 0, **options: Any) -> Iterator[Manager]:
    """A started Manager on a virtual clock, serving its web view; closed afterwards."""
    ruleset = RuleSet.from_file(rules) if isinstance(rules, Path) else RuleSet.from_text(rules)
    m = Manager(ruleset, clock=options.pop("clock", VirtualClock()), dispatch=False, **options)
    try:
        attach_web(m, web).start(m)
        yield m
    finally:
        close(m)


def view(m: Manager) -> WebView:
    v = web_view(m)
    assert isinstance(v, WebView)
    return v


def url(m: Manager) -> str:
    u = web_url(m)
    assert u is not None
    return u


def port(m: Manager) -> int:
    return urlsplit(url(m)).port or 0


def state(m: Manager) -> dict[str, Any]:
    r = httpx.get(url(m) + "state", timeout=5)
    assert r.status_code == 200
    return r.json()  # type: ignore[no-any-return]


def web_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "cosleec-web"]


def refused(p: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", p), timeout=1).close()
    except ConnectionRefusedError:
        return True
    return False


def wait(cond: Callable[[], object], timeout: float = 5) -> None:
    end = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.01)


def on_loop(m: Manager, fn: Callable[[], Any]) -> Any:
    """Run ``fn`` on the server's loop and return what it returns: everything queued before has run."""
    loop = view(m)._hub.loop
    assert loop is not None

    async def call() -> Any:
        return fn()

    return asyncio.run_coroutine_threadsafe(call(), loop).result(5)


_MESSAGE = re.compile(rb"event: (\w+)\r?\ndata: ([^\r\n]*)\r?\n")


class Browser:
    """A browser's ``/events`` stream, read by hand from a raw socket (HTTP/1.0: no chunks)."""

    def __init__(self, m: Manager, *, rcvbuf: int | None = None) -> None:
        self.sock = socket.socket()
        if rcvbuf is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.connect(("127.0.0.1", port(m)))
        self.sock.sendall(b"GET /events HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
        self.data = b""

    def messages(self, kind: str = "state") -> list[dict[str, Any]]:
        return [json.loads(d) for k, d in _MESSAGE.findall(self.data) if k.decode() == kind]

    def close(self, *, reset: bool = False) -> None:
        if reset:  # an abrupt end: RST, not FIN
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        self.sock.close()


def pump(browsers: list[Browser], until: Callable[[], bool], timeout: float = 10) -> None:
    """Read every browser's stream until ``until()`` holds."""
    sel = selectors.DefaultSelector()
    for b in browsers:
        sel.register(b.sock, selectors.EVENT_READ, b)
    end = time.monotonic() + timeout
    try:
        while not until():
            assert time.monotonic() < end, "timed out"
            for key, _ in sel.select(0.05):
                key.data.data += key.fileobj.recv(1 << 16)  # type: ignore[union-attr]
    finally:
        sel.close()


# ---------------------------------------------------------------------- security


def test_a_forwarded_for_header_does_not_decide_who_the_client_is() -> None:
    # uvicorn's default (proxy_headers on, trusting 127.0.0.1) would make this client 10.0.0.5: 403
    spoof = {"x-forwarded-for": "10.0.0.5", "forwarded": "for=10.0.0.5", "x-real-ip": "10.0.0.5"}
    with served() as m:
        assert httpx.get(url(m) + "state", headers=spoof).status_code == 200

        async def remote_claiming_loopback() -> int:
            transport = httpx.ASGITransport(app=view(m).app, client=("10.0.0.5", 40000))
            async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1:8765") as c:
                r = await c.get(
                    "/state", headers={"x-forwarded-for": "127.0.0.1", "forwarded": "for=127.0.0.1"}
                )
                return r.status_code

        assert asyncio.run(remote_claiming_loopback()) == 403


@pytest.mark.parametrize(
    ("host", "status"),
    [
        ("127.0.0.1", 200),
        ("127.0.0.1:8765", 200),
        ("[::1]:8765", 200),
        ("[::ffff:127.0.0.1]:80", 200),
        ("localhost:evil", 403),  # the port is not a port
        ("10.0.0.1:80@evil.example", 403),  # what a URL parser reads as evil.example
        ("127.0.0.1:8765 evil.example", 403),
        ("[::1]evil.example", 403),
        ("evil.example:80:127.0.0.1", 403),
        ("127.1", 403),  # not how an address is written in a Host header: fail closed
    ],
)
def test_a_host_header_is_an_address_and_a_port_and_nothing_else(host: str, status: int) -> None:
    with served() as m, socket.create_connection(("127.0.0.1", port(m)), timeout=5) as s:
        s.sendall(f"GET /state HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode())
        head = s.recv(64)
    assert head.startswith(f"HTTP/1.1 {status} ".encode()), head


def test_methods_other_than_get_are_refused_and_nothing_allows_other_origins() -> None:
    with served() as m, httpx.Client(base_url=url(m).rstrip("/")) as c:
        for path in ("/", "/state", "/events", "/static/web.js"):
            for method in ("POST", "PUT", "DELETE", "PATCH", "OPTIONS", "TRACE"):
                r = c.request(method, path, headers={"origin": "http://evil.example"})
                assert r.status_code == 405, (method, path)
                assert not any(h.startswith("access-control-") for h in r.headers), r.headers
                assert r.headers["x-frame-options"] == "DENY"
        assert c.head("/").status_code == 200
        assert c.get("/control/event").status_code == 405
        r = c.options("/control/event", headers={"access-control-request-method": "POST"})
        assert r.status_code == 405 and "access-control-allow-origin" not in r.headers
        for path in ("/static/../web.py", "/static/%2e%2e/web.py", "/static/live.py", "/%ff"):
            assert c.get(path).status_code == 404, path
        assert m.stats["events"] == 0


def test_a_control_body_is_bounded_and_a_huge_one_is_refused_before_it_is_read() -> None:
    with served(web={"controls": True}) as m:
        with socket.create_connection(("127.0.0.1", port(m)), timeout=3) as s:
            s.sendall(  # announces 100 MB and sends none of it: answered at once
                b"POST /control/event HTTP/1.1\r\nHost: 127.0.0.1\r\ncontent-type: application/json\r\n"
                b"content-length: 100000000\r\n\r\n"
            )
            assert s.recv(64).startswith(b"HTTP/1.1 413 ")

        def chunks(n: int) -> Iterator[bytes]:  # no length: sent chunked
            yield b'{"event": "E", "pad": "'
            yield b" " * (n - 25)
            yield b'"}'

        big = httpx.post(url(m) + "control/event", content=chunks(MAX_BODY + 1), headers=JSON)
        assert big.status_code == 413 and "at most 65536 bytes" in big.json()["error"]
        assert httpx.post(url(m) + "control/event", content=b"", headers=JSON).status_code == 400
        ok = httpx.post(url(m) + "control/event", content=chunks(MAX_BODY), headers=JSON)
        assert ok.status_code == 200, ok.text
        assert m.stats["events"] == 1


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail("Playwright is missing under CI: scripts/setup --dev installs it")
        pytest.skip("Playwright is not installed here (the browser extra)")
    if not Path(CHROMIUM).exists():
        if os.environ.get("CI"):
            pytest.fail("Debian's chromium is missing under CI: scripts/setup --dev installs it (as root)")
        pytest.skip("Debian's chromium is not installed here (apt-get install chromium)")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        yield b
        b.close()


ATTACK = """<!doctype html><html><body>
<form id="f" method="post" enctype="text/plain" action="{target}control/event">
<input name='{{"event":"E","x":"' value='"}}'></form>
<script>
window.results = [];
fetch("{target}control/event", {{method: "POST", mode: "no-cors",
  headers: {{"content-type": "application/json"}}, body: '{{"event":"E"}}'}})
  .then(() => results.push("no-cors sent"), (e) => results.push("no-cors " + e));
fetch("{target}control/event", {{method: "POST",
  headers: {{"content-type": "application/json"}}, body: '{{"event":"E"}}'}})
  .then(() => results.push("cors sent"), (e) => results.push("cors blocked"));
</script></body></html>"""


@contextmanager
def attacker(page: str) -> Iterator[str]:
    """Another origin on this machine (a real server: Chromium keeps pages it cannot place from loopback)."""

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            self.send_response(200)
            self.send_header("content-type", "text/html; charset=utf-8")
            self.end_headers()
            self.wfile.write(page.encode())

        def log_message(self, *args: Any) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5)


def test_another_origin_cannot_send_an_event_from_chromium(browser: Any) -> None:
    with served(web={"controls": True}) as m, attacker(ATTACK.format(target=url(m))) as evil:
        context = browser.new_context()
        try:
            page = context.new_page()
            seen: list[tuple[str, str, int]] = []
            page.on("response", lambda r: seen.append((r.request.method, urlsplit(r.url).path, r.status)))
            page.goto(evil)
            page.wait_for_function("window.results.length === 2", timeout=5000)
            assert sorted(page.evaluate("window.results")) == ["cors blocked", "no-cors sent"]
            with page.expect_navigation():
                page.evaluate("document.getElementById('f').submit()")
            posts = [s for method, path, s in seen if method == "POST" and path == "/control/event"]
            assert posts == [403, 403], seen  # both reached the view, which refused their origin
            # the view's own page can: the attack did not fail for want of a working control
            page.goto(url(m))
            answer = page.evaluate(
                """fetch("/control/event", {method: "POST", headers: {"content-type": "application/json"},
                     body: JSON.stringify({event: "F"})}).then((r) => r.json())"""
            )
            assert answer == {"ok": True, "decisions": [1]}
        finally:
            context.close()
        assert m.stats["events"] == 1 and [d.event for d in m.decisions] == ["F"]


def test_markup_in_names_is_shown_as_text_never_run(browser: Any, tmp_path: Path) -> None:
    from playwright.sync_api import expect

    name = 'règles ✓ <img src=x onerror="window.pwned=1"><b>&amp; "bold".sleec'
    path = tmp_path / name
    path.write_text(TEXT, encoding="utf-8")
    context = browser.new_context()
    try:
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        with served(path) as m:
            m.event("E")
            page.goto(url(m))
            expect(page.locator("#source")).to_have_text(name)
            expect(page.locator("#source")).to_have_attribute("title", str(path))
            expect(page.locator("#decisions li").first).to_contain_text("on E")
            assert page.locator("img, b").count() == 0
            assert page.evaluate("window.pwned") is None
        assert not errors
    finally:
        context.close()


# ---------------------------------------------------------------------- the Manager is never held up


def test_the_manager_wakes_the_server_only_when_a_browser_waits_for_a_change() -> None:
    with served() as m:
        hub = view(m)._hub
        fired: list[float] = []
        fire = hub._fire

        def counted() -> None:
            fired.append(time.monotonic())
            fire()

        hub._fire = counted  # type: ignore[method-assign]
        for i in range(10_000):  # a value that changes as fast as it can
            m.update(m=bool(i % 2))
        on_loop(m, lambda: None)
        assert fired == [], f"{len(fired)} wake-ups of the server with no browser to tell"
        b = Browser(m)
        try:
            pump([b], lambda: bool(b.messages("clock")))  # past its first state: it waits for a change
            on_loop(m, lambda: None)
            m.update(m=False)  # the last was True (9999 is odd)
            pump([b], lambda: len(b.messages()) == 2)
            assert len(fired) >= 1  # it was woken, not left to its heartbeat
            assert b.messages()[-1]["context"][0]["value"] is False
            before = len(fired)
            started = time.monotonic()
            for i in range(10_000):
                m.update(m=bool(i % 2))
            took = time.monotonic() - started
            on_loop(m, lambda: None)
            # a wake-up at most once per state sent (one per MIN_INTERVAL_S), not one per record
            assert len(fired) - before <= took / 0.1 + 3, (len(fired) - before, took)
            pump([b], lambda: b.messages()[-1]["version"] == view(m).live.version)
            assert b.messages()[-1]["context"][0]["value"] is True  # the newest value
        finally:
            b.close()


def test_two_hundred_browsers_share_one_state_per_change_each_with_its_own_now() -> None:
    clock = VirtualClock()
    # 200 streams: more than the default max_streams (100), so allowed here (test_web_limits.py)
    with served(clock=clock, web={"max_connections": 256, "max_streams": 201}) as m:
        live = view(m).live
        made: list[int] = []
        snapshot = live.snapshot

        def counted() -> dict[str, Any]:
            s = snapshot()
            made.append(s["version"])
            return s

        live.snapshot = counted  # type: ignore[method-assign]
        browsers = [Browser(m) for _ in range(200)]
        try:
            pump(browsers, lambda: all(b.messages() for b in browsers))
            assert len(made) <= 2, f"{len(made)} states made for 200 browsers and no change"
            clock.advance(5)
            m.event("E")
            version = live.version  # a decision, then its obligation: one state or two
            pump(browsers, lambda: all(b.messages()[-1]["version"] == version for b in browsers))
            assert len(made) <= 2 + 2 * 2, len(made)
            assert all(b.messages()[-1]["obligations"][0]["what"] == "A within 10 s" for b in browsers)
            clock.advance(2)
            late = Browser(m)  # nothing changed since: the state it is sent has the time now, not then
            pump([late], lambda: bool(late.messages()))
            assert late.messages()[0]["now"] == 7 and late.messages()[0]["version"] == live.version
            late.close()
        finally:
            for b in browsers:
                b.close()


def test_a_view_closed_twice_or_before_its_manager_leaves_the_manager_able_to_close() -> None:
    m = Manager.from_text(TEXT, clock=VirtualClock(), dispatch=False)
    attach_web(m, 0).start(m)
    p = port(m)
    v = view(m)
    v.close()
    v.close()
    assert refused(p) and not web_threads()
    m.update(m=True)  # the Manager goes on without its view
    close(m)  # and closes: ValueError here left the journal, the audit log and the timer open
    assert web_url(m) is None
    with pytest.raises(UserError):
        m.event("E")  # closed


def test_close_is_prompt_with_stalled_and_half_open_clients_and_frees_the_port() -> None:
    m = Manager.from_text(TEXT, clock=VirtualClock(), dispatch=False)
    attach_web(m, {"controls": True}).start(m)
    p = port(m)
    stalled = [Browser(m, rcvbuf=1024) for _ in range(50)]  # never read
    half: list[socket.socket] = []
    for request in (
        b"GET /state HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ",  # headers never end
        b"POST /control/event HTTP/1.1\r\nHost: 127.0.0.1\r\ncontent-type: application/json\r\n"
        b"content-length: 100\r\n\r\n{",  # a body never ends
    ):
        for _ in range(10):
            s = socket.create_connection(("127.0.0.1", p))
            s.sendall(request)
            half.append(s)
    for i in range(500):
        m.update(m=bool(i % 2))
        m.event("F")
    started = time.monotonic()
    close(m)
    took = time.monotonic() - started
    for b in stalled:
        b.close()
    for s in half:
        s.close()
    assert took < SHUTDOWN_S + 1.5, took
    assert refused(p) and not web_threads()


def test_starts_and_closes_leak_no_thread_and_no_socket() -> None:
    def fds() -> int:
        return len(os.listdir("/proc/self/fd"))

    gc.collect()
    threads, files = set(threading.enumerate()), fds()
    for _ in range(10):  # 50 leak nothing either (each takes uvicorn's 0.1 s to notice it must stop)
        with served() as m, socket.create_connection(("127.0.0.1", port(m))) as s:
            s.sendall(b"GET /state HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n")
            assert s.recv(64).startswith(b"HTTP/1.1 200 ")
    gc.collect()
    assert set(threading.enumerate()) == threads
    assert fds() == files


def test_a_port_in_use_fails_clearly_and_leaves_no_thread_and_no_socket() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        files = len(os.listdir("/proc/self/fd"))
        m = Manager.from_text(TEXT, dispatch=False)
        attached = attach_web(m, taken.getsockname()[1])
        with pytest.raises(UserError, match="cannot serve the web view"):
            attached.start(m)
        assert web_url(m) is None and not web_threads()
        assert len(os.listdir("/proc/self/fd")) == files
        close(m)


def test_browsers_that_drop_mid_stream_are_forgotten() -> None:
    with served() as m:
        browsers = [Browser(m) for _ in range(30)]
        pump(browsers, lambda: all(b.messages("clock") for b in browsers))  # each waits for a change
        for i, b in enumerate(browsers):
            b.close(reset=i % 2 == 0)
        m.update(m=True)  # something to send: a write finds the dropped ones
        server = view(m)._server
        wait(lambda: not server.server_state.connections)
        wait(lambda: on_loop(m, lambda: view(m)._hub.waiting) == 0)
        assert state(m)["context"][0]["value"] is True


def test_a_view_that_raises_cannot_stop_enforcement(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args: Any) -> Any:
        raise RuntimeError("a bug in the view")

    clock = VirtualClock()
    with served(clock=clock) as m:
        monkeypatch.setattr(live_module, "_decision", broken)  # every decision record breaks it
        monkeypatch.setattr(live_module, "_obligation", broken)
        m.update(m=False)
        m.event("F")  # R2: B is forbidden for 30 s
        assert not m.request("B")
        m.event("E")  # R1: A within 10 s
        clock.advance(11)
        m.tick()
        assert m.stats["decisions"] == 2 and m.stats["refused"] == 1 and m.stats["violations"] == 1
        assert [t.rule for t in m.outstanding(prohibitions=True)] == ["R2"]
        monkeypatch.setattr(view(m).live, "snapshot", broken)
        assert httpx.get(url(m) + "state").status_code == 500  # an error, not a stale page
        m.update(m=True)
        assert m.rule_layers()["R2"] == "R2.1"


# ---------------------------------------------------------------------- what it shows


def test_a_fulfilled_obligation_goes_and_a_refused_one_is_a_listed_violation() -> None:
    with served() as m:
        m.event("E")
        assert [o["what"] for o in state(m)["obligations"]] == ["A within 10 s"]
        m.event("A")
        s = state(m)
        assert s["obligations"] == [] and s["violations"] == []
    with served(Path(rules_path())) as m:
        m.update(userConsent=False, userUndressed=False, userConscious=True)
        m.event("UserFallen")  # R6 forbids RecordVideo for 10 minutes
        m.update(userConsent=True)
        m.event("CameraRequest")  # R10 obliges RecordVideo within 5 s: blocked, a violation
        s = state(m)
    assert s["stats"]["violations"] == 1 and len(s["conflicts"]) == 1
    [v] = s["violations"]  # counted, so listed
    assert (v["rule"], v["what"], v["status"], v["by"]) == ("R10", "RecordVideo within 5 s", "blocked", "R6")


def test_the_page_says_a_blocked_obligation_was_blocked(browser: Any) -> None:
    from playwright.sync_api import expect

    context = browser.new_context()
    try:
        page = context.new_page()
        with served(Path(rules_path())) as m:
            m.update(userConsent=False, userUndressed=False, userConscious=True)
            m.event("UserFallen")
            m.update(userConsent=True)
            m.event("CameraRequest")
            page.goto(url(m))
            v = page.locator("#violations li")
            expect(v).to_have_count(1)
            expect(v.locator(".badge")).to_have_text("blocked")
            expect(v).to_contain_text("R10, decision #3: blocked, R6 forbids it")
    finally:
        context.close()


NEW = """def_start event E event G event A measure k : numeric def_end
rule_start
S1 when G then A within 5 seconds unless (k > 3)
R1 when E then A within 10 seconds
rule_end"""


def test_after_a_reload_the_state_has_the_new_rules_and_a_new_measure_has_no_age() -> None:
    clock = VirtualClock()
    with served(clock=clock) as m:
        m.update(m=True)
        m.event("E")
        clock.advance(2)
        m.reload(RuleSet.from_text(NEW))
        s = state(m)
        assert [(r["name"], r["layer"]) for r in s["rules"]] == [("S1", "?"), ("R1", None)]
        assert s["context"] == [
            {"name": "k", "type": "numeric", "value": None, "since": None, "before": False}
        ]
        assert [(o["rule"], o["what"]) for o in s["obligations"]] == [("R1", "A within 10 s")]
        clock.advance(1)
        m.update(k=5)
        s = state(m)
        assert s["context"][0]["value"] == 5 and s["context"][0]["since"] == 3
        assert [(r["name"], r["layer"]) for r in s["rules"]] == [("S1", "S1.1"), ("R1", None)]


def test_a_view_on_ipv6_loopback_serves_there_only() -> None:
    with served(web={"host": "::1"}) as m:
        assert url(m).startswith("http://[::1]:")
        assert httpx.get(url(m) + "state").status_code == 200
        assert refused(port(m))  # not on 127.0.0.1


def test_a_manager_that_fails_to_start_serves_no_view() -> None:
    m = Manager.from_text(TEXT, clock=VirtualClock(), dispatch=False, audit="/dev/full")
    try:
        attached = attach_web(m, 0)
        with pytest.raises(UserError, match="cannot write the audit log"):
            attached.start(m)  # a full disk
        assert web_url(m) is None and not web_threads()
    finally:
        with contextlib.suppress(OSError):  # the audit log cannot flush to /dev/full
            close(m)
