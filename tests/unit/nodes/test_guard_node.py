"""The guard node: forwards a guarded topic's messages only when the Manager permits their event,
in arrival order whatever order the answers come in, failing closed; and the checks of its
routes (``route``, ``load_routes``).

The transport is a fake of a ROS transport's extra parts: ``subscribe_raw`` hands the test
each route's handler, ``publish_raw`` records what was forwarded, and ``ask`` keeps each
question so that the test answers it -- in any order, or with None (no answer in time).
The cosleec topics go over a :class:`LocalBus`.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import random
import re
import threading
from collections.abc import Callable
from dataclasses import FrozenInstanceError, dataclass
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.errors import UserError
from cosleec.nodes import LocalBus, ManagerNode
from cosleec.nodes.guard_node import GuardError, GuardNode, Route, load_routes, route
from cosleec.nodes.qos import Qos
from cosleec.runtime import RuleSet

from .support import collect, unnumbered

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "ros" / "vacuum"
VACUUM = RuleSet.from_file(EXAMPLE / "rules.sleec")

PERMITTED: dict[str, Any] = {"permitted": True, "rules": [], "reason": "permitted"}
REFUSED: dict[str, Any] = {"permitted": False, "rules": ["R3"], "reason": "forbidden by R3 until 30 s"}


@dataclass
class Ask:
    """One question the guard asked, for the test to answer."""

    name: str
    kind: str
    fields: dict[str, Any]
    answer: Callable[[dict[str, Any] | None], None]
    timeout: float


class FakeRos:
    """A LocalBus transport with the parts of a ROS transport the guard needs beyond it."""

    def __init__(self, bus: LocalBus, *, answer_at_once: dict[str, Any] | str | None = "no") -> None:
        self.local = bus.transport()
        self.raw: dict[str, tuple[str, Callable[[Any], None], Any]] = {}
        self.forwarded: list[tuple[str, str, Any, Any]] = []
        self.asks: list[Ask] = []
        self.published: list[tuple[str, dict[str, Any]]] = []
        self.advertised: list[tuple[str, bool]] = []
        # "no": keep the question; anything else: answer it inside ask (as ROS 2 does with
        # None when the service is not there)
        self.answer_at_once = answer_at_once
        self.lock = threading.Lock()
        self.outputs: list[tuple[str, str, Any]] = []  # advertise_raw: the guard's outputs
        self.prepared: list[tuple[str, str]] = []  # the service clients made at start

    # the Transport protocol, on the bus
    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        record = json.loads(message) if isinstance(message, str) else dict(message)
        with self.lock:
            self.published.append((topic, unnumbered(record)))
        self.local.publish(topic, message)

    def subscribe(self, topic: str, handler: Callable[[Any], None]) -> None:
        self.local.subscribe(topic, handler)

    def subscribe_typed(
        self, topic: str, type_name: str, handler: Callable[[dict[str, Any]], None], qos: Qos | None = None
    ) -> None:
        self.local.subscribe_typed(topic, type_name, handler, qos)

    def advertise_raw(self, topic: str, type_name: str, qos: Any) -> None:
        with self.lock:
            self.outputs.append((topic, type_name, qos))

    def advertise(self, topic: str, latched: bool = False) -> None:
        self.advertised.append((topic, latched))
        self.local.advertise(topic, latched)

    def close(self) -> None:
        self.local.close()

    # the ROS transports' extras
    def subscribe_raw(self, topic: str, type_name: str, handler: Callable[[Any], None], qos: Any) -> None:
        assert topic not in self.raw, f"{topic} subscribed twice"
        self.raw[topic] = (type_name, handler, qos)

    def publish_raw(self, topic: str, type_name: str, data: Any, qos: Any) -> None:
        with self.lock:
            self.forwarded.append((topic, type_name, data, qos))

    def prepare(self, name: str, kind: str) -> None:
        with self.lock:
            self.prepared.append((name, kind))

    def ask(
        self,
        name: str,
        kind: str,
        fields: dict[str, Any],
        answer: Callable[[dict[str, Any] | None], None],
        timeout: float,
    ) -> None:
        if self.answer_at_once != "no":
            a = self.answer_at_once
            answer(dict(a) if isinstance(a, dict) else None)
            return
        with self.lock:
            self.asks.append(Ask(name, kind, fields, answer, timeout))

    # for the test
    def send(self, topic: str, message: Any) -> None:
        """A message arrives on the robot's topic ``topic``."""
        self.raw[topic][1](message)

    def data(self) -> list[Any]:
        """What was forwarded, the messages only."""
        return [f[2] for f in self.forwarded]

    def refusals(self, namespace: str = "/cosleec") -> list[dict[str, Any]]:
        return [m for t, m in self.published if t == f"{namespace}/refusals"]


