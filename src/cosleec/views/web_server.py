"""The web view's HTTP server: uvicorn, with the bounds its own server lacks (issue 28, finding 9).

uvicorn times out a kept-alive connection only after a response, and any byte received
cancels that: a client that connects and sends nothing, or half a request, or a byte every
second, held its connection for ever (1,500 of 1,500 slowloris connections stayed open).
asyncio's accept loop, at the descriptor limit, retried ``accept()`` up to the backlog
times per turn of the loop, each failure logged with its traceback (270k lines in 5 s),
and the connections it did accept took every descriptor the Manager's process had left.
So here:

- :class:`Protocol` (uvicorn's h11 protocol) gives each request a deadline from the moment
  it may begin (the connection opened, or the previous answer ended): no byte of it within
  ``idle_timeout``, or not all of its headers within ``request_timeout``, and the connection
  is closed (with a 408 if part of a request came). Bytes arriving do not move the
  deadline. Once the application has the request its own bounds apply (a control's body
  must arrive within ``request_timeout``; a stream's browser must read within
  ``SEND_TIMEOUT_S``).
- :class:`Server` accepts connections itself: at most ``max_connections`` at once (the
  next ones wait in the kernel's queue, unaccepted, taking no descriptor of this process),
  and after a failed ``accept()`` (out of descriptors, of memory) it pauses, from
  :data:`PAUSE_MIN_S` doubling to :data:`PAUSE_MAX_S`, before it tries again.
- Errors are logged by kind through :class:`~cosleec.nodes.LogLimiter`: the first of each
  kind at once, then at most one every :data:`LOG_EVERY_S` with the count of the rest --
  ``accept()`` failures, uvicorn's own warnings (a malformed request, ...) and the event
  loop's errors alike.

:func:`descriptors_left` says how many descriptors the process may still open
(RLIMIT_NOFILE): the view takes at most half of them (web.py).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import resource
import socket
import threading
from collections.abc import Callable
from typing import Any

import h11
import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol
from uvicorn.server import ServerState

from cosleec.nodes import LogLimiter

log = logging.getLogger("cosleec.views")

#: the first pause after a failed ``accept()`` (seconds); each failure in a row doubles it
PAUSE_MIN_S = 0.05
#: the longest pause between two tries of ``accept()`` (seconds)
PAUSE_MAX_S = 1.0
#: an error of a kind already logged is logged again at most this often, with a count (seconds)
LOG_EVERY_S = 600.0


def descriptors_left() -> int | None:
    """How many more files this process may open (RLIMIT_NOFILE less those open); None: no limit."""
    soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY:
        return None
    for listing in ("/proc/self/fd", "/dev/fd"):
        with contextlib.suppress(OSError):
            return int(soft) - len(os.listdir(listing))
    return int(soft)


def seconds(t: float) -> str:
    """``1 second``, ``1.5 seconds``."""
    return f"{t:g} second{'' if t == 1 else 's'}"


class Protocol(H11Protocol):
    """uvicorn's h11 protocol, with a deadline for each request to begin and to arrive whole.

    ``on_lost`` is called after the connection has gone (the server may accept another).
    """

    def __init__(
        self,
        config: uvicorn.Config,
        server_state: ServerState,
        app_state: dict[str, Any],
        *,
        idle_timeout: float,
        request_timeout: float,
        on_lost: Callable[[], None],
        headers: list[tuple[bytes, bytes]],
    ) -> None:
        super().__init__(config, server_state, app_state)
        self._idle_timeout = idle_timeout
        self._request_timeout = request_timeout
        self._on_lost = on_lost
        self._headers = headers
        self._idle: asyncio.TimerHandle | None = None
        self._whole: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        """A connection: its first request may begin (the deadlines start)."""
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        """Gone: the server may accept another."""
        self._disarm()
        super().connection_lost(exc)
        self._on_lost()

    def data_received(self, data: bytes) -> None:
        """Bytes of a request: it is no longer idle (its deadline to arrive whole stays)."""
        if self._idle is not None:
            self._idle.cancel()
            self._idle = None
        super().data_received(data)

    def on_response_complete(self) -> None:
        """An answer sent: the next request may begin (the deadlines start again)."""
        super().on_response_complete()  # may hand a pipelined request to the application
        if not self.transport.is_closing():
            self._arm()

    def _arm(self) -> None:
        """A request may begin now: it has ``idle_timeout`` to begin, ``request_timeout`` to arrive."""
        self._disarm()
        self._idle = self.loop.call_later(self._idle_timeout, self._expired, False)
        self._whole = self.loop.call_later(self._request_timeout, self._expired, True)

    def _disarm(self) -> None:
        """No deadline (the connection has gone, or new ones follow)."""
        for timer in (self._idle, self._whole):
            if timer is not None:
                timer.cancel()
        self._idle = self._whole = None

    def _expired(self, whole: bool) -> None:
        """A deadline passed (``whole``: the request's, else the idle one) while no request is
        in the application's hands: close; with a 408 if part of a request came, abruptly if
        the last answer is still unread (closing would wait for the reader for ever)."""
        if whole:
            self._whole = None
        else:
            self._idle = None
        if self.transport.is_closing() or (self.cycle is not None and not self.cycle.response_complete):
            return  # gone, or the application has the request: its own bounds apply
        begun = bool(self.conn.trailing_data[0])
        if not whole:
            if begun or self.transport.get_write_buffer_size():
                return  # not idle: the request deadline decides
            self._disarm()
            self.transport.close()
            return
        self._disarm()
        if self.transport.get_write_buffer_size():  # the last answer is still unread: a stalled reader
            self.transport.abort()
            return
        if begun and self.conn.our_state is h11.IDLE:
            self.transport.write(self._timeout_response())
        self.transport.close()

    def _timeout_response(self) -> bytes:
        """A 408 written as is (h11 answers only a request it has read whole)."""
        body = f"the request did not arrive whole within {seconds(self._request_timeout)}".encode()
        head = [
            b"HTTP/1.1 408 Request Timeout",
            b"content-type: text/plain; charset=utf-8",
            b"connection: close",
            b"content-length: %d" % len(body),
            *(name + b": " + value for name, value in self._headers),
        ]
        return b"\r\n".join(head) + b"\r\n\r\n" + body


class Server(uvicorn.Server):
    """uvicorn's server, accepting on ``sock`` itself: at most ``max_connections`` at once,
    pausing after a failed ``accept()``, each kind of error logged once (then rarely)."""

    def __init__(
        self,
        config: uvicorn.Config,
        sock: socket.socket,
        *,
        max_connections: int,
        idle_timeout: float,
        request_timeout: float,
        headers: list[tuple[bytes, bytes]],
    ) -> None:
        super().__init__(config)
        self.sock = sock
        self.max_connections = max_connections
        self.limiter = LogLimiter(log, LOG_EVERY_S)
        self._timeouts = (idle_timeout, request_timeout)
        self._headers = headers
        self._room: asyncio.Event | None = None
        self._accepting: asyncio.Task[None] | None = None
        self.filter = _Limited(self)

    async def startup(self, sockets: list[socket.socket] | None = None) -> None:
        """Start the application, then accept (uvicorn's own startup would use asyncio's accept loop)."""
        await self.lifespan.startup()
        if self.lifespan.should_exit:  # the application could not start (it logged why)
            self.should_exit = True
            return
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(self._loop_error)
        self.servers = []  # uvicorn closes these when it stops: there are none
        self._room = asyncio.Event()
        self._accepting = loop.create_task(self._accept(), name="cosleec-web-accept")
        self.started = True

    async def shutdown(self, sockets: list[socket.socket] | None = None) -> None:
        """Stop accepting, then uvicorn's own shutdown (it closes ``sockets`` and the connections)."""
        if self._accepting is not None:
            self._accepting.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._accepting
        await super().shutdown(sockets)

    def _connection(self) -> Protocol:
        idle, whole = self._timeouts
        return Protocol(
            self.config,
            self.server_state,
            self.lifespan.state,
            idle_timeout=idle,
            request_timeout=whole,
            on_lost=self._gone,
            headers=self._headers,
        )

    def _gone(self) -> None:
        if self._room is not None:
            self._room.set()

    async def _accept(self) -> None:
        """Accept while there is room; after a failure pause, longer each time it fails again."""
        loop = asyncio.get_running_loop()
        room = self._room
        assert room is not None
        pause = 0.0
        while True:
            while len(self.server_state.connections) >= self.max_connections:
                room.clear()
                await room.wait()
            try:
                conn, _ = await loop.sock_accept(self.sock)
            except (BlockingIOError, InterruptedError, ConnectionAbortedError):
                continue  # the client gave up before it was accepted
            except OSError as e:
                pause = min(max(2 * pause, PAUSE_MIN_S), PAUSE_MAX_S)
                self.limiter.log(
                    logging.ERROR,
                    ("accept", e.errno),
                    "the web view cannot accept a connection: %s; it tries again after pauses of up to %s",
                    e.strerror or e,
                    seconds(PAUSE_MAX_S),
                )
                await asyncio.sleep(pause)
                continue
            pause = 0.0
            try:
                await loop.connect_accepted_socket(self._connection, conn)
            except OSError as e:  # the client went away meanwhile, or no memory for it
                conn.close()
                self.limiter.log(
                    logging.WARNING, ("connect", e.errno), "the web view lost a connection: %s", e
                )

    def _loop_error(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        message = str(context.get("message", "an error"))
        self.limiter.log(
            logging.ERROR, ("loop", message), "the web view: %s", message, exc_info=context.get("exception")
        )


class _Limited(logging.Filter):
    """On uvicorn's logger: what it logs from this server's thread goes through the server's
    :class:`~cosleec.nodes.LogLimiter` (a malformed request per line no more)."""

    def __init__(self, server: Server) -> None:
        super().__init__()
        self.server = server
        self.thread: int | None = None  # the server's thread, once it runs

    def filter(self, record: logging.LogRecord) -> bool:
        if self.thread is None or record.thread != self.thread:
            return True
        self.server.limiter.log(
            record.levelno, ("uvicorn", str(record.msg)), "%s", record.getMessage(), exc_info=record.exc_info
        )
        return False

    def attach(self, thread: threading.Thread) -> None:
        """Limit what uvicorn logs on ``thread`` (started), until :meth:`detach`."""
        self.thread = thread.ident
        logging.getLogger("uvicorn.error").addFilter(self)

    def detach(self) -> None:
        logging.getLogger("uvicorn.error").removeFilter(self)
