"""Drive a running CO-SLEEC system through a scenario over the middleware, and watch it.

Used by ``cosleec ros2 demo`` and by the end-to-end tests. Between steps the driver waits
until the system is quiet -- the Manager has handled every message sent to it (by the
driver and by the task nodes) and the task nodes have handled every obligation -- because
separate topics carry no ordering guarantee between them.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from cosleec.demo import Step, play
from cosleec.nodes import record, topic


class Driver:
    """Plays scenario steps into a running system and collects everything the nodes publish.

    Call :meth:`ready` before the first step. Each step publishes one message and waits
    until the system is quiet, so ``decisions``, ``obligations``, ``violations`` and
    ``rejected`` are complete after it. Expects a Manager in simulated time
    (``--sim-time``), as :class:`cosleec.ros.demo.System` starts it; ``--status-each`` on the
    Manager and task nodes makes the waits short. ``tasks`` names the task nodes to wait for.
    """

    def __init__(
        self, transport: Any, namespace: str = "/cosleec", tasks: tuple[str, ...] = ("task",)
    ) -> None:
        self.t = transport
        self.ns = namespace
        self.tasks = tasks
        self.sent = 0
        self.now = 0.0
        self.decisions: list[dict[str, Any]] = []
        self.obligations: list[dict[str, Any]] = []
        self.violations: list[dict[str, Any]] = []
        self.rejected: list[dict[str, Any]] = []
        self.replies: dict[str, dict[str, Any]] = {}
        self.layers_message: dict[str, Any] = {}
        self.status: dict[str, dict[str, Any]] = {}
        self._lock = threading.Condition()
        for name in ("context", "events", "clock", "request"):
            self.t.advertise(topic(namespace, name))
        for name, sink in (
            ("decisions", self.decisions),
            ("obligations", self.obligations),
            ("violations", self.violations),
            ("rejected", self.rejected),
        ):
            self.t.subscribe(topic(namespace, name), self._collector(sink))
        self.t.subscribe(topic(namespace, "status"), self._status)
        self.t.subscribe(topic(namespace, "layers"), self._layers)
        self.t.subscribe(topic(namespace, "request_reply"), self._reply)

    def _collector(self, sink: list[dict[str, Any]]) -> Any:
        def collect(payload: Any) -> None:
            with self._lock:
                sink.append(record(payload))
                self._lock.notify_all()

        return collect

    def _status(self, payload: Any) -> None:
        msg = record(payload)
        with self._lock:
            old = self.status.get(msg["node"])
            if old is None or msg.get("seq", 0) >= old.get("seq", 0):
                self.status[msg["node"]] = msg
            self._lock.notify_all()

    def _layers(self, payload: Any) -> None:
        with self._lock:
            self.layers_message = record(payload)
            self._lock.notify_all()

    def _reply(self, payload: Any) -> None:
        msg = record(payload)
        with self._lock:
            self.replies[str(msg["id"])] = msg
            self._lock.notify_all()

    # ------------------------------------------------------------------ waiting
    def wait(self, predicate: Any, timeout: float = 20.0, what: str = "condition") -> None:
        """Block until ``predicate()`` holds, checked under the driver's lock as messages arrive.

        TimeoutError after ``timeout`` seconds, naming ``what`` and the last status of
        every node.
        """
        deadline = time.monotonic() + timeout
        with self._lock:
            while not predicate():
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"timed out waiting for {what}; status: {self.status}")
                self._lock.wait(min(left, 0.2))

    def ready(self, timeout: float = 30.0, layers: bool = True) -> None:
        """Wait until every node is up and every connection of the graph is made.

        ROS 1 delivers nothing to a subscriber whose connection is not yet set up, and ROS 2
        nothing before discovery: a message sent earlier would be lost.
        """
        n = len(self.tasks)

        def connected() -> bool:
            m = self.status.get("manager")
            if (
                m is None
                or any(t not in self.status for t in self.tasks)
                or (layers and "layers" not in self.status)
            ):
                return False
            if m.get("lifecycle", "active") != "active":  # a lifecycle Manager not yet enforcing
                return False
            ms = m.get("subscribers", {})
            if (
                ms.get("obligations", 0) < n
                or ms.get("request_reply", 0) < n + 1
                or ms.get("decisions", 0) < 1
            ):
                return False
            for t in self.tasks:
                ts = self.status[t].get("subscribers", {})
                if ts.get("events", 0) < 1 or ts.get("request", 0) < 1:
                    return False
            return True

        self.wait(connected, timeout, "every node to connect")
        want = {"context": 2 if layers else 1, "events": 1, "clock": 1, "request": 1}
        end = time.monotonic() + timeout
        for name, k in want.items():
            while self.t.subscribers(topic(self.ns, name)) < k:
                if time.monotonic() > end:
                    raise TimeoutError(f"nobody subscribes to {name}")
                time.sleep(0.02)

    def quiet(self, timeout: float = 20.0) -> None:
        """Wait until the Manager has received every message sent to it and the tasks ran every obligation.

        Messages to the Manager come from this driver and from the task nodes (reports and
        requests); every decision the Manager counted must have reached this driver too.
        Each step waits for it before the next is sent, so a task's report is never
        overtaken by the next clock message or context update: with the Manager in
        simulated time, the run then has the outcome of the embedded one, whatever the
        timing. TimeoutError if that does not happen within ``timeout`` seconds.
        """

        def settled() -> bool:
            m = self.status.get("manager")
            if m is None:
                return False
            task_msgs = 0
            handled = 0
            for name in self.tasks:
                s = self.status.get(name, {})
                c = s.get("counters", {})
                task_msgs += c.get("reported", 0) + c.get("requested", 0)
                handled += s.get("handled", 0) + c.get("duplicates", 0)  # a duplicate is handled too
            # every message to the Manager handled, and every obligation it sent handled by a task
            # handled, not just received: a report still in its handler has changed nothing yet
            received: int = m["counters"].get("processed", m["counters"]["received"])
            published: int = m["counters"].get("obligations", 0)
            # ...and every decision it counted published (obligations go out just before): a
            # report whose decision is still on its way is not yet in `published`
            delivered = len(self.decisions) >= m.get("stats", {}).get("decisions", 0)
            # (with no task nodes, nobody handles obligations: only the Manager's side counts)
            return (
                received == self.sent + task_msgs and (handled == published or not self.tasks) and delivered
            )

        self.wait(settled, timeout, "the system to settle")

    # ------------------------------------------------------------------ steps
    def _send(self, name: str, message: dict[str, Any]) -> None:
        self.raw(name, message)

    def set(self, values: dict[str, Any]) -> None:
        """Publish one atomic context update and wait until the system is quiet."""
        self._send("context", {"values": values})
        self.quiet()

    def event(self, name: str) -> None:
        """Publish the event ``name`` and wait until the system is quiet."""
        self._send("events", {"event": name})
        self.quiet()

    def advance(self, seconds: float) -> None:
        """Move simulated time forward by ``seconds`` on the ``clock`` topic and wait until quiet."""
        self.now += seconds
        self._send("clock", {"t": self.now})
        self.quiet()

    def request(self, event: str, settle: bool = True) -> bool:
        """Ask the Manager whether ``event`` may happen now and return its answer.

        With ``settle`` it also waits until the system is quiet afterwards.
        """
        rid = f"driver-{self.sent}"
        self._send("request", {"id": rid, "event": event})
        self.wait(lambda: rid in self.replies, what=f"reply to {rid}")
        if settle:
            self.quiet()
        return bool(self.replies[rid]["allowed"])

    def raw(self, name: str, payload: dict[str, Any] | str) -> None:
        """Publish a record, or anything as JSON text (tests of bad input, on the JSON wire): counted as sent."""
        self.sent += 1
        self.t.publish(topic(self.ns, name), payload)

    def run(self, steps: list[Step], on_step: Any = None) -> None:
        """Play ``steps`` (kinds set, event, advance, request); ``on_step(now, step)`` runs before each.

        ValueError for a step kind the driver cannot play (``fail``/``recover`` exist only
        in the embedded demo).
        """
        actions = {"set": self.set, "event": self.event, "advance": self.advance, "request": self.request}
        play(steps, actions, lambda: self.now, on_step)  # type: ignore[arg-type]