CMD = Route(
    source="/planner/cmd_vel", target="/cmd_vel", type="geometry_msgs/msg/Twist", event="MoveNearUser"
)
ARM = Route(
    source="/arm/goal",
    target="/arm/goal_checked",
    type="geometry_msgs/msg/Pose",
    event="HandOver",
    qos=Qos.SENSOR_DATA,
)


def guard(bus: LocalBus, routes: list[Route] | None = None, **kw: Any) -> tuple[GuardNode, FakeRos]:
    answer_at_once = kw.pop("answer_at_once", "no")
    t = FakeRos(bus, answer_at_once=answer_at_once)
    kw.setdefault("manager", "/cosleec_manager")
    return GuardNode(t, routes if routes is not None else [CMD], **kw), t


def twist(i: int) -> dict[str, Any]:
    return {"linear": {"x": float(i)}, "angular": {"z": 0.0}}


# ----------------------------------------------------------------------------- wiring


def test_it_subscribes_each_route_with_its_type_and_qos_and_advertises_refusals(bus: LocalBus) -> None:
    node, t = guard(bus, [CMD, ARM], namespace="/robot1")
    assert set(t.raw) == {"/planner/cmd_vel", "/arm/goal"}
    assert t.raw["/planner/cmd_vel"][0] == "geometry_msgs/msg/Twist"
    assert t.raw["/planner/cmd_vel"][2] == Qos.RELIABLE
    assert t.raw["/arm/goal"][0] == "geometry_msgs/msg/Pose"
    assert t.raw["/arm/goal"][2] == Qos.SENSOR_DATA
    assert ("/robot1/refusals", False) in t.advertised
    # each output is advertised at start, so its subscribers have matched it before a message goes
    assert t.outputs == [
        ("/cmd_vel", "geometry_msgs/msg/Twist", Qos.RELIABLE),
        ("/arm/goal_checked", "geometry_msgs/msg/Pose", Qos.SENSOR_DATA),
    ]
    for key in ("forwarded", "blocked", "unanswered", "overflow"):
        assert node.counters[key] == 0


@pytest.mark.parametrize("manager", ["/cosleec_manager", "/cosleec_manager/"])
def test_it_asks_the_managers_request_service_about_the_routes_event(bus: LocalBus, manager: str) -> None:
    node, t = guard(bus, [CMD, ARM], manager=manager, timeout=0.25)
    assert node.service == "/cosleec_manager/request"
    # its client is made when it starts: a client made at the first message finds no service
    # yet (ROS 2), and that message would be blocked for no reason
    assert t.prepared == [("/cosleec_manager/request", "request")] and t.asks == []
    t.send("/arm/goal", {"x": 1})
    t.send("/planner/cmd_vel", twist(1))
    assert [(a.name, a.kind, a.fields, a.timeout) for a in t.asks] == [
        ("/cosleec_manager/request", "request", {"event": "HandOver", "source": "/arm/goal"}, 0.25),
        (
            "/cosleec_manager/request",
            "request",
            {"event": "MoveNearUser", "source": "/planner/cmd_vel"},
            0.25,
        ),
    ]
    assert node.counters["received"] == 2
    assert t.forwarded == []  # nothing leaves before the answer


# ----------------------------------------------------------------------------- one message


def test_a_permitted_message_goes_on_unchanged_to_its_target(bus: LocalBus) -> None:
    node, t = guard(bus, [ARM])
    msg = {"position": {"x": 1.0}}
    t.send("/arm/goal", msg)
    t.asks[0].answer(dict(PERMITTED))
    assert t.forwarded == [("/arm/goal_checked", "geometry_msgs/msg/Pose", msg, Qos.SENSOR_DATA)]
    assert t.forwarded[0][2] is msg  # the very message, not a copy or a re-encoding
    assert node.counters["forwarded"] == 1
    assert node.counters["blocked"] == node.counters["unanswered"] == node.counters["overflow"] == 0
    assert node.counters["processed"] == 1
    assert t.refusals() == []


def test_a_refusal_by_the_manager_blocks_and_is_not_published_again_by_the_guard(bus: LocalBus) -> None:
    node, t = guard(bus)
    refusals = collect(bus, "/cosleec/refusals")
    t.send("/planner/cmd_vel", twist(1))
    t.asks[0].answer(dict(REFUSED))
    assert bus.wait_idle()
    assert t.forwarded == []
    assert node.counters["blocked"] == 1
    assert node.counters["unanswered"] == 0 and node.counters["overflow"] == 0
    assert node.counters["forwarded"] == 0
    assert refusals == []  # the Manager published it, with the rules: not twice


@pytest.mark.parametrize("answer", [{"rules": [], "reason": "no permitted field"}, {"permitted": None}, {}])
def test_an_answer_that_does_not_say_permitted_blocks(bus: LocalBus, answer: dict[str, Any]) -> None:
    node, t = guard(bus)
    t.send("/planner/cmd_vel", twist(1))
    t.asks[0].answer(answer)
    assert t.forwarded == [] and node.counters["blocked"] == 1


