"""The typed wire's codec against the real generated ``cosleec_interfaces`` classes of this
backend (rosidl on ROS 2, genpy on ROS 1): every record a node publishes survives the trip,
and inputs written by a robot's own code (typed fields only, no record) are read."""

from __future__ import annotations

import math
from typing import Any

import pytest

from cosleec.nodes import MessageError
from cosleec.runtime import Manager, VirtualClock

RULES = """def_start
event Ask event Do event Stop event Done
measure hot : boolean
measure level : numeric
measure mood : scale(low, high)
def_end
rule_start
R1 when Ask then Do within 5 seconds unless hot then Stop within 2 seconds
R2 when Ask then not Stop within 3 seconds
R3 when Ask then Done within 1 seconds
rule_end
"""


@pytest.fixture
def codec(backend: str) -> Any:
    from cosleec.ros.interfaces import Codec, interfaces

    msg, _ = interfaces()
    if backend == "ros2":
        from builtin_interfaces.msg import Time

        def stamp(t: float) -> Any:
            sec, ns = divmod(round(t * 1e9), 10**9)
            return Time(sec=sec, nanosec=ns)

        def seconds(s: Any) -> float:
            return float(s.sec + s.nanosec * 1e-9)
    else:
        import rospy

        def stamp(t: float) -> Any:
            sec, ns = divmod(round(t * 1e9), 10**9)
            return rospy.Time(sec, ns)

        def seconds(s: Any) -> float:
            return float(s.secs + s.nsecs * 1e-9)

    return Codec(msg, stamp, seconds, lambda: 1234.5)


def records() -> dict[str, list[dict[str, Any]]]:
    """Real records of a small run, by the topic a Manager node publishes them on."""
    m = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False)
    out: dict[str, list[dict[str, Any]]] = {}

    def keep(ev: Any) -> None:
        topic = {
            "decision": "decisions",
            "layers": "layers",
            "conflict": "conflicts",
            "refused": "refusals",
        }.get(ev.kind)
        if ev.kind == "obligation" and ev.data["status"] == "violated":
            topic = "violations"
        if topic:
            out.setdefault(topic, []).append(ev.data)

    m.subscribe(keep)
    m.start(check=False)
    m.update(hot=True, level=2.5, mood="high")
    m.event("Ask")
    m.request("Stop")
    m.clock.advance(10)
    m.tick()
    return out


def test_every_output_record_survives_the_typed_wire(codec: Any) -> None:
    got = records()
    assert set(got) >= {"decisions", "layers", "refusals", "violations"}
    for topic, recs in got.items():
        for r in recs:
            numbered = {**r, "_from": "abc", "_n": 7}
            m = codec.encode(topic, numbered)
            assert m.sender == "abc" and m.seq == 7
            assert m.header.stamp is not None
            assert codec.decode(topic, m) == _jsonish(numbered)


def test_decision_fields_are_typed(codec: Any) -> None:
    d = records()["decisions"][0]
    m = codec.encode("decisions", {**d, "session": "s1"})
    assert (m.rule, m.clause, m.layer, m.trigger, m.session) == ("R1", 1, "R1.1", "Ask", "s1")
    assert m.explanation == "R1: Stop within 2 s [clause 1 (unless hot)], because hot was true"
    values = {v.name: v for v in m.values}
    assert values["hot"].kind == values["hot"].BOOLEAN and values["hot"].boolean is True
    assert [o.event for o in m.obligations] == ["Stop"]
    undetermined = codec.encode("decisions", {**d, "clause": None})
    assert undetermined.clause == -1  # -1, not 0: an undetermined decision is not the default


def test_inputs_are_read_from_typed_fields_alone(codec: Any) -> None:
    msg = codec.msg
    update = msg.ContextUpdate()
    update.values = [codec.value("hot", False), codec.value("level", 3), codec.value("mood", "low")]
    decoded = codec.decode("context", update)
    assert decoded == {"values": {"hot": False, "level": 3, "mood": "low"}}
    assert type(decoded["values"]["level"]) is int  # a whole number reads as JSON carries it
    update.values = [codec.value("level", 2.5), codec.value("big", 2.0**60)]
    assert codec.decode("context", update)["values"] == {"level": 2.5, "big": 2.0**60}
    ev = msg.Event()
    ev.event = "Ask"
    assert codec.decode("events", ev) == {"event": "Ask"}  # unnumbered: no _from/_n
    q = msg.PermissionQuery()
    q.id, q.event = "7", "Stop"
    assert codec.decode("request", q) == {"id": "7", "event": "Stop", "source": ""}


@pytest.mark.parametrize("kind", [0, 4, 9, 255])  # 0: UNKNOWN, which no update can set
def test_a_measure_value_of_an_unknown_kind_is_rejected(codec: Any, kind: int) -> None:
    update = codec.msg.ContextUpdate()
    v = codec.msg.MeasureValue()
    v.name, v.kind = "hot", kind
    update.values = [v]
    with pytest.raises(MessageError, match="kind"):
        codec.decode("context", update)


def test_a_measure_given_twice_is_rejected(codec: Any) -> None:
    update = codec.msg.ContextUpdate()
    update.values = [codec.value("hot", True), codec.value("hot", False)]
    with pytest.raises(MessageError, match="twice"):
        codec.decode("context", update)


def test_an_output_without_its_record_cannot_be_read(codec: Any) -> None:
    with pytest.raises(MessageError, match="record"):
        codec.decode("decisions", codec.msg.Decision())


def test_stamps_round_to_the_nanosecond_without_losing_a_second(codec: Any) -> None:
    s = codec.stamp(1.9999999999)
    assert math.isclose(codec.seconds(s), 2.0)
    assert codec.seconds(codec.stamp(12.25)) == 12.25


def _jsonish(r: dict[str, Any]) -> dict[str, Any]:
    import json

    from cosleec.nodes import dumps

    return dict(json.loads(dumps(r)))


def test_a_decisions_obligations_have_their_window_on_the_managers_clock(codec: Any) -> None:
    d = {**records()["decisions"][0], "time": 100.0}  # decided at 100 s: Stop within 2 s
    (o,) = codec.encode("decisions", d).obligations
    assert (o.event, o.prohibition, o.window_start, o.deadline) == ("Stop", False, 100.0, 102.0)
    untimed = {**d, "obligations": [{**d["obligations"][0], "within_s": None}]}
    assert codec.encode("decisions", untimed).obligations[0].deadline == math.inf
