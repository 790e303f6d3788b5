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
from typing import Any

from cosleec.nodes.base import Node
from cosleec.runtime.decision import Decision
from cosleec.runtime.dispatcher import Capability, TaskDispatcher
from cosleec.runtime.manager import load_rules
from cosleec.runtime.model import Obligation, compile_rules
from cosleec.runtime.tasks import Task


def decision_from_json(d: dict[str, Any]) -> Decision:
    obligations = tuple(
        Obligation(o["event"], bool(o.get("negated")), o.get("within_s"), rule=d.get("rule", ""))
        for o in d.get("obligations", [])
    )
    return Decision(
        int(d["id"]),
        float(d.get("time", 0.0)),
        str(d.get("event", "")),
        str(d["rule"]),
        d.get("clause"),
        d.get("layer"),
        str(d.get("semantics", "")),
        dict(d.get("values", {})),
        tuple((c["clause"], c["condition"], c["value"]) for c in d.get("conditions", [])),
        obligations,
        tuple(d.get("missing", [])),
        str(d.get("explanation", "")),
    )


class TaskNode(Node):
    name = "task"

    def __init__(
        self,
        transport: Any,
        rules: str,
        *,
        namespace: str = "/cosleec",
        name: str = "task",
        request_timeout: float = 2.0,
        status_each: bool = False,
    ) -> None:
        super().__init__(transport, namespace)
        self.name = name
        self.status_each = status_each  # status after every handled obligation (harnesses)
        spec, symbols = load_rules(rules)
        self.spec = spec
        self.ruleset = compile_rules(spec, symbols)
        self.dispatcher = TaskDispatcher(self.ruleset)
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

    # the subset of the Manager's interface that tasks use
    def event(self, name: str) -> None:
        self._count("reported")
        self.publish("events", {"event": name})

    report = event

    def request(self, event: str) -> bool:
        """Ask the Manager whether ``event`` is allowed now; no answer in time means no."""
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
        for t in tasks:
            self.dispatcher.bind(t)
            t.manager = self  # type: ignore[assignment]
        return self

    def capability(self, event: str) -> Any:
        return self.dispatcher.capability(event)

    def start(self, rules: list[str] | None = None) -> TaskNode:
        """Check that the bound rules are fully implemented, then start taking obligations."""
        chosen = [r for r in self.ruleset.rules if rules is None or r.name in rules]
        self.dispatcher.check(chosen)
        self.rules = {r.name for r in chosen}
        self.on("obligations", self._obligation)
        self.status()
        return self

    def _obligation(self, msg: dict[str, Any]) -> None:
        if msg.get("rule") not in self.rules:
            return  # another task node's rule
        self._work.put(decision_from_json(msg))

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
                self.dispatcher.dispatch_fallback(rule, d)
            else:
                self.dispatcher.dispatch(rule, d)
            self.handled.append(d)
            if self.status_each:
                self.status()

    def status(self, **extra: Any) -> None:
        with self._status_lock:
            super().status(handled=len(self.handled), failures=self.dispatcher.failures, **extra)

    def close(self) -> None:
        self._work.put(None)
        self._worker.join(5)


__all__ = ["Capability", "TaskNode", "decision_from_json"]