def test_no_answer_blocks_and_the_guard_publishes_the_refusal_itself(bus: LocalBus) -> None:
    node, t = guard(bus, namespace="/robot1", timeout=0.25)
    refusals = collect(bus, "/robot1/refusals")
    elsewhere = collect(bus, "/cosleec/refusals")
    t.send("/planner/cmd_vel", twist(1))
    t.asks[0].answer(None)
    assert bus.wait_idle()
    assert t.forwarded == []
    assert node.counters["blocked"] == 1 and node.counters["unanswered"] == 1
    assert node.counters["forwarded"] == 0 and node.counters["overflow"] == 0
    assert len(refusals) == 1 and elsewhere == []
    r = refusals[0]
    assert r["event"] == "MoveNearUser"
    assert r["by"] == []
    assert r["source"] == "/planner/cmd_vel"
    assert r["topic"] == "/cmd_vel"
    assert r["guard"] is True
    assert "/cosleec_manager/request" in r["reason"]
    assert "did not answer within 0.25 s" in r["reason"]
    assert "fails closed" in r["reason"]


def test_when_ask_answers_none_at_once_the_guard_fails_closed_without_deadlock(bus: LocalBus) -> None:
    # ROS 2's ask answers None inside the call when the service is not there at all
    node, t = guard(bus, answer_at_once=None)
    for i in range(3):
        t.send("/planner/cmd_vel", twist(i))
    assert t.forwarded == []
    assert node.counters["blocked"] == node.counters["unanswered"] == 3
    assert len(t.refusals()) == 3


def test_when_ask_permits_at_once_each_message_goes_at_once(bus: LocalBus) -> None:
    node, t = guard(bus, answer_at_once=PERMITTED)
    for i in range(3):
        t.send("/planner/cmd_vel", twist(i))
        assert t.data() == [twist(j) for j in range(i + 1)]
    assert node.counters["forwarded"] == 3


# ----------------------------------------------------------------------------- order


@pytest.mark.parametrize("order", list(itertools.permutations(range(3))))
def test_messages_leave_in_arrival_order_whatever_order_the_answers_come_in(
    bus: LocalBus, order: tuple[int, ...]
) -> None:
    node, t = guard(bus)
    for i in range(3):
        t.send("/planner/cmd_vel", twist(i))
    answered: set[int] = set()
    for i in order:
        t.asks[i].answer(dict(PERMITTED))
        answered.add(i)
        prefix = 0
        while prefix in answered:
            prefix += 1
        # exactly the longest answered prefix has left, nothing after a message still waiting
        assert t.data() == [twist(j) for j in range(prefix)], (order, i)
    assert node.counters["forwarded"] == 3


def test_a_blocked_message_does_not_hold_up_the_ones_after_it(bus: LocalBus) -> None:
    node, t = guard(bus)
    for i in range(4):
        t.send("/planner/cmd_vel", twist(i))
    t.asks[3].answer(dict(PERMITTED))
    t.asks[1].answer(dict(REFUSED))
    t.asks[2].answer(None)
    assert t.data() == []  # 0 still waits
    t.asks[0].answer(dict(PERMITTED))
    assert t.data() == [twist(0), twist(3)]
    assert node.counters["forwarded"] == 2
    assert node.counters["blocked"] == 2 and node.counters["unanswered"] == 1
    assert len(t.refusals()) == 1 and t.refusals()[0]["source"] == "/planner/cmd_vel"


def test_each_route_keeps_its_own_order_one_waiting_does_not_hold_up_another(bus: LocalBus) -> None:
    node, t = guard(bus, [CMD, ARM])
    t.send("/planner/cmd_vel", twist(0))  # waits
    t.send("/arm/goal", {"p": 1})
    t.asks[1].answer(dict(PERMITTED))
    assert t.forwarded == [("/arm/goal_checked", "geometry_msgs/msg/Pose", {"p": 1}, Qos.SENSOR_DATA)]
    t.asks[0].answer(dict(PERMITTED))
    assert t.forwarded[-1] == ("/cmd_vel", "geometry_msgs/msg/Twist", twist(0), Qos.RELIABLE)
    assert node.counters["forwarded"] == 2


ANSWER = st.sampled_from(["permit", "refuse", "none"])


