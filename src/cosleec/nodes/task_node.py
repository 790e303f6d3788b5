"""The task-node base: layered methods dispatched by the active layer, in another process.

A task node loads the same rules, binds tasks (paper style) and capabilities, and listens
to ``obligations``. Each decision names its clause and layer; the node runs that variant
on a worker thread (so a task may block, or ask whether an action is allowed, without
stalling the middleware), and tasks report what they did on ``events``.

Each action runs at most once: the node remembers the ``(session, id, action)`` of what it
ran (the Manager node stamps its obligations with its ``session``; an action is an event
the decision obliges), so a message duplicated on the wire -- re-delivered, replayed from
a recording, forged -- is counted in ``duplicates`` and not run again. The Manager hands a
decision on in parts when some of its actions are held (forbidden for now): each part
names only its own actions and runs when it arrives; a message that repeats actions
already run runs only the others.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
import queue
import threading
from collections import OrderedDict, deque
from collections.abc import Callable
from typing import Any

from cosleec.errors import ConfigurationError, UserError
from cosleec.nodes.base import Answering, MessageError, Node
from cosleec.nodes.transport import DEFAULT_NAMESPACE, Transport
from cosleec.runtime import Capability, Decision, Implementations, RuleSet, Task

#: what :meth:`TaskNode.request` does when the Manager does not answer in time
WHEN_MANAGER_DOWN = ("refuse", "raise")

#: at most this long (s) the transport's thread waits for an idle worker to take an obligation
HANDOFF_WAIT_S = 0.002


class ManagerUnavailable(UserError):
    """The Manager did not answer a task node's request in time (``when_manager_down="raise"``).

    Raised into the task code that called :meth:`TaskNode.request`; the task node counts the
    task as failed, as for any exception of a task.
    """


class SeenDecisions:
    """The ``(session, id, action)`` of what a task node ran, in bounded memory.

    ``action`` is an event the decision obliges, or ``""`` for a decision that obliges
    none (its task method runs once all the same).

    The last ``window`` keys are remembered exactly. When one is forgotten, every id of its
    session up to it is from then on treated as seen: the Manager numbers its decisions
    upwards, so only a decision that arrives after ``window`` later ones of its session
    -- never in practice -- would be wrongly skipped, and a replay of old ones never runs.
    A new session (a restarted Manager) starts afresh; the floors of the last
    ``max_sessions`` sessions are kept. Not thread-safe: the caller holds a lock.
    """

    def __init__(self, window: int = 100_000, max_sessions: int = 64) -> None:
        if window < 1:
            raise ConfigurationError(f"the window of seen decisions must be at least 1, not {window}")
        self.window = window
        self.max_sessions = max_sessions
        self._seen: OrderedDict[tuple[str, int, str], None] = OrderedDict()
        self._floor: OrderedDict[str, int] = OrderedDict()  # session -> every id <= it counts as seen

    def add(self, session: str, decision: int, action: str = "") -> bool:
        """Remember that ``action`` of ``decision`` of ``session`` ran; False if it had (a duplicate)."""
        key = (session, decision, action)
        floor = self._floor.get(session)
        if key in self._seen or (floor is not None and decision <= floor):
            return False
        self._seen[key] = None
        if len(self._seen) > self.window:
            (old_session, old, _), _ = self._seen.popitem(last=False)
            self._floor[old_session] = max(old, self._floor.get(old_session, old))
            self._floor.move_to_end(old_session)
            if len(self._floor) > self.max_sessions:
                self._floor.popitem(last=False)
        return True

    def __len__(self) -> int:
        return len(self._seen)


class TaskNode(Node):
    """A task node: runs the implementations of some rules in its own process.

    Build it from the same rule set as the Manager, bind tasks and capabilities (an
    ``install(node)`` function of the ``--module``), then :meth:`start` it. It offers the
    part of the Manager's interface tasks use (``event``, ``request``).

    ``when_manager_down`` says what :meth:`request` does when the Manager does not answer
    within ``request_timeout`` seconds: ``"refuse"`` (the default) answers no, so the robot
    does not act; ``"raise"`` raises :class:`ManagerUnavailable` into the task. There is
    deliberately no "allow": without the Manager nobody checks the prohibitions.
    ``handled`` holds the last ``keep_handled`` decisions run; status reports the total.
    """

    name = "task"

    def __init__(
        self,
        transport: Transport,
        rules: RuleSet,
        *,
        namespace: str = DEFAULT_NAMESPACE,
        name: str = "task",
        request_timeout: float = 2.0,
        when_manager_down: str = "refuse",
        status_each: bool = False,
        keep_handled: int = 1000,
        seen_window: int = 100_000,
    ) -> None:
        if when_manager_down not in WHEN_MANAGER_DOWN:
            raise ConfigurationError(
                f"when_manager_down must be one of {', '.join(WHEN_MANAGER_DOWN)}, not {when_manager_down!r}"
            )
        super().__init__(transport, namespace)
        self.name = name
        self.status_each = status_each  # status after every handled obligation (harnesses)
        self.ruleset = rules
        self.implementations = Implementations(rules)
        if (
            isinstance(request_timeout, bool)
            or not isinstance(request_timeout, int | float)
            or not 0 < request_timeout < math.inf
        ):
            raise ConfigurationError(
                f"request_timeout must be a positive number of seconds, not {request_timeout!r}"
            )
        self.request_timeout = request_timeout
        self.when_manager_down = when_manager_down
        self._ids = itertools.count(1)
        self._replies: dict[str, tuple[threading.Event, list[bool], str]] = {}
        self._work: queue.Queue[Decision | None] = queue.Queue()
        # the hand-off (see _hand_over): the worker waits on an empty queue / has taken a decision
        self._worker_waiting = False
        self._taken = threading.Event()
        self.handled: deque[Decision] = deque(maxlen=keep_handled)  # the most recent decisions run
        self.handled_total = 0  # every decision run (status `handled`)
        self._seen = SeenDecisions(seen_window)
        self._seen_lock = threading.Lock()
        for key in ("duplicates", "request_timeouts"):
            self.counters[key] = 0
        self.answering = Answering()  # did the Manager answer the last request? (status, /diagnostics)
        for t in ("events", "request"):
            self.advertise(t)
        self._worker = threading.Thread(target=self._run, name=f"cosleec-{name}", daemon=True)
        self._worker.start()
        self.on("request_reply", self._reply)

    # the subset of the Manager's interface that tasks use (cosleec.runtime.Reporter)
    def event(self, name: str) -> None:
        """The robot did ``name``: tell the Manager."""
        self._count("reported")
        self.publish("events", {"event": name})

    def request(self, event: str) -> bool:
        """Ask the Manager whether ``event`` is allowed now.

        Blocks for up to ``request_timeout`` seconds. No answer in time (the Manager is
        down, or the graph is not connected) is counted in ``request_timeouts`` and then
        refused (returns False) or raises :class:`ManagerUnavailable`, as
        ``when_manager_down`` says. Call it from task code, which runs on the node's worker
        thread, never from a transport callback: the reply may need that very thread, and
        would then arrive only after the wait.
        """
        rid = f"{self.name}-{self.session[:12]}-{next(self._ids)}"  # unique: nodes may share a name
        self._count("requested")
        done = threading.Event()
        box: list[bool] = []
        self._replies[rid] = (done, box, event)
        try:
            self.publish("request", {"id": rid, "event": event})
            done.wait(self.request_timeout)
        finally:
            self._replies.pop(rid, None)
        if box:
            if self.answering.answered():
                self.status()  # healthy again: say so now
            return box[0]
        self._count("request_timeouts")
        then = "are refused" if self.when_manager_down == "refuse" else "raise ManagerUnavailable"
        why = f"the Manager did not answer a request within {self.request_timeout:g} s"
        if self.answering.unanswered(f"{why}: the tasks' requests {then} until it answers"):
            self.status()  # health changed: say so now, not at the next heartbeat
        self.limiter.log(
            logging.WARNING,
            "request_timeout",
            "%s: no answer from the Manager within %.1f s to a request for %s: %s",
            self.name,
            self.request_timeout,
            event,
            "refused" if self.when_manager_down == "refuse" else "raising ManagerUnavailable",
        )
        if self.when_manager_down == "raise":
            raise ManagerUnavailable(
                f"the Manager did not answer within {self.request_timeout} s whether {event!r} is allowed",
                hint="is the Manager node running, in the same namespace?",
                where=self.topic("request"),
            )
        return False

    def bind(self, *tasks: Task) -> TaskNode:
        """Bind paper-style tasks (one per rule) to this node."""
        for t in tasks:
            self.implementations.bind(t)
            t.manager = self
        return self

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        """Decorator: register the handler that performs ``event``."""
        return self.implementations.capability(event)

    def start(self, rules: list[str] | None = None) -> TaskNode:
        """Check that the bound rules are fully implemented, then start taking obligations.

        ``rules`` limits the node to those rule names (``--only``); obligations of other
        rules are left to other task nodes. BindingError lists what is missing. Returns ``self``.
        """
        chosen = [r for r in self.ruleset.rules if rules is None or r.name in rules]
        self.implementations.check(chosen)
        self.implementations.prepare(chosen)
        self.rules = {r.name for r in chosen}
        self.on("obligations", self._obligation)
        self.status()
        return self

    def _obligation(self, msg: dict[str, Any]) -> None:
        rule = msg.get("rule")
        if not isinstance(rule, str):
            raise MessageError("obligation message needs a string `rule`")
        if rule not in self.rules:
            return  # another task node's rule
        d = Decision.from_json(msg)
        session = msg.get("session", "")
        if not isinstance(session, str):
            raise MessageError("obligation `session` must be a string")
        actions = sorted({o.event for o in d.obligations if not o.negated}) or [""]
        with self._seen_lock:
            new = [a for a in actions if self._seen.add(session, d.id, a)]
        if len(new) < len(actions) and new:  # a part of it ran before: only the rest runs now
            d = dataclasses.replace(
                d, obligations=tuple(o for o in d.obligations if o.negated or o.event in new)
            )
        if not new:
            self._count("duplicates")
            self.limiter.log(
                logging.WARNING,
                "duplicate",
                "%s: decision %s of %s already taken: not run again",
                self.name,
                d.id,
                rule,
            )
            if self.status_each:
                self.status()
            return
        self._hand_over(d)

    def _hand_over(self, d: Decision) -> None:
        """Queue ``d`` for the worker; if the worker was idle, give it the CPU to take it.

        Called on the transport's thread. Left to itself that thread would go on (rebuilding
        the executor's wait set, holding the GIL) while the woken worker waits to run: the
        obligation's latency would include that. Waiting here, at most ``HANDOFF_WAIT_S``,
        for the worker to take the decision lets it start at once; the wait is bounded, so
        the transport is never held longer (never deaf), and skipped when the worker is busy
        (the decision then waits its turn in the queue anyway).
        """
        handoff = self._worker_waiting and self._work.empty()
        if handoff:
            self._taken.clear()
        self._work.put(d)
        if handoff:
            self._taken.wait(HANDOFF_WAIT_S)

    def _reply(self, msg: dict[str, Any]) -> None:
        entry = self._replies.get(str(msg.get("id")))
        if entry is not None:
            # an answer about another event is no answer (a refusal), whatever it says
            entry[1].append(msg.get("allowed") is True and msg.get("event") == entry[2])
            entry[0].set()

    def _run(self) -> None:
        while True:
            self._worker_waiting = True
            d = self._work.get()
            self._worker_waiting = False
            self._taken.set()
            if d is None:
                return
            try:
                rule = self.ruleset.rule(d.rule)
                if d.fallback:  # a fallback after a missed deadline
                    self.implementations.dispatch_fallback(rule, d)
                else:
                    self.implementations.dispatch(rule, d)
            except Exception as e:  # the dispatch guards task code; this guards the worker itself
                self._count("errors")
                self.limiter.log(
                    logging.ERROR, "worker", "%s: decision %s failed to dispatch", self.name, d.id, exc_info=e
                )
            finally:
                self.handled.append(d)
                self.handled_total += 1
            if self.status_each:
                self.status()

    def status(self, **extra: Any) -> None:
        """Publish the counters with ``handled`` (decisions run, in all) and ``failures`` (implementations raised).

        The counters include ``duplicates`` (decisions received again, not run) and
        ``request_timeouts`` (requests the Manager did not answer in time); whether the
        Manager answered the last request is ``manager_answering`` (``manager_problem`` says
        why not: ``/diagnostics`` then shows ERROR).
        """
        with self._status_lock:
            super().status(
                handled=self.handled_total,
                failures=self.implementations.failures,
                **self.answering.fields(),
                **extra,
            )

    def close(self) -> None:
        """Stop the worker once the decisions already queued have run (waits up to 5 s).

        The transport is the caller's to close.
        """
        self._work.put(None)
        self._worker.join(5)
