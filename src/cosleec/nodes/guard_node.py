"""The guard: enforce prohibitions on a robot's existing topics, without touching its nodes.

A robot that already has its planners and drivers should not have to rewrite them as
cosleec task nodes before a rule is enforced. The guard sits between a producer and its
consumer -- a planner's ``/planner/cmd_vel`` and the base's ``/cmd_vel`` -- and forwards
each message only while the event it stands for is permitted::

    guards:
      /planner/cmd_vel: {to: /cmd_vel, type: geometry_msgs/msg/Twist, event: MoveNearUser}
      /arm/goal:        {to: /arm/goal_checked, type: geometry_msgs/msg/Pose, event: HandOver,
                         qos: reliable}

For every message it asks the Manager (the ``~/request`` service): may this event happen
now? Permitted: the message goes on, unchanged and in order. Refused: it is dropped, and
the Manager records and publishes the refusal, with the rules that forbid it and why
(``refusals``, with this topic as its source). No answer in time, or no Manager at all:
the message is dropped too (fail closed), and the guard itself publishes that refusal.
Messages leave in the order they came, whatever order the answers come in; at most
``max_pending`` wait for an answer per route, the oldest refused first beyond that.
While the Manager does not answer, the guard's status says so (``manager_answering``
false, with the reason) and ``/diagnostics`` shows ERROR, until the next answer.
"""

from __future__ import annotations

import difflib
import logging
import math
import re
import threading
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes.base import Answering, Node
from cosleec.nodes.mapping import MappingError, read_yaml
from cosleec.nodes.qos import Qos, QosError
from cosleec.nodes.transport import DEFAULT_NAMESPACE

log = logging.getLogger("cosleec.nodes")

ROUTE_KEYS = ("to", "type", "event", "qos")
#: a guarded topic's name: absolute (a relative name could be the same topic spelt
#: otherwise: a guard that feeds itself), tokens as both ROS 2 and ROS 1 accept them
TOPIC = re.compile(r"(/[A-Za-z_][A-Za-z0-9_]*)+")


class GuardError(UserError, ValueError):
    """A guard mapping is wrong; the message names the file, the route and the fix."""


@dataclass(frozen=True)
class Route:
    """Messages of ``type`` on ``source`` go on to ``target`` only while ``event`` is permitted."""

    source: str
    target: str
    type: str
    event: str
    qos: Qos = Qos.RELIABLE


