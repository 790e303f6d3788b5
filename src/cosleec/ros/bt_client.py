"""A behaviour tree's link to the ROS 2 Manager node: :mod:`cosleec.bt` over the middleware.

:class:`RosLink` is a :class:`cosleec.bt.Link` (by shape: this module does not import
``cosleec.bt``, and ``cosleec.bt`` never imports ROS). It asks the Manager node's
``<manager>/request`` service whether an event is permitted, its ``<manager>/decide``
service for the decisions of a trigger (the node must run with ``--decide events-only``
or ``all``), and reports what the robot did on ``<namespace>/events``, as a task node
does. What is owed is followed from the node's topics: the obligations of each decision
on ``decisions``, met by an event seen on ``events``, gone when ``violations`` reports
the miss or the Manager's time (its ``status``) passes the deadline.

It fails closed: no answer within ``timeout`` is a refusal that says so; a Decide call
that is not answered or not accepted raises :class:`cosleec.errors.UserError` with the
node's reason (the rule task turns it into FAILURE). Call it from the tree's thread, never
from a transport callback (the answer needs the executor).
"""

from __future__ import annotations

import threading
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import record, topic
from cosleec.runtime import Decision, Permission


class RosLink:
    """The Manager node as a tree's :class:`cosleec.bt.Link` (see the module).

    ``transport`` is a ROS 2 transport (:func:`cosleec.ros.transport`); ``manager`` the
    Manager node's full name (``/cosleec_manager``); ``namespace`` the one of its topics.
    """

    def __init__(
        self, transport: Any, manager: str, namespace: str = "/cosleec", timeout: float = 2.0
    ) -> None:
        self.t = transport
        self.manager = manager.rstrip("/")
        self.ns = namespace
        self.timeout = timeout
        self.now = 0.0  # the Manager's time, from its status
        self._owed: dict[tuple[int, int], dict[str, Any]] = {}
        self._lock = threading.Lock()
        self.t.advertise(topic(namespace, "events"))
        self.t.subscribe(topic(namespace, "decisions"), self._decision)
        self.t.subscribe(topic(namespace, "events"), self._event)
        self.t.subscribe(topic(namespace, "violations"), self._violation)
        self.t.subscribe(topic(namespace, "status"), self._status)

    # ------------------------------------------------------------------ the Link
    def permission(self, event: str) -> Permission:
        """Asked as :meth:`request` is: the node has one permission service, whose refusals
        it records (a question that records nothing needs a field the service lacks)."""
        return self.request(event)

    def request(self, event: str, *, source: str = "") -> Permission:
        """The node's ``request`` service; no answer in time is a refusal (fail closed)."""
        answer = self._call("request", {"event": event, "source": source})
        if answer is None:
            why = f"{event} is not permitted: the Manager ({self.manager}) did not answer within {self.timeout:g} s"
            return Permission(event, False, (), why)
        return Permission(
            event, bool(answer["permitted"]), tuple(answer.get("rules", ())), str(answer["reason"])
        )

    def event(self, name: str) -> object:
        """Report ``name`` on the ``events`` topic (the Manager records the occurrence)."""
        self.t.publish(topic(self.ns, "events"), {"event": name})
        self._met(name)
        return None

    def decide(self, trigger: str) -> list[Decision]:
        """The node's ``decide`` service with ``trigger``: its decisions (UserError when refused)."""
        answer = self._call("decide", {"values": {}, "event": trigger})
        if answer is None:
            raise UserError(
                f"the Manager ({self.manager}) did not answer Decide within {self.timeout:g} s",
                hint="is the Manager node running, and started with --decide events-only?",
            )
        if not answer.get("accepted"):
            raise UserError(str(answer.get("error") or "the Manager did not accept the trigger"))
        decisions = [Decision.from_json(d) for d in answer.get("decisions", [])]
        for d in decisions:  # its obligations are owed from now: do not wait for the topic
            self._add(d.to_json())
        return decisions

    def outstanding(self) -> list[dict[str, Any]]:
        """The obligations owed as the topics tell them (see the module), deadline not yet passed."""
        with self._lock:
            gone = [
                k for k, o in self._owed.items() if o["deadline"] is not None and o["deadline"] < self.now
            ]
            for k in gone:
                del self._owed[k]
            return [dict(o) for o in self._owed.values()]

    # ------------------------------------------------------------------ the topics
    def _call(self, kind: str, fields: dict[str, Any]) -> dict[str, Any] | None:
        done = threading.Event()
        box: list[dict[str, Any] | None] = []

        def answer(a: dict[str, Any] | None) -> None:
            box.append(a)
            done.set()

        self.t.ask(f"{self.manager}/{kind}", kind, fields, answer, self.timeout)
        done.wait(self.timeout + 1.0)
        return box[0] if box else None

    def _add(self, d: dict[str, Any]) -> None:
        """Owe the obligations of decision record ``d`` (prohibitions are not owed: they forbid)."""
        if d.get("clause") is None:
            return
        with self._lock:
            for i, ob in enumerate(d.get("obligations", [])):
                if ob.get("negated"):
                    continue
                within = ob.get("within_s")
                deadline = None if within is None else float(d["time"]) + float(within)
                self._owed.setdefault(
                    (int(d["id"]), i),
                    {
                        "id": int(d["id"]) * 1000 + i,
                        "rule": d["rule"],
                        "event": ob["event"],
                        "deadline": deadline,
                        "decision": int(d["id"]),
                        "clause": d["clause"],
                    },
                )

    def _met(self, event: str) -> None:
        with self._lock:
            for k in [k for k, o in self._owed.items() if o["event"] == event]:
                del self._owed[k]

    def _decision(self, payload: Any) -> None:
        self._add(record(payload))

    def _event(self, payload: Any) -> None:
        self._met(str(record(payload).get("event", "")))

    def _violation(self, payload: Any) -> None:
        v = record(payload)
        with self._lock:
            for k in [
                k
                for k, o in self._owed.items()
                if o["decision"] == v.get("decision") and o["event"] == v.get("event")
            ]:
                del self._owed[k]

    def _status(self, payload: Any) -> None:
        s = record(payload)
        if s.get("node") == "manager" and isinstance(s.get("time"), int | float):
            with self._lock:
                self.now = max(self.now, float(s["time"]))
