"""What every node shares: topic names, JSON handling, rejection of bad messages, counters.

It exists so that the Manager, the Layer Manager, the Context Listener and the task nodes
behave alike on the wire: a bad message is rejected and counted, never fatal. Whatever a
message does -- not JSON, nested too deep for the parser, a number too large for a float,
a field of the wrong type, a 10 MB string -- the node rejects it and hears the next one.
"""

from __future__ import annotations

import logging
import threading
import time
import uuid
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

from cosleec.errors import UserError, clip
from cosleec.nodes.transport import DEFAULT_NAMESPACE, LATCHED, Transport, dumps, record, topic

log = logging.getLogger("cosleec.nodes")

#: a rejection's reason is cut to this many characters (a reason may echo the message)
REASON_LIMIT = 200
#: the payload excerpt published on ``rejected`` is cut to this many characters
PAYLOAD_LIMIT = 500
#: the errors a bad message is expected to cause in a handler; anything else is also
#: rejected, but logged with its traceback and counted in ``errors`` too: it is our bug
MESSAGE_FAULTS = (ValueError, TypeError, KeyError, RecursionError, OverflowError)


class MessageError(UserError, ValueError):
    """A message on a topic cannot be used (not JSON, a field missing or of the wrong type).

    Raise it from a topic handler: :meth:`Node.on` rejects the message -- logged, counted
    and published on ``rejected`` -- and the node keeps running.
    """


def excerpt(payload: Any, limit: int = PAYLOAD_LIMIT) -> str:
    """The start of a rejected payload as text (JSON for a dict), cut to ``limit``; never raises."""
    if isinstance(payload, str):
        return clip(payload, limit)
    try:
        return clip(dumps(payload) if isinstance(payload, dict) else repr(payload), limit)
    except Exception:  # nested too deep to print: say what it was
        return f"<{type(payload).__name__} that cannot be shown>"


