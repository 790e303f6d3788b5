"""The task-node base: layered methods dispatched by the active layer, in another process.

A task node loads the same rules, binds tasks (paper style) and capabilities, and listens
to ``obligations``. Each decision names its clause and layer; the node runs that variant
on a worker thread (so a task may block, or ask whether an action is allowed, without
stalling the middleware), and tasks report what they did on ``events``.
"""

from __future__ import annotations

import itertools
import queue
import threading
from collections.abc import Callable
from typing import Any

from cosleec.nodes.base import Node
from cosleec.nodes.transport import DEFAULT_NAMESPACE, Transport
from cosleec.runtime import Capability, Decision, Implementations, RuleSet, Task


class TaskNode(Node):
    """A task node: runs the implementations of some rules in its own process.

    Build it from the same rule set as the Manager, bind tasks and capabilities (an
    ``install(node)`` function of the ``--module``), then :meth:`start` it. It offers the
    part of the Manager's interface tasks use (``event``, ``request``).
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
        status_each: bool = False,
    ) -> None:
        super().__init__(transport, namespace)
        self.name = name
        self.status_each = status_each  # status after every handled obligation (harnesses)
        self.ruleset = rules
        self.implementations = Implementations(rules)
        self.request_timeout = request_timeout
        self._ids = itertools.count(1)
        self._replies: dict[str, tuple[threading.Event, list[bool]]] = {}
        self._work: queue.Queue[Decision | None] = queue.Queue()
        self.handled: list[Decision] = []
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
        """Ask the Manager whether ``event`` is allowed now; no answer in time means no.

        Blocks for up to ``request_timeout`` seconds. Call it from task code, which runs on
        the node's worker thread, never from a transport callback: the reply may need that
        very thread, and would then arrive only after the wait.
        """
        rid = f"{self.name}-{next(self._ids)}"
        self._count("requested")
        done = threading.Event()
        box: list[bool] = []
        self._replies[rid] = (done, box)
        self.publish("request", {"id": rid, "event": event})
        done.wait(self.request_timeout)
        self._replies.pop(rid, None)
        return bool(box and box[0])

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
        if msg.get("rule") not in self.rules:
            return  # another task node's rule
        self._work.put(Decision.from_json(msg))

    def _reply(self, msg: dict[str, Any]) -> None:
        entry = self._replies.get(str(msg.get("id")))
        if entry is not None:
            entry[1].append(bool(msg.get("allowed")))
            entry[0].set()

    def _run(self) -> None:
        while True:
            d = self._work.get()
            if d is None:
                return
            rule = self.ruleset.rule(d.rule)
            if d.event == "otherwise":  # a fallback after a missed deadline
                self.implementations.dispatch_fallback(rule, d)
            else:
                self.implementations.dispatch(rule, d)
            self.handled.append(d)
            if self.status_each:
                self.status()

    def status(self, **extra: Any) -> None:
        """Publish the counters with ``handled`` (decisions run) and ``failures`` (implementations raised)."""
        with self._status_lock:
            super().status(handled=len(self.handled), failures=self.implementations.failures, **extra)

    def close(self) -> None:
        """Stop the worker once the decisions already queued have run (waits up to 5 s).

        The transport is the caller's to close.
        """
        self._work.put(None)
        self._worker.join(5)