@settings(max_examples=150, deadline=None)
@given(
    answers=st.lists(ANSWER, min_size=1, max_size=8),
    seed=st.integers(0, 2**32 - 1),
)
def test_property_released_in_order_permitted_forwarded_and_counters_add_up(
    answers: list[str], seed: int
) -> None:
    bus = LocalBus()
    try:
        node, t = guard(bus)
        n = len(answers)
        for i in range(n):
            t.send("/planner/cmd_vel", {"i": i})
        order = list(range(n))
        random.Random(seed).shuffle(order)
        done: set[int] = set()
        for i in order:
            a = answers[i]
            t.asks[i].answer(dict(PERMITTED) if a == "permit" else dict(REFUSED) if a == "refuse" else None)
            done.add(i)
            prefix = 0
            while prefix in done:
                prefix += 1
            expected = [{"i": j} for j in range(prefix) if answers[j] == "permit"]
            assert t.data() == expected
        assert node.counters["forwarded"] == answers.count("permit")
        assert node.counters["blocked"] == answers.count("refuse") + answers.count("none")
        assert node.counters["unanswered"] == answers.count("none")
        assert node.counters["overflow"] == 0
        assert node.counters["received"] == node.counters["processed"] == n
        # the guard's own refusals: one per unanswered message, in arrival order
        assert len(t.refusals()) == answers.count("none")
    finally:
        bus.close()


# ----------------------------------------------------------------------------- overflow


def test_up_to_max_pending_may_wait_without_overflow(bus: LocalBus) -> None:
    node, t = guard(bus, max_pending=2)
    t.send("/planner/cmd_vel", twist(0))
    t.send("/planner/cmd_vel", twist(1))
    assert node.counters["overflow"] == 0 and node.counters["blocked"] == 0
    assert t.refusals() == []
    for a in t.asks:
        a.answer(dict(PERMITTED))
    assert t.data() == [twist(0), twist(1)]


def test_beyond_max_pending_the_oldest_is_dropped_with_its_own_refusal(bus: LocalBus) -> None:
    node, t = guard(bus, max_pending=2)
    refusals = collect(bus, "/cosleec/refusals")
    for i in range(3):
        t.send("/planner/cmd_vel", twist(i))
    assert bus.wait_idle()
    assert node.counters["overflow"] == 1 and node.counters["blocked"] == 1
    assert len(t.asks) == 3  # the newest was asked about all the same
    assert len(refusals) == 1
    r = refusals[0]
    assert r["event"] == "MoveNearUser" and r["by"] == [] and r["guard"] is True
    assert r["source"] == "/planner/cmd_vel" and r["topic"] == "/cmd_vel"
    assert "more than 2 messages waited" in r["reason"] and "oldest was dropped" in r["reason"]
    # the dropped one's answer, when it comes, sends nothing; the others go in order
    t.asks[0].answer(dict(PERMITTED))
    assert t.data() == []
    t.asks[2].answer(dict(PERMITTED))
    assert t.data() == []
    t.asks[1].answer(dict(PERMITTED))
    assert t.data() == [twist(1), twist(2)]
    assert node.counters["forwarded"] == 2


def test_overflow_keeps_dropping_the_oldest(bus: LocalBus) -> None:
    node, t = guard(bus, max_pending=1)
    for i in range(4):
        t.send("/planner/cmd_vel", twist(i))
    assert node.counters["overflow"] == 3 and node.counters["blocked"] == 3
    for a in t.asks:
        a.answer(dict(PERMITTED))
    assert t.data() == [twist(3)]  # only the newest was still waiting


def test_a_message_dropped_by_overflow_is_not_counted_again_when_its_ask_times_out(bus: LocalBus) -> None:
    node, t = guard(bus, max_pending=1)
    t.send("/planner/cmd_vel", twist(0))
    t.send("/planner/cmd_vel", twist(1))  # drops 0
    t.asks[0].answer(None)  # the Manager is down: 0's ask times out later
    t.asks[1].answer(None)
    assert node.counters["blocked"] == 2
    assert node.counters["overflow"] == 1
    # each blocked message is blocked for one reason: 0 for overflow, 1 for want of an answer
    assert node.counters["unanswered"] == 1


# ----------------------------------------------------------------------------- threads


def test_answers_from_many_threads_forward_each_permitted_message_exactly_once(bus: LocalBus) -> None:
    node, t = guard(bus, max_pending=1000)
    n = 300
    for i in range(n):
        t.send("/planner/cmd_vel", {"i": i})
    permit = [i % 3 != 0 for i in range(n)]
    barrier = threading.Barrier(4)

    def answer(part: list[int]) -> None:
        barrier.wait()
        for i in part:
            t.asks[i].answer(dict(PERMITTED) if permit[i] else None)

    parts = [list(range(k, n, 4)) for k in range(4)]
    threads = [threading.Thread(target=answer, args=(p,)) for p in parts]
    for th in threads:
        th.start()
    for th in threads:
        th.join(10)
    got = sorted(d["i"] for d in t.data())
    assert got == [i for i in range(n) if permit[i]]
    assert node.counters["forwarded"] == sum(permit)
    assert node.counters["blocked"] == node.counters["unanswered"] == n - sum(permit)