class LogLimiter:
    """Logs at most one line per kind of trouble every ``every`` seconds, with a count of the rest.

    A broken publisher at 1 kHz, or someone flooding a topic, must not flood the log (nor
    fill the disk): the first line of a kind goes out at once, the next ones of that kind
    are held back until ``every`` seconds have passed, and the next line that goes out says
    how many were held back. The counters of the node count every one of them. Thread-safe.
    """

    #: kinds remembered at most (they are topic x error type, so few; a bound all the same)
    MAX_KINDS = 1024

    def __init__(
        self, logger: logging.Logger, every: float = 10.0, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.logger = logger
        self.every = every
        self.clock = clock
        self._last: dict[Hashable, tuple[float, int]] = {}  # kind -> (last logged at, held back since)
        self._lock = threading.Lock()

    def log(self, level: int, kind: Hashable, msg: str, *args: Any, exc_info: Any = None) -> bool:
        """Log ``msg % args`` at ``level`` unless a line of ``kind`` went out less than ``every`` s ago.

        Returns True if the line was logged.
        """
        with self._lock:
            now = self.clock()
            last = self._last.get(kind)
            if last is not None and now - last[0] < self.every:
                self._last[kind] = (last[0], last[1] + 1)
                return False
            held = last[1] if last is not None else 0
            self._last.pop(kind, None)
            if len(self._last) >= self.MAX_KINDS:
                self._last.pop(next(iter(self._last)))  # forget the kind logged longest ago
            self._last[kind] = (now, 0)
        if held:
            msg += " (%d more like it in the last %.0f s not logged)"
            args = (*args, held, self.every)
        self.logger.log(level, msg, *args, exc_info=exc_info)
        return True


class Answering:
    """Whether the Manager answered the last question a node asked it: the node's health says so.

    A guard or task node whose Manager is gone fails closed -- every guarded message
    blocked, every request refused -- and its status must say why, not "ok"
    (``/diagnostics`` shows ERROR while :meth:`fields` has ``manager_answering`` false).
    Unknown until the first question; the last question decides, so the node is healthy
    again with the first answer. Thread-safe; :meth:`answered` and :meth:`unanswered`
    return True when the state changed (the node then publishes its status at once).
    """

    def __init__(self) -> None:
        self._state: tuple[bool, str] | None = None  # (answering, why not)
        self._lock = threading.Lock()

    def answered(self) -> bool:
        """The Manager answered (yes or no); True if it had not answered before."""
        return self._set((True, ""))

    def unanswered(self, why: str) -> bool:
        """The Manager did not answer in time, or could not be asked: ``why``, and what it means."""
        return self._set((False, why))

    def _set(self, state: tuple[bool, str]) -> bool:
        with self._lock:
            changed = self._state is None or self._state[0] != state[0]
            self._state = state
        return changed

    def fields(self) -> dict[str, Any]:
        """The status fields: ``manager_answering`` (once asked) and, while false, ``manager_problem``."""
        with self._lock:
            state = self._state
        if state is None:
            return {}
        return (
            {"manager_answering": True}
            if state[0]
            else {"manager_answering": False, "manager_problem": state[1]}
        )


def context_values(msg: dict[str, Any]) -> dict[str, Any]:
    """The ``values`` of a ``context`` message (Manager and Layer Manager read the same stream)."""
    values = msg.get("values")
    if not isinstance(values, dict) or not values:
        raise MessageError("context message needs a non-empty object `values`")
    return values


#: senders remembered per topic for counting lost messages (the oldest is forgotten first)
MAX_SENDERS = 256
#: a gap in a sender's numbering larger than this is counted as out of order, not as lost
MAX_GAP = 1_000_000


class Node:
    """A node publishes and subscribes JSON objects on ``<namespace>/<name>`` topics.

    A message that is not a JSON object, or that the handler fails on in any way, is
    rejected: logged (rate-limited), counted and reported on ``rejected``; the node keeps
    running. ``session`` is a token new with every node object: a node that restarts is
    told apart from its earlier life (task nodes key decision ids by the Manager's).
    """

    name = "node"
    #: publish status after every rejection, so a harness sees counts change at once;
    #: nodes whose status is a heartbeat in deployment turn this off
    status_each = True

    def __init__(self, transport: Transport, namespace: str = DEFAULT_NAMESPACE) -> None:
        self.transport = transport
        self.namespace = namespace
        self.session = uuid.uuid4().hex
        self._sender = uuid.uuid4().hex[:16]  # numbers what this node object publishes (_from, _n)
        # errors: messages a handler failed on in a way no message should cause (our bugs)
        self.counters: dict[str, int] = {
            "received": 0,
            "processed": 0,
            "rejected": 0,
            "published": 0,
            "errors": 0,
        }
        self._count_lock = threading.Lock()
        self._status_lock = threading.RLock()  # snapshots are published in the order they are taken
        self._status_seq = 0
        self._advertised: list[str] = []  # what status reports subscriber counts for
        self.limiter = LogLimiter(log)
        self._published: dict[str, int] = {}  # per topic: the number of the last message sent
        self._publish_lock = threading.Lock()  # messages leave numbered in order
        self._heard: dict[str, OrderedDict[str, int]] = {}  # per topic, per sender: last number heard
        for t in ("rejected", "status"):
            self.advertise(t)

    def topic(self, name: str) -> str:
        """The full name of topic ``name`` under this node's namespace (``/cosleec/decisions``)."""
        return topic(self.namespace, name)

    def advertise(self, name: str) -> None:
        """Declare that this node publishes on ``name`` (latched if it is in ``LATCHED``).

        Advertise every output in the constructor: :meth:`status` reports the subscriber
        count of each advertised topic, which is how a harness sees the graph is connected.
        """
        self.transport.advertise(self.topic(name), latched=name in LATCHED)
        self._advertised.append(name)

    def publish(self, name: str, message: dict[str, Any]) -> None:
        """Send ``message`` as JSON on topic ``name`` and count it (values JSON lacks go as ``str``).

        Each message carries its sender (``_from``, this node's session) and its number on
        the topic (``_n``, 1, 2, ...): a receiver counts the numbers it never saw as ``lost``
        (a middleware that drops messages under load says so nowhere else).
        """
        full = self.topic(name)
        with self._publish_lock:
            n = self._published[full] = self._published.get(full, 0) + 1
            self.transport.publish(full, {**message, "_from": self._sender, "_n": n})
        self._count("published")

    def _heard_from(self, where: str, message: dict[str, Any]) -> None:
        """Count the messages of ``message``'s sender on ``where`` that never arrived (``lost``)
        or arrived late or twice (``out_of_order``); takes the numbering fields out."""
        sender, n = message.pop("_from", None), message.pop("_n", None)
        if not isinstance(sender, str) or isinstance(n, bool) or not isinstance(n, int) or not 0 < n < 2**53:
            return  # not from a cosleec node (a hand-written or forged message): nothing to check
        with self._count_lock:
            senders = self._heard.setdefault(where, OrderedDict())
            last = senders.pop(sender[:64], None)
            if last is not None and last + 1 < n <= last + MAX_GAP:
                self.counters["lost"] = self.counters.get("lost", 0) + n - last - 1
            elif last is not None and n != last + 1:  # again, late, or a jump no middleware loss makes
                self.counters["out_of_order"] = self.counters.get("out_of_order", 0) + 1
            senders[sender[:64]] = max(n, last or 0)
            if len(senders) > MAX_SENDERS:
                senders.popitem(last=False)

    def on(self, name: str, handler: Callable[[dict[str, Any]], None]) -> None:
        """Call ``handler`` with every JSON object received on topic ``name``.

        A payload that is not a JSON object, or that the handler fails on with any
        Exception, is rejected (:meth:`reject_error`) and the node carries on: one bad
        message must never stop the transport's thread, or the node would go deaf while
        its heartbeat still said it was alive. The handler runs on a thread of the
        transport, not the caller's.
        """
        full = self.topic(name)

        def receive(payload: Any) -> None:
            self._count("received")
            try:
                message = record(payload)
                if not isinstance(message, dict):
                    raise MessageError("expected a JSON object")
                self._heard_from(full, message)
                handler(message)
            except Exception as e:
                self.reject_error(full, e, payload)
            finally:
                self._count("processed")  # after its handler and what it published: a harness waits for this
                self.after_message()

        self.transport.subscribe(full, receive)

    def after_message(self) -> None:
        """Called once each message on a topic of :meth:`on` is handled (or rejected); nothing here."""

    def reject_error(self, where: str, error: Exception, payload: Any) -> None:
        """Reject a message on ``where`` that raised ``error``: :meth:`reject` with its reason.

        An error outside :data:`MESSAGE_FAULTS` is a bug of ours rather than of the
        message: it is also counted in ``errors`` and logged with its traceback.
        """
        if isinstance(error, MESSAGE_FAULTS):
            self.reject(where, str(error) or type(error).__name__, payload, kind=type(error).__name__)
            return
        self._count("errors")
        self.reject(
            where, f"{type(error).__name__}: {error}", payload, kind=type(error).__name__, exc_info=error
        )

    def reject(
        self,
        where: str,
        reason: str,
        payload: Any,
        *,
        kind: Hashable = "rejected",
        exc_info: BaseException | None = None,
    ) -> None:
        """Count, log and publish on ``rejected`` a message this node cannot use.

        ``where`` is the topic it came from. The reason is cut to :data:`REASON_LIMIT`
        characters and the payload to :data:`PAYLOAD_LIMIT`, so a huge message makes a short
        report. The log is rate-limited per ``where`` and ``kind`` (:class:`LogLimiter`);
        the count and the ``rejected`` message are not. With ``status_each`` a status
        message follows at once.
        """
        self._count("rejected")
        reason = clip(reason, REASON_LIMIT)
        level = logging.ERROR if exc_info is not None else logging.WARNING
        self.limiter.log(
            level,
            (where, kind),
            "%s: rejected message on %s: %s",
            self.name,
            where,
            reason,
            exc_info=exc_info,
        )
        self.publish(
            "rejected", {"node": self.name, "topic": where, "reason": reason, "payload": excerpt(payload)}
        )
        if self.status_each:
            self.status()  # the count just changed: say so

    def _count(self, key: str, n: int = 1) -> None:
        with self._count_lock:
            self.counters[key] = self.counters.get(key, 0) + n

    def status(self, **extra: Any) -> None:
        """Publish the node's counters on ``status``; snapshots go out in the order they are taken.

        ``extra`` fields join the message, with the subscriber count of every advertised
        topic when the transport can tell, and what the transport says of its own health:
        ``executor_alive`` (False once the thread that delivers messages has stopped: the
        node is deaf), ``transport_errors`` (callbacks that raised into the transport) and
        ``transport_lost`` (messages the middleware reports lost). The counters include
        ``lost`` and ``out_of_order``: messages of cosleec senders that never arrived, or
        arrived late or twice, by the numbers every node puts on what it publishes.
        :func:`cosleec.ros.serve` calls it every 0.5 s as a heartbeat.
        """
        with self._status_lock:
            with self._count_lock:
                counters = dict(self.counters)
            subs = {}
            count = getattr(self.transport, "subscribers", None)
            if count is not None:  # who listens to what this node publishes: is the graph complete?
                subs = {n: count(self.topic(n)) for n in self._advertised}
            health: dict[str, Any] = {}
            alive = getattr(self.transport, "alive", None)
            if alive is not None:
                health["executor_alive"] = bool(alive())
            errors = getattr(self.transport, "errors", None)
            if isinstance(errors, int):
                health["transport_errors"] = errors
            incompatible = getattr(self.transport, "incompatible", None)
            if isinstance(incompatible, int):  # peers whose QoS can never match ours (ROS 2)
                health["qos_incompatible"] = incompatible
            lost = getattr(self.transport, "lost", None)
            if isinstance(lost, int):
                health["transport_lost"] = lost  # what the middleware itself says it dropped
            self._status_seq += 1
            message = {
                "node": self.name,
                "seq": self._status_seq,
                "session": self.session,
                "counters": counters,
                "subscribers": subs,
                **health,
            }
            self.publish("status", {**message, **extra})
