"""The live web view: one page that shows a running Manager as it decides.

``attach(manager, PORT)`` (:mod:`cosleec.views.registry`), ``cosleec demo --web`` and the ROS
Manager node's ``--web PORT`` serve it: the context with each value's age, each rule's layer, the latest decisions and
why, the obligations in force with a countdown to their deadline, violations, conflicts
and refused actions (``docs/runtime.md``, "The live web view"). It is found by the entry
point ``cosleec.views: web`` (:func:`serve`; :func:`~cosleec.views.registry.load_view`), so
that nothing imports the web packages until the view is asked for; ``cosleec.runtime`` names
no view at all.

Built on Starlette, served by uvicorn on a daemon thread with its own asyncio loop, from
:func:`~cosleec.views.registry.attach` (before :meth:`Manager.start
<cosleec.runtime.Manager.start>`) to :meth:`WebView.close` (before :meth:`Manager.close
<cosleec.runtime.Manager.close>`). ``GET /`` is the page (package data in ``static/``:
HTML, CSS and plain JavaScript, nothing fetched from elsewhere), ``GET /state`` the state as
JSON, ``GET /events`` a stream of server-sent events: a ``state`` message whenever
something shown changed (at most every :data:`MIN_INTERVAL_S`) and a ``clock`` message with
the runtime's time every :data:`HEARTBEAT_S` (a virtual clock moved by a test or a
simulator reaches the page that way; the page runs a real clock on between two).

The Manager's threads are never held up by a browser: its records update :class:`Live`
and at most one wake-up waits in the loop at any time; every browser is sent the newest
state, never a backlog, so a slow or stalled one costs no memory (and one that does not read
for :data:`SEND_TIMEOUT_S` is disconnected).

Bounded under abuse (web_server.py): a request must begin within ``idle_timeout`` and
arrive whole within ``request_timeout`` of the moment it may begin, whatever it sends
meanwhile; at most ``max_connections`` connections are open at once, never more than half
the descriptors the process had left when the view started (RLIMIT_NOFILE), so that the
Manager can still open its files; at most ``max_streams`` pages follow the stream (503
beyond); a failed ``accept()`` makes the server pause, not spin, and each kind of error is
logged once, then at most every ten minutes with a count.

Safe by default: bound to 127.0.0.1; a client that is not on this machine is refused
(403) unless ``allow_remote``, even when bound to every interface; a ``Host`` header that
is neither an IP address nor ``localhost`` (nor this machine's name, with ``allow_remote``)
is refused, against DNS rebinding; no CORS; read-only unless ``controls`` (then ``POST
/control/event`` and ``POST /control/advance`` take JSON of at most :data:`MAX_BODY` bytes
from the page's own origin).
"""

from __future__ import annotations

import asyncio
import contextlib
import difflib
import ipaddress
import json
import math
import re
import socket
import threading
import time
from collections.abc import AsyncIterator, Mapping
from dataclasses import dataclass, fields
from importlib import resources
from itertools import accumulate
from typing import Any

import anyio
import uvicorn
from sse_starlette import EventSourceResponse
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.routing import Route
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from cosleec.errors import ConfigurationError, UserError, show
from cosleec.runtime import Manager, VirtualClock
from cosleec.views.live import Live
from cosleec.views.web_server import Server, descriptors_left, seconds

#: the runtime's time is sent to every browser this often (seconds)
HEARTBEAT_S = 0.2
#: a browser is sent a new state at most this often (seconds): a burst of records is one message
MIN_INTERVAL_S = 0.1
#: a browser that takes no data for this long is disconnected (seconds)
SEND_TIMEOUT_S = 10.0
#: how long :meth:`WebView.close` lets open streams finish before they are cut (seconds)
SHUTDOWN_S = 1
#: how long the server may take to start (seconds)
START_S = 10.0
#: the most seconds ``POST /control/advance`` moves a virtual clock at once
MAX_ADVANCE_S = 86_400.0
#: the largest body a control request may have (bytes): a bigger one is refused unread (413)
MAX_BODY = 64 * 1024
#: how deep a control request's JSON may nest (it is one flat object): deeper is a 400
MAX_BODY_DEPTH = 4
#: the most connections open at once when ``max_connections`` is not given (fewer if the
#: process has fewer than twice as many descriptors left)
DEFAULT_CONNECTIONS = 128
#: the longest timeout an option may give (seconds)
MAX_TIMEOUT_S = 3600.0