@pytest.mark.timeout(30)
def test_two_answers_on_two_threads_still_leave_in_arrival_order(bus: LocalBus) -> None:
    _, t = guard(bus)
    t.send("/planner/cmd_vel", {"i": 0})
    t.send("/planner/cmd_vel", {"i": 1})
    first_in = threading.Event()
    gate = threading.Event()
    record = t.publish_raw

    def slow_publish(topic: str, type_name: str, data: Any, qos: Any) -> None:
        if data == {"i": 0}:  # the first thread is preempted on its way to the wire
            first_in.set()
            gate.wait(5)
        record(topic, type_name, data, qos)

    t.publish_raw = slow_publish  # type: ignore[method-assign]
    a = threading.Thread(target=t.asks[0].answer, args=(dict(PERMITTED),))
    a.start()
    assert first_in.wait(5)
    b = threading.Thread(target=t.asks[1].answer, args=(dict(PERMITTED),))
    b.start()
    b.join(0.5)  # with the fix, b waits for a; without it, b sends at once
    gate.set()
    a.join(5)
    b.join(5)
    assert t.data() == [{"i": 0}, {"i": 1}]


# ----------------------------------------------------------------------------- with a Manager


class WithManager(FakeRos):
    """The guard's transport and the Manager node's on one bus: ``ask`` calls the served handler."""

    def __init__(self, bus: LocalBus) -> None:
        super().__init__(bus)
        self.services: dict[str, Callable[[dict[str, Any]], dict[str, Any]]] = {}

    def serve(
        self, name: str, kind: str, handler: Callable[[dict[str, Any]], dict[str, Any]], rejected: Any = None
    ) -> None:
        self.services[name.replace("~", "/cosleec_manager")] = handler

    def ask(
        self,
        name: str,
        kind: str,
        fields: dict[str, Any],
        answer: Callable[[dict[str, Any] | None], None],
        timeout: float,
    ) -> None:
        handler = self.services.get(name)
        answer(handler(dict(fields)) if handler else None)


def test_with_the_manager_node_the_guard_forwards_until_a_prohibition_and_only_the_manager_reports(
    bus: LocalBus,
) -> None:
    t = WithManager(bus)
    manager = ManagerNode(t, VACUUM, sim_time=True)
    g = GuardNode(t, [CMD], manager="/cosleec_manager")
    refusals = collect(bus, "/cosleec/refusals")
    t.send("/planner/cmd_vel", twist(0))
    t.local.publish("/cosleec/events", json.dumps({"event": "UserApproaches"}))
    assert bus.wait_idle()
    t.send("/planner/cmd_vel", twist(1))
    t.local.publish("/cosleec/clock", json.dumps({"t": 31.0}))
    assert bus.wait_idle()
    t.send("/planner/cmd_vel", twist(2))
    assert bus.wait_idle()
    assert t.data() == [twist(0), twist(2)]
    assert g.counters["forwarded"] == 2 and g.counters["blocked"] == 1
    assert len(refusals) == 1  # the Manager's, naming R3 and the guarded topic; none of the guard's
    assert refusals[0]["by"] == ["R3"] and refusals[0]["source"] == "/planner/cmd_vel"
    assert "guard" not in refusals[0]
    manager.close()


def test_with_no_manager_serving_every_message_is_blocked_and_reported_by_the_guard(bus: LocalBus) -> None:
    t = WithManager(bus)  # nobody serves /cosleec_manager/request
    g = GuardNode(t, [CMD], manager="/cosleec_manager")
    refusals = collect(bus, "/cosleec/refusals")
    t.send("/planner/cmd_vel", twist(0))
    assert bus.wait_idle()
    assert t.data() == [] and g.counters["unanswered"] == 1
    assert len(refusals) == 1 and refusals[0]["guard"] is True


def test_a_message_blocked_by_an_inactive_manager_is_reported_on_refusals(bus: LocalBus) -> None:
    t = WithManager(bus)
    manager = ManagerNode(t, VACUUM, sim_time=True, active=False)
    g = GuardNode(t, [CMD], manager="/cosleec_manager")
    refusals = collect(bus, "/cosleec/refusals")
    t.send("/planner/cmd_vel", twist(0))
    assert bus.wait_idle()
    manager.close()
    assert t.data() == [] and g.counters["blocked"] == 1
    assert len(refusals) == 1  # by the Manager or by the guard, but by someone
    assert "inactive" in refusals[0]["reason"]


def test_a_failing_ask_blocks_that_message_and_does_not_hold_up_the_next(bus: LocalBus) -> None:
    node, t = guard(bus)
    calls = {"n": 0}
    keep = t.ask

    def flaky(*args: Any) -> None:
        calls["n"] += 1
        if calls["n"] == 1:
            raise RuntimeError("the service type cannot be loaded")
        keep(*args)

    t.ask = flaky  # type: ignore[method-assign,assignment]
    with contextlib.suppress(RuntimeError):
        t.send("/planner/cmd_vel", twist(0))
    t.send("/planner/cmd_vel", twist(1))
    t.asks[-1].answer(dict(PERMITTED))
    assert t.data() == [twist(1)]
    assert node.counters["blocked"] == 1