def load_routes(path: str | Path, events: frozenset[str] | None = None) -> list[Route]:
    """The ``guards`` section of a mapping file; GuardError names the file and route at fault.

    ``events`` (the rules' events) checks that each route's event is declared.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise GuardError(
            f"cannot read the mapping: {getattr(e, 'strerror', None) or e}", where=str(path)
        ) from None
    try:
        doc = read_yaml(text, str(path))  # a route given twice is an error, not the last one silently
    except MappingError as e:
        raise GuardError(str(e)) from None
    section = doc.get("guards") if isinstance(doc, dict) else None
    if not isinstance(section, dict) or not section:
        raise GuardError(
            "no `guards` section: nothing to guard",
            where=str(path),
            hint="add `guards: {/planner/cmd_vel: {to: /cmd_vel, type: geometry_msgs/msg/Twist, event: Move}}`",
        )
    return [route(str(src), spec, str(path), events) for src, spec in section.items()]


def route(source: str, spec: Any, where: str = "<guard>", events: frozenset[str] | None = None) -> Route:
    """One checked route from ``source`` with ``spec`` ``{to, type, event, qos}``."""
    at = f"{where}: guards.{source}"
    if not isinstance(spec, dict):
        raise GuardError(f"{at}: expected {{to, type, event}}")
    extra = sorted(set(spec) - set(ROUTE_KEYS))
    if extra:
        close = difflib.get_close_matches(extra[0], ROUTE_KEYS, n=1)
        raise GuardError(
            f"{at}: unknown key {extra[0]!r}",
            hint=f"did you mean {close[0]!r}?" if close else f"keys: {', '.join(ROUTE_KEYS)}",
        )
    for key in ("to", "type", "event"):
        if not isinstance(spec.get(key), str) or not spec[key]:
            raise GuardError(f"{at}: `{key}` is required and must be a string")
    for what, name in (("guarded topic", source), ("`to`", spec["to"])):
        if not TOPIC.fullmatch(name):
            raise GuardError(
                f"{at}: {what} {name!r} is not an absolute ROS topic name",
                hint="give it from the root: /planner/cmd_vel (letters, digits and _ between slashes)",
            )
    if spec["to"] == source:
        raise GuardError(f"{at}: `to` must differ from the guarded topic, or the guard would feed itself")
    if events is not None and spec["event"] not in events:
        close = difflib.get_close_matches(spec["event"], sorted(events), n=1)
        raise GuardError(
            f"{at}: the rules declare no event {spec['event']!r}",
            hint=f"did you mean {close[0]!r}?" if close else "declare it in the rules' def block",
        )
    try:
        qos = Qos.parse(spec["qos"], Qos.RELIABLE) if "qos" in spec else Qos.RELIABLE
    except QosError as e:
        raise GuardError(f"{at}: {e}") from None
    return Route(source=source, target=spec["to"], type=spec["type"], event=spec["event"], qos=qos)


class _Waiting:
    __slots__ = ("answer", "message")

    def __init__(self, message: Any) -> None:
        self.message = message
        self.answer: dict[str, Any] | None = None


class GuardNode(Node):
    """Forwards each guarded message only if the Manager permits its event now (see the module).

    ``manager`` is the Manager node's name (its services are ``<manager>/request``);
    ``timeout`` how long a message waits for the answer before it is dropped. The
    transport needs ``subscribe_raw``, ``publish_raw`` and ``ask`` (ROS 2 and ROS 1 have
    them). Counters: ``forwarded``, ``blocked``, ``unanswered`` (blocked for want of an
    answer), ``overflow`` (blocked because ``max_pending`` were waiting). Status also says
    whether the Manager answered the last question (:class:`~cosleec.nodes.base.Answering`).
    """

    name = "guard"

    def __init__(
        self,
        transport: Any,
        routes: list[Route],
        *,
        manager: str,
        namespace: str = DEFAULT_NAMESPACE,
        timeout: float = 0.5,
        max_pending: int = 100,
    ) -> None:
        if isinstance(timeout, bool) or not isinstance(timeout, int | float) or not 0 < timeout < math.inf:
            raise GuardError(f"the guard's timeout must be a positive number of seconds, not {timeout!r}")
        if isinstance(max_pending, bool) or not isinstance(max_pending, int) or max_pending < 1:
            raise GuardError(f"max_pending must be a whole number of at least 1, not {max_pending!r}")
        super().__init__(transport, namespace)
        self.io: Any = transport  # the parts of a ROS transport beyond the Transport protocol
        self.routes = routes
        self.service = f"{manager.rstrip('/')}/request"
        self.timeout = timeout
        self.max_pending = max_pending
        self._queues: dict[str, deque[_Waiting]] = {r.source: deque() for r in routes}
        self._lock = threading.Lock()
        self._sending = threading.Lock()
        self.answering = Answering()
        for key in ("forwarded", "blocked", "unanswered", "overflow"):
            self.counters[key] = 0
        self.advertise("refusals")
        # the client first: it finds the Manager's service before the first message asks it
        self.io.prepare(self.service, "request")
        for r in routes:
            # the output first: its subscribers match it before the first message is forwarded
            self.io.advertise_raw(r.target, r.type, r.qos)
            transport.subscribe_raw(r.source, r.type, lambda m, r=r: self._message(r, m), r.qos)

    def _message(self, r: Route, message: Any) -> None:
        self._count("received")
        waiting = _Waiting(message)
        dropped: _Waiting | None = None
        with self._lock:
            q = self._queues[r.source]
            q.append(waiting)
            if len(q) > self.max_pending:  # the Manager is slower than the producer: the oldest goes
                dropped = q.popleft()
        if dropped is not None:
            self._count("overflow")
            self._block(
                r,
                {
                    "permitted": False,
                    "rules": [],
                    "reason": f"more than {self.max_pending} "
                    "messages waited for the Manager's answer; the oldest was dropped",
                },
                own=True,
            )
        try:
            self.io.ask(
                self.service,
                "request",
                {"event": r.event, "source": r.source},
                lambda answer: self._answered(r, waiting, answer),
                self.timeout,
            )
        except Exception as e:  # no way to ask: no answer, so no permission (and the queue goes on)
            self.limiter.log(logging.ERROR, ("ask", r.source), "guard: cannot ask the Manager: %s", e)
            self._answered(r, waiting, None)

    def _answered(self, r: Route, waiting: _Waiting, answer: dict[str, Any] | None) -> None:
        own = answer is None
        if answer is None:  # fail closed: no Manager, no permission
            with self._lock:  # a message already dropped (overflow) was counted there
                queued = waiting in self._queues[r.source]
            if queued:
                self._count("unanswered")
            why = f"the Manager ({self.service}) did not answer within {self.timeout:g} s"
            if self.answering.unanswered(f"{why}: every guarded message is blocked until it answers"):
                self.status()  # health changed: say so now, not at the next heartbeat
            answer = {"permitted": False, "rules": [], "reason": f"{why}: blocked, as the guard fails closed"}
        elif self.answering.answered():
            self.status()
        answer["_own"] = own
        # answers come on several threads (the executor, a timeout's timer): one sends at a
        # time, from taking the ready messages off the queue to the last send, so they leave in
        # the order they came
        with self._sending:
            ready: list[_Waiting] = []
            with self._lock:
                waiting.answer = answer
                q = self._queues[r.source]
                while q and q[0].answer is not None:  # in arrival order, whatever order the answers came
                    ready.append(q.popleft())
            for w in ready:
                assert w.answer is not None
                if w.answer.get("permitted"):
                    try:
                        self.io.publish_raw(r.target, r.type, w.message, r.qos)
                    except Exception as e:  # counted and said; the next message is tried all the same
                        self._count("errors")
                        self.limiter.log(
                            logging.ERROR,
                            ("forward", r.target),
                            "guard: cannot forward to %s: %s",
                            r.target,
                            e,
                        )
                        continue
                    self._count("forwarded")
                else:
                    # the Manager publishes the refusals of its prohibitions; any other "no"
                    # (no answer, inactive, an undeclared event) only the guard can report
                    self._block(r, w.answer, own=bool(w.answer.get("_own")) or not w.answer.get("rules"))
        self._count("processed")

    def status(self, **extra: Any) -> None:
        """Publish the counters, and whether the Manager answered the last question (and if not, why)."""
        with self._status_lock:
            super().status(**self.answering.fields(), **extra)

    def _block(self, r: Route, answer: dict[str, Any], *, own: bool) -> None:
        """Count a blocked message; publish its refusal if the Manager could not (it did otherwise)."""
        self._count("blocked")
        reason = str(answer.get("reason", ""))
        self.limiter.log(
            logging.WARNING, ("blocked", r.source), "guard: blocked a message on %s: %s", r.source, reason
        )
        if own:
            self.publish(
                "refusals",
                {
                    "event": r.event,
                    "by": list(answer.get("rules", [])),
                    "reason": reason,
                    "source": r.source,
                    "topic": r.target,
                    "guard": True,
                },
            )