_FILES = {  # path -> (package file, media type)
    "/": ("index.html", "text/html; charset=utf-8"),
    "/static/web.js": ("web.js", "text/javascript; charset=utf-8"),
    "/static/web.css": ("web.css", "text/css; charset=utf-8"),
    "/static/favicon.svg": ("favicon.svg", "image/svg+xml"),
}
_HEADERS = [  # on every response
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
    (b"cache-control", b"no-store"),
    (
        b"content-security-policy",
        b"default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self'; "
        b"connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'",
    ),
]


@dataclass(frozen=True, kw_only=True)
class WebOptions:
    """How the web view serves: ``attach(manager, PORT)`` or ``attach(manager, {...})`` with these keys.

    ``port`` (0: a free one), ``host`` (an IP address or ``localhost``; 127.0.0.1 by
    default), ``allow_remote`` (serve clients on other machines: needed for any host other
    than loopback, and off by default), ``controls`` (accept the page's POST requests that
    change state -- send an event, advance a virtual clock; off by default).

    The bounds: ``request_timeout`` (seconds a request has to arrive whole -- its headers,
    and a control's body -- from the moment it may begin; 10), ``idle_timeout`` (seconds a
    connection may send nothing before or between requests; 5), ``max_connections`` (open
    at once, the next ones wait unaccepted; by default :data:`DEFAULT_CONNECTIONS`, or half
    the descriptors the process has left if that is fewer; more than that half is refused)
    and ``max_streams`` (pages following the live stream at once, less than
    ``max_connections``; 100).
    """

    port: int = 0
    host: str = "127.0.0.1"
    allow_remote: bool = False
    controls: bool = False
    request_timeout: float = 10.0
    idle_timeout: float = 5.0
    max_connections: int | None = None
    max_streams: int = 100

    @classmethod
    def of(cls, value: object) -> WebOptions:
        """The options given as a port or a mapping; ConfigurationError (a UserError) naming what is wrong."""
        if isinstance(value, WebOptions):
            return value
        if isinstance(value, int) and not isinstance(value, bool):
            given: dict[str, Any] = {"port": value}
        elif isinstance(value, Mapping):
            given = dict(value)
        else:
            raise ConfigurationError(
                f"web must be a port number or a mapping of options, not {show(value)}",
                hint="web=8765, web=0 (a free port) or web={'port': 8765, 'host': '127.0.0.1'}",
            )
        names = [f.name for f in fields(cls)]
        for key in given:
            if key not in names:
                close = difflib.get_close_matches(str(key), names, n=1)
                raise ConfigurationError(
                    f"unknown web option {show(key)}",
                    hint=f"did you mean {close[0]!r}?" if close else f"the options: {', '.join(names)}",
                )
        options = cls(**given)
        options._check()
        return options

    def _check(self) -> None:
        port, host = self.port, self.host
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise ConfigurationError(
                f"the web port must be a whole number from 0 to 65535, not {show(port)}",
                hint="0 picks a free port",
            )
        for name in ("allow_remote", "controls"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigurationError(
                    f"web option {name} must be true or false, not {show(getattr(self, name))}"
                )
        self._check_bounds()
        address = _address(host) if isinstance(host, str) else None
        if address is None:
            raise ConfigurationError(
                f"the web host must be an IP address or localhost, not {show(host)}",
                hint="127.0.0.1 (the default) serves this machine only",
            )
        if not address.is_loopback and not self.allow_remote:
            raise ConfigurationError(
                f"the web view would serve other machines on {host}, but allow_remote is off",
                hint="keep the default host 127.0.0.1, or give allow_remote=True if others may see the "
                "rules, the context and the decisions (anyone who can reach the port can)",
            )

    def _check_bounds(self) -> None:
        for name in ("request_timeout", "idle_timeout"):
            t = getattr(self, name)
            if (
                isinstance(t, bool)
                or not isinstance(t, int | float)
                or not math.isfinite(t)
                or not 0 < t <= MAX_TIMEOUT_S
            ):
                raise ConfigurationError(
                    f"web option {name} must be a number of seconds, more than 0 and at most "
                    f"{MAX_TIMEOUT_S:g}, not {show(t)}"
                )
        for name, least in (("max_connections", 2), ("max_streams", 1)):
            n = getattr(self, name)
            if n is None and name == "max_connections":
                continue
            if isinstance(n, bool) or not isinstance(n, int) or not least <= n <= 1_000_000:
                raise ConfigurationError(
                    f"web option {name} must be a whole number from {least} to 1000000, not {show(n)}"
                )
        if self.max_connections is not None and self.max_streams >= self.max_connections:
            raise ConfigurationError(
                f"web option max_streams must be less than max_connections, not {self.max_streams} "
                f"of {self.max_connections}",
                hint="a page also needs connections for its files and its state",
            )

    def limits(self) -> tuple[int, int]:
        """The connections and streams this view may have open at once, here and now: the
        descriptors the process has left decide the default, and refuse more than half of them."""
        left = descriptors_left()
        budget = None if left is None else max(0, left - 8) // 2  # 8: the view's own (listening, loop)
        wanted = self.max_connections
        if budget is not None and (budget < 2 or (wanted is not None and wanted > budget)):
            raise UserError(
                f"the web view may not take {wanted or 2} connections: the process has {left} file "
                f"descriptors left, and the view takes at most half of them ({budget})",
                hint="raise the limit of open files (ulimit -n) or give a smaller max_connections",
            )
        connections = wanted or (DEFAULT_CONNECTIONS if budget is None else min(DEFAULT_CONNECTIONS, budget))
        return connections, min(self.max_streams, connections - 1)


class WebView:
    """The web view of one Manager, serving on a daemon thread: made by :func:`serve`.

    ``url`` is where to open it, ``port`` the port it took, ``live`` what it shows
    (:class:`~cosleec.views.live.Live`) and ``app`` its ASGI application;
    ``max_connections`` and ``max_streams`` what it allows at once (:meth:`WebOptions.limits`).
    :meth:`close` stops the server, frees the port and stops following the Manager
    (call it before ``Manager.close()``; :class:`~cosleec.views.registry.AttachedView` does).
    """

    def __init__(self, manager: Manager, options: WebOptions) -> None:
        self.manager = manager
        self.options = options
        self.max_connections, self.max_streams = options.limits()
        address = _address(options.host)
        assert address is not None  # WebOptions checked it
        family = socket.AF_INET6 if address.version == 6 else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((str(address), options.port))
            sock.listen(128)  # now: a browser that connects before the loop serves waits, it is not refused
            sock.setblocking(False)  # the server's loop accepts on it
        except OSError as e:
            sock.close()
            raise UserError(
                f"cannot serve the web view on {options.host} port {options.port}: {e.strerror or e}",
                hint="give another port, or 0 for a free one",
            ) from None
        self._socket = sock
        self.port: int = sock.getsockname()[1]
        shown = (
            "127.0.0.1"
            if address.is_unspecified
            else f"[{address}]"
            if address.version == 6
            else str(address)
        )
        self.url = f"http://{shown}:{self.port}/"
        self._hub = _Hub()
        self.live = Live(manager, self._hub.wake, controls=options.controls)
        self.app = _app(self)  # the ASGI application, guarded (it can be mounted or tested alone)
        config = uvicorn.Config(
            self.app,
            log_config=None,  # the host program's logging stays as it is
            log_level="warning",
            access_log=False,
            lifespan="on",
            loop="asyncio",
            http="h11",
            ws="none",
            proxy_headers=False,  # the client is the peer: a header cannot claim another address
            server_header=False,
            timeout_graceful_shutdown=SHUTDOWN_S,
            timeout_keep_alive=math.ceil(options.idle_timeout),  # a backstop: the Protocol closes first
        )
        self._server = Server(
            config,
            sock,
            max_connections=self.max_connections,
            idle_timeout=options.idle_timeout,
            request_timeout=options.request_timeout,
            headers=_HEADERS,
        )
        self._thread = threading.Thread(
            target=self._server.run, kwargs={"sockets": [sock]}, name="cosleec-web", daemon=True
        )
        self._thread.start()
        self._server.filter.attach(self._thread)
        deadline = time.monotonic() + START_S
        while not self._hub.ready.wait(0.05):
            if not self._thread.is_alive() or time.monotonic() > deadline:
                self.close()
                raise ConfigurationError("the web view could not start (see the log above)")

    def close(self) -> None:
        """Stop serving (open streams end, the port is freed) and stop following the Manager."""
        self.live.close()
        self._hub.close()
        self._server.should_exit = True
        self._thread.join(SHUTDOWN_S + 5)
        self._server.filter.detach()
        self._socket.close()


def serve(manager: Manager, options: object) -> WebView:
    """Serve ``manager``'s live web view: the ``web`` entry point of the group ``cosleec.views``.

    ``options`` is what :func:`~cosleec.views.registry.attach` was given (see
    :class:`WebOptions`); it serves from now, and its caller closes it before the Manager.
    """
    return WebView(manager, WebOptions.of(options))


class _Hub:
    """Between the Manager's threads and the server's loop: wake every browser's stream, at
    most one wake-up pending at a time (a burst of records costs one), and none while no
    stream waits for a change (with no browser, or while each is sending or pausing, a
    record costs the Manager no wake-up at all). Every stream is sent the same state,
    made once per version (:meth:`state`)."""

    def __init__(self) -> None:
        self.ready = threading.Event()
        self.loop: asyncio.AbstractEventLoop | None = None
        self.changed: asyncio.Event | None = None
        self.stopping: anyio.Event | None = None
        self.closing = False
        self.waiting = 0  # streams waiting for a change (changed under the lock)
        self.streams = 0  # pages following the stream (changed on the loop only)
        self._lock = threading.Lock()
        self._pending = False
        self._state: tuple[int, str] | None = None  # the newest state's version, and its JSON without now

    def started(self) -> None:
        """(On the loop, at startup.) The loop is running: wake-ups can be delivered."""
        self.changed = asyncio.Event()
        self.stopping = anyio.Event()
        self.loop = asyncio.get_running_loop()
        self.ready.set()

    def wake(self) -> None:
        """(Any thread; never waits.) Something shown changed: let the streams look."""
        with self._lock:
            if self._pending or self.loop is None or self.closing or not self.waiting:
                return
            self._pending = True
        with contextlib.suppress(RuntimeError):  # the loop has closed meanwhile
            self.loop.call_soon_threadsafe(self._fire)

    async def wait(self, live: Live, sent: int) -> None:
        """(On the loop.) Until the state has moved past version ``sent``, or :data:`HEARTBEAT_S`."""
        changed = self.changed
        with self._lock:  # counted before the version is read: a change after it wakes us
            self.waiting += 1
        try:
            if changed is not None and live.version == sent:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(changed.wait(), HEARTBEAT_S)
        finally:
            with self._lock:
                self.waiting -= 1

    def state(self, live: Live) -> tuple[int, str]:
        """(On the loop.) The newest state's version and JSON without ``now``: made once per
        version, whatever the number of browsers (each is sent it with its own ``now``)."""
        if self._state is None or self._state[0] != live.version:
            state = live.snapshot()
            del state["now"]
            self._state = (state["version"], _json(state))
        return self._state

    def _fire(self) -> None:
        with self._lock:
            self._pending = False
        fired, self.changed = self.changed, asyncio.Event()
        if fired is not None:
            fired.set()

    def close(self) -> None:
        """(Any thread.) Streams end: the server can stop."""
        with self._lock:
            self.closing = True
        if self.loop is not None:
            with contextlib.suppress(RuntimeError):
                self.loop.call_soon_threadsafe(self._stop)

    def _stop(self) -> None:
        if self.stopping is not None:
            self.stopping.set()
        self._fire()


def _app(view: WebView) -> ASGIApp:
    """The Starlette application of ``view``: the page, its state, its stream, its controls."""
    hub, live, options = view._hub, view.live, view.options
    files = {
        path: (resources.files("cosleec.views").joinpath("static", name).read_bytes(), media)
        for path, (name, media) in _FILES.items()
    }

    async def page(request: Request) -> Response:
        body, media = files[request.url.path]
        return Response(body, media_type=media)

    async def state(request: Request) -> Response:
        return Response(_json(live.snapshot()), media_type="application/json")

    async def events(request: Request) -> Response:
        if hub.streams >= view.max_streams:
            return _error(
                503,
                f"this view serves at most {view.max_streams} live pages at once: close another one "
                "and reload this one (the web option max_streams)",
                headers={"retry-after": "5"},
            )
        return _Counted(
            hub,
            _stream(hub, live),
            send_timeout=SEND_TIMEOUT_S,
            shutdown_event=hub.stopping,
            headers={"x-accel-buffering": "no"},
        )

    async def control_event(request: Request) -> Response:
        body = await _control(request, options)
        if isinstance(body, Response):
            return body
        name = body.get("event")
        if not isinstance(name, str) or not name:
            return _error(400, 'give the event to send: {"event": "Name"}')
        try:
            decided = await anyio.to_thread.run_sync(view.manager.event, name)
        except UserError as e:
            return _error(400, e.message + (f" ({e.hint})" if e.hint else ""))
        return JSONResponse({"ok": True, "decisions": [d.id for d in decided]})

    async def control_advance(request: Request) -> Response:
        body = await _control(request, options)
        if isinstance(body, Response):
            return body
        clock = view.manager.clock
        if not isinstance(clock, VirtualClock):
            return _error(409, "this Manager runs on a real clock: only a virtual clock can be advanced")
        seconds = body.get("seconds")
        if (
            isinstance(seconds, bool)
            or not isinstance(seconds, int | float)
            or not 0 < seconds <= MAX_ADVANCE_S
            or not math.isfinite(seconds)
        ):
            return _error(400, f"give the seconds to advance, more than 0 and at most {MAX_ADVANCE_S:g}")

        def advance() -> float:
            clock.advance(float(seconds))
            view.manager.tick()
            return clock.now()

        try:
            now = await anyio.to_thread.run_sync(advance)
        except UserError as e:
            return _error(400, str(e))
        return JSONResponse({"ok": True, "now": now})

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        hub.started()
        yield

    routes = [Route(path, page) for path in _FILES]
    routes += [
        Route("/state", state),
        Route("/events", events),
        Route("/control/event", control_event, methods=["POST"]),
        Route("/control/advance", control_advance, methods=["POST"]),
    ]
    return _Guard(Starlette(routes=routes, lifespan=lifespan), options)


class _Counted(EventSourceResponse):
    """A page's stream, counted in ``hub.streams`` from its making until it ends."""

    def __init__(self, hub: _Hub, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.hub = hub
        hub.streams += 1  # made on the loop, and served at once: nothing runs in between

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await super().__call__(scope, receive, send)
        finally:
            self.hub.streams -= 1


async def _stream(hub: _Hub, live: Live) -> AsyncIterator[dict[str, str]]:
    """One browser's server-sent events: the newest state when it changed, the clock between."""
    sent = -1
    while not hub.closing:
        if live.version != sent:
            sent, state = hub.state(live)
            now = _json(live.manager.clock.now())
            yield {"event": "state", "data": '{"now":' + now + "," + state[1:]}
            await asyncio.sleep(MIN_INTERVAL_S)  # what changes meanwhile goes in the next one
        else:
            yield {"event": "clock", "data": _json({"now": live.manager.clock.now()})}
        await hub.wait(live, sent)


async def _control(request: Request, options: WebOptions) -> dict[str, Any] | Response:
    """The JSON body of a control request, or the response that refuses it.

    403 while controls are off, or when the request comes from another origin; 415 unless
    it is JSON (a form posted by another site's page cannot be); 413 when its body is
    larger than :data:`MAX_BODY` (refused unread when it says so, else once it passes it:
    the robot's memory is not the client's to fill); 408 when it has not arrived within
    ``request_timeout``; 400 unless it is one JSON object nested at most
    :data:`MAX_BODY_DEPTH` levels (the depth is counted before it is parsed).
    """
    if not options.controls:
        return _error(403, "this view is read-only: controls are off (web={'controls': True} turns them on)")
    origin = request.headers.get("origin")
    if origin is not None and origin != f"{request.url.scheme}://{request.headers.get('host', '')}":
        return _error(403, "a control request must come from this view's own page")
    if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
        return _error(415, "a control request is JSON (content-type: application/json)")
    length = request.headers.get("content-length", "0")
    too_big = _error(413, f"a control request is at most {MAX_BODY} bytes")
    if not length.isascii() or not length.isdigit() or int(length) > MAX_BODY:
        return too_big
    data = b""
    with anyio.move_on_after(options.request_timeout) as waited:
        async for chunk in request.stream():
            data += chunk
            if len(data) > MAX_BODY:
                return too_big
    if waited.cancelled_caught:
        return _error(
            408,
            f"the request's body did not arrive within {seconds(options.request_timeout)}",
            headers={"connection": "close"},
        )
    depth = _nesting(data)
    if depth > MAX_BODY_DEPTH:
        return _error(
            400,
            f"a control request is one flat JSON object: this one is nested {depth} levels deep "
            f"(at most {MAX_BODY_DEPTH})",
        )
    try:
        body = json.loads(data)
    except ValueError:
        return _error(400, "a control request is a JSON object")
    if not isinstance(body, dict):
        return _error(400, "a control request is a JSON object")
    return body


def _error(status: int, message: str, headers: dict[str, str] | None = None) -> Response:
    return JSONResponse({"ok": False, "error": message}, status_code=status, headers=headers)


_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")
_STEP = [0] * 256
_STEP[ord("[")] = _STEP[ord("{")] = 1
_STEP[ord("]")] = _STEP[ord("}")] = -1


def _nesting(data: bytes) -> int:
    """How deep the JSON text ``data`` nests arrays and objects (brackets in strings are text):
    linear and without recursion, whatever the depth, unlike the parser. Escapes go first
    (``\\\\``, then ``\\"``), so every quote left delimits a string. (cosleec.lsp.wire
    counts the same way: the two floors do not import each other.)"""
    plain = data.replace(b"\\\\", b"").replace(b'\\"', b"")
    brackets = b"".join(plain.split(b'"')[::2]).translate(None, _NOT_BRACKETS)
    return max(accumulate(map(_STEP.__getitem__, brackets)), default=0)


def _json(data: Any) -> str:
    return json.dumps(data, default=str, separators=(",", ":"))


def _address(host: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    """The IP address ``host`` names (``localhost`` is 127.0.0.1), or None; no name is looked up."""
    if host == "localhost":
        return ipaddress.IPv4Address("127.0.0.1")
    try:
        return ipaddress.ip_address(host.strip("[]"))
    except ValueError:
        return None


def _loopback(host: str) -> bool:
    """Is the client address ``host`` on this machine (``::ffff:127.0.0.1`` included)?"""
    address = _address(host)
    if isinstance(address, ipaddress.IPv6Address) and address.ipv4_mapped is not None:
        address = address.ipv4_mapped
    return address is not None and address.is_loopback


#: a Host header: a name or an address, ``[an IPv6 address]``, then at most a port
_HOST = re.compile(r"(?:\[(?P<v6>[0-9a-f:.]+)\]|(?P<name>[^:\[\]]+))(?::[0-9]{0,5})?")


class _Guard:
    """Who may look: clients on this machine (unless ``allow_remote``), through a ``Host``
    this server can be (an IP address, ``localhost``, with ``allow_remote`` this machine's
    name), against DNS rebinding; every response gets the security headers."""

    def __init__(self, app: ASGIApp, options: WebOptions) -> None:
        self.app = app
        self.allow_remote = options.allow_remote
        self.names = {"localhost"} | ({socket.gethostname().lower()} if options.allow_remote else set())

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        client = scope.get("client")
        if not self.allow_remote and (client is None or not _loopback(str(client[0]))):
            await _refuse(send, "this view serves this machine only (allow_remote is off)")
            return
        host = _HOST.fullmatch(dict(scope["headers"]).get(b"host", b"").decode("latin-1").lower())
        name = (host.group("v6") or host.group("name")) if host is not None else ""
        if not name or not (name in self.names or _address(name) is not None):
            await _refuse(send, "this view answers only to its address (an IP address or localhost)")
            return

        async def secured(message: Message) -> None:
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message.get("headers", []), *_HEADERS]}
            await send(message)

        await self.app(scope, receive, secured)


async def _refuse(send: Send, why: str) -> None:
    body = why.encode()
    await send(
        {
            "type": "http.response.start",
            "status": 403,
            "headers": [(b"content-type", b"text/plain; charset=utf-8"), *_HEADERS],
        }
    )
    await send({"type": "http.response.body", "body": body})