# ----------------------------------------------------------------------------- route


GOOD = {"to": "/cmd_vel", "type": "geometry_msgs/msg/Twist", "event": "MoveNearUser"}


def test_route_builds_a_frozen_route_reliable_by_default() -> None:
    r = route("/planner/cmd_vel", dict(GOOD))
    assert r == Route("/planner/cmd_vel", "/cmd_vel", "geometry_msgs/msg/Twist", "MoveNearUser", Qos.RELIABLE)
    with pytest.raises(FrozenInstanceError):
        r.target = "/elsewhere"  # type: ignore[misc]


@pytest.mark.parametrize(
    ("qos", "expected"),
    [
        ("sensor_data", Qos.SENSOR_DATA),
        ("reliable", Qos.RELIABLE),
        ("latched", Qos.LATCHED),
        ({"depth": 5}, Qos("reliable", "volatile", 5)),  # left-out keys from RELIABLE, not sensor data
        ({"reliability": "best_effort"}, Qos("best_effort", "volatile", 10)),
    ],
)
def test_route_qos(qos: Any, expected: Qos) -> None:
    assert route("/a", {**GOOD, "qos": qos}).qos == expected


def test_route_events_checked_only_when_given() -> None:
    assert route("/a", {**GOOD, "event": "Anything"}).event == "Anything"
    assert route("/a", dict(GOOD), events=VACUUM.events).event == "MoveNearUser"
    with pytest.raises(GuardError, match="the rules declare no event 'MoveNearUser'"):
        route("/a", dict(GOOD), events=frozenset())  # an empty set is a set of events, not "unchecked"


def error(source: str, spec: Any, events: frozenset[str] | None = None, where: str = "g.yaml") -> GuardError:
    with pytest.raises(GuardError) as info:
        route(source, spec, where, events)
    return info.value


@pytest.mark.parametrize("spec", ["/cmd_vel", ["/cmd_vel"], None, 3])
def test_route_spec_must_be_a_table(spec: Any) -> None:
    assert str(error("/a", spec)) == "g.yaml: guards./a: expected {to, type, event}"


def test_route_unknown_key_with_did_you_mean() -> None:
    e = error("/a", {"to": "/b", "type": "T", "evnt": "E"})
    assert e.message == "g.yaml: guards./a: unknown key 'evnt'"
    assert e.hint == "did you mean 'event'?"
    assert "hint: did you mean 'event'?" in e.render()


def test_route_unknown_key_without_a_close_match_lists_the_keys() -> None:
    e = error("/a", {**GOOD, "colour": "red"})
    assert e.message == "g.yaml: guards./a: unknown key 'colour'"
    assert e.hint == "keys: to, type, event, qos"


def test_route_names_the_first_unknown_key_in_sorted_order() -> None:
    e = error("/a", {**GOOD, "zzz": 1, "qoss": 1})
    assert e.message == "g.yaml: guards./a: unknown key 'qoss'" and e.hint == "did you mean 'qos'?"


@pytest.mark.parametrize("key", ["to", "type", "event"])
@pytest.mark.parametrize("value", [None, "", 5, ["/b"]])
def test_route_required_keys_must_be_non_empty_strings(key: str, value: Any) -> None:
    spec = {**GOOD, key: value} if value is not None else {k: v for k, v in GOOD.items() if k != key}
    assert str(error("/a", spec)) == f"g.yaml: guards./a: `{key}` is required and must be a string"


def test_route_required_keys_checked_in_order_to_type_event() -> None:
    assert "`to` is required" in str(error("/a", {}))
    assert "`type` is required" in str(error("/a", {"to": "/b"}))
    assert "`event` is required" in str(error("/a", {"to": "/b", "type": "T"}))


def test_route_source_must_be_a_topic() -> None:
    with pytest.raises(GuardError):
        route("", dict(GOOD), "--from/--to/--type/--event")


def test_route_to_must_differ_from_the_source() -> None:
    e = error("/cmd_vel", dict(GOOD))
    assert e.message == (
        "g.yaml: guards./cmd_vel: `to` must differ from the guarded topic, or the guard would feed itself"
    )


def test_route_undeclared_event_with_did_you_mean() -> None:
    e = error("/a", {**GOOD, "event": "MoveNearUsr"}, VACUUM.events)
    assert e.message == "g.yaml: guards./a: the rules declare no event 'MoveNearUsr'"
    assert e.hint == "did you mean 'MoveNearUser'?"


def test_route_undeclared_event_without_a_close_match() -> None:
    e = error("/a", {**GOOD, "event": "Xyzzy"}, VACUUM.events)
    assert e.message == "g.yaml: guards./a: the rules declare no event 'Xyzzy'"
    assert e.hint == "declare it in the rules' def block"


@pytest.mark.parametrize(
    ("qos", "says"),
    [
        ("fast", "no QoS profile 'fast'"),
        (5, "qos must be a profile name"),
        ({"depth": 0}, "depth must be a whole number from 1 to 100000"),
        ({"reliability": "sometimes"}, "reliability 'sometimes' is not one of reliable, best_effort"),
        ({"history": 3}, "unknown qos key(s) ['history']"),
    ],
)
def test_route_bad_qos(qos: Any, says: str) -> None:
    e = error("/a", {**GOOD, "qos": qos})
    assert str(e).startswith("g.yaml: guards./a: ") and says in str(e)


def test_route_default_where() -> None:
    assert str(error("/a", "x", where="<guard>")).startswith("<guard>: guards./a:")
    with pytest.raises(GuardError, match=r"^<guard>: guards\./a: expected"):
        route("/a", "x")


def test_guard_error_is_a_user_error() -> None:
    e = error("/a", "x")
    assert isinstance(e, UserError) and isinstance(e, ValueError)
    assert issubclass(GuardError, UserError)


# ----------------------------------------------------------------------------- load_routes


def write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "mapping.yaml"
    p.write_text(text, encoding="utf-8")
    return p


def test_load_routes_reads_the_example_mapping_against_its_rules() -> None:
    routes = load_routes(EXAMPLE / "mapping.yaml", VACUUM.events)
    assert routes == [
        Route("/planner/cmd_vel", "/cmd_vel", "geometry_msgs/msg/Twist", "MoveNearUser", Qos.RELIABLE)
    ]


def test_load_routes_keeps_the_files_order(tmp_path: Path) -> None:
    p = write(
        tmp_path,
        "guards:\n"
        "  /z: {to: /z2, type: T, event: A}\n"
        "  /a: {to: /a2, type: T, event: B, qos: sensor_data}\n"
        "  /m: {to: /m2, type: T, event: C}\n",
    )
    routes = load_routes(p)
    assert [r.source for r in routes] == ["/z", "/a", "/m"]
    assert routes[1].qos == Qos.SENSOR_DATA and routes[0].qos == Qos.RELIABLE
    assert load_routes(str(p)) == routes  # a str path too


@pytest.mark.parametrize(
    "text",
    [
        "",
        "measures: {}\n",
        "guards:\n",
        "guards: {}\n",
        "guards: []\n",
        "guards: /cmd_vel\n",
        "- guards\n",
        "42\n",
    ],
)
def test_load_routes_without_a_guards_section(tmp_path: Path, text: str) -> None:
    p = write(tmp_path, text)
    with pytest.raises(GuardError) as info:
        load_routes(p)
    e = info.value
    assert e.message == "no `guards` section: nothing to guard"
    assert e.where == str(p)
    assert e.hint.startswith("add `guards: {/planner/cmd_vel: {to: /cmd_vel,")
    assert e.render().startswith(f"{p}: no `guards` section")


def test_load_routes_missing_file(tmp_path: Path) -> None:
    p = tmp_path / "nope.yaml"
    with pytest.raises(GuardError) as info:
        load_routes(p)
    assert info.value.message == "cannot read the mapping: No such file or directory"
    assert info.value.where == str(p)


def test_load_routes_a_directory(tmp_path: Path) -> None:
    with pytest.raises(GuardError) as info:
        load_routes(tmp_path)
    assert info.value.message == "cannot read the mapping: Is a directory"
    assert info.value.where == str(tmp_path)


def test_load_routes_not_utf8(tmp_path: Path) -> None:
    p = tmp_path / "latin1.yaml"
    p.write_bytes(b"guards:\n  /caf\xe9: {to: /b, type: T, event: E}\n")
    with pytest.raises(GuardError) as info:
        load_routes(p)
    assert str(info.value).startswith("cannot read the mapping: 'utf-8' codec can't decode")
    assert info.value.where == str(p)


@pytest.mark.parametrize("text", ["guards: {/a: [\n", "guards:\n  /a: {to: /b\n", "a: b: c\n", "\t- x"])
def test_load_routes_invalid_yaml(tmp_path: Path, text: str) -> None:
    p = write(tmp_path, text)
    with pytest.raises(GuardError) as info:
        load_routes(p)
    assert re.match(re.escape(str(p)) + r":\d+:\d+: not valid YAML: ", str(info.value))  # file:line:col
    assert isinstance(info.value, UserError)


def test_load_routes_a_route_given_twice_is_an_error_not_the_last_one(tmp_path: Path) -> None:
    p = write(tmp_path, "guards:\n  /a: {to: /b, type: T, event: E}\n  /a: {to: /c, type: T, event: E}\n")
    with pytest.raises(GuardError, match=r":3:3: '/a' is given twice"):
        load_routes(p)


@pytest.mark.parametrize("bad", ["/a b", "/a/", "", "/1a", "a//b", "hf/cmd", "~cmd", "~/cmd", "/{node}/x"])
def test_a_route_names_absolute_ros_topics(bad: str) -> None:
    # relative names are refused: `--from /hf/cmd --to hf/cmd` is one topic, and the guard fed itself
    with pytest.raises(GuardError, match="is not an absolute ROS topic name"):
        route(bad, {"to": "/b", "type": "T", "event": "E"})
    with pytest.raises(GuardError, match="is not an absolute ROS topic name"):
        route("/a", {"to": bad or "/x y", "type": "T", "event": "E"})


@pytest.mark.parametrize("good", ["/_private/cmd", "/a/_b", "/a1/b2_c", "/cmd_vel"])
def test_valid_absolute_names_are_taken(good: str) -> None:
    assert route(good, {"to": "/out", "type": "T", "event": "E"}).source == good


def test_load_routes_names_the_file_and_route_of_a_bad_route(tmp_path: Path) -> None:
    p = write(tmp_path, "guards:\n  /planner/cmd_vel: {to: /cmd_vel, type: T, event: MoveNearUsr}\n")
    with pytest.raises(GuardError) as info:
        load_routes(p, VACUUM.events)
    assert info.value.message == f"{p}: guards./planner/cmd_vel: the rules declare no event 'MoveNearUsr'"
    assert info.value.hint == "did you mean 'MoveNearUser'?"
    assert load_routes(p)[0].event == "MoveNearUsr"  # without the rules, not checked


def test_load_routes_a_key_that_is_no_topic_name_is_refused(tmp_path: Path) -> None:
    p = write(tmp_path, "guards:\n  1: {to: /b, type: T, event: E}\n")
    with pytest.raises(GuardError, match=r"guards\.1: guarded topic '1' is not an absolute ROS topic name"):
        load_routes(p)


# ----------------------------------------------------------------------------- health (issue 28, finding 12)


def diagnosed(t: FakeRos) -> list[tuple[int, str]]:
    """Each status the guard published, as /diagnostics would show it: (level, message)."""
    from cosleec.ros.diagnostics import Diagnostics

    out: list[tuple[int, str]] = []
    d = Diagnostics(
        "guard", lambda s: out.append((s["level"], s["message"])), clock=itertools.count().__next__
    )
    for topic, m in t.published:
        if topic == "/cosleec/status":
            d.report(m)
    return out


def test_a_guard_whose_manager_does_not_answer_reports_an_error_until_it_answers(bus: LocalBus) -> None:
    # before: level 0, "ok", while every message was blocked and `unanswered` rose
    node, t = guard(bus, [CMD], answer_at_once=None, timeout=0.5)
    node.status()
    assert "manager_answering" not in t.published[-1][1]  # not asked yet: nothing known
    for i in range(3):
        t.send("/planner/cmd_vel", twist(i))
    node.status()  # the heartbeat
    last = [m for topic, m in t.published if topic == "/cosleec/status"][-1]
    assert last["manager_answering"] is False and last["counters"]["unanswered"] == 3
    problem = (
        "the Manager (/cosleec_manager/request) did not answer within 0.5 s: "
        "every guarded message is blocked until it answers"
    )
    assert last["manager_problem"] == problem
    assert diagnosed(t)[-1] == (2, problem)  # ERROR, and why
    t.answer_at_once = PERMITTED  # the Manager is back
    t.send("/planner/cmd_vel", twist(9))
    bus.wait_idle()
    last = [m for topic, m in t.published if topic == "/cosleec/status"][-1]
    assert last["manager_answering"] is True and "manager_problem" not in last
    assert diagnosed(t)[-1] == (0, "ok")


def test_a_refusal_is_an_answer_the_manager_is_there(bus: LocalBus) -> None:
    node, t = guard(bus, [CMD], answer_at_once=REFUSED)
    t.send("/planner/cmd_vel", twist(1))
    bus.wait_idle()
    node.status()
    bus.wait_idle()
    last = [m for topic, m in t.published if topic == "/cosleec/status"][-1]
    assert last["manager_answering"] is True and node.counters["blocked"] == 1
    assert diagnosed(t)[-1][0] == 0


def test_the_guard_says_at_once_when_the_manager_stops_answering(bus: LocalBus) -> None:
    _, t = guard(bus, [CMD], answer_at_once=PERMITTED)
    t.send("/planner/cmd_vel", twist(1))
    t.answer_at_once = None
    before = len([1 for topic, _ in t.published if topic == "/cosleec/status"])
    t.send("/planner/cmd_vel", twist(2))  # no heartbeat in between: the change itself publishes
    statuses = [m for topic, m in t.published if topic == "/cosleec/status"]
    assert len(statuses) > before and statuses[-1]["manager_answering"] is False
