"""The Manager node hands on to task nodes only what the Manager would dispatch itself: a
decision refused by a conflict never reaches them, one held while forbidden reaches them
when allowed."""

from __future__ import annotations

import json

from cosleec.nodes import LocalBus, ManagerNode
from cosleec.runtime import RuleSet
from tests.unit.nodes.support import collect

CURTAINS = """def_start
  event CurtainOpenRequest
  event OpenCurtains
  measure night: boolean
def_end
rule_start
R1 when CurtainOpenRequest then OpenCurtains within 1 minutes
R2 when CurtainOpenRequest and night then not OpenCurtains within {window}
rule_end
"""


def run(bus: LocalBus, window: str, night: bool, later: float | None = None) -> list[dict[str, object]]:
    t = bus.transport()
    node = ManagerNode(t, RuleSet.from_text(CURTAINS.format(window=window)), sim_time=True)
    handed = collect(bus, "/cosleec/obligations")
    t.publish("/cosleec/context", json.dumps({"values": {"night": night}}))
    t.publish("/cosleec/events", json.dumps({"event": "CurtainOpenRequest"}))
    assert bus.wait_idle()
    if later is not None:
        t.publish("/cosleec/clock", json.dumps({"t": later}))
        assert bus.wait_idle()
    node.close()
    return handed


def test_a_refused_decision_never_reaches_the_task_nodes(bus: LocalBus) -> None:
    handed = run(bus, "10 minutes", night=True, later=120.0)
    assert [d["rule"] for d in handed] == ["R2"]  # the prohibition's decision only


def test_a_held_decision_reaches_them_once_allowed(bus: LocalBus) -> None:
    handed = run(bus, "30 seconds", night=True)
    assert [d["rule"] for d in handed] == ["R2"]
    bus2 = LocalBus()
    try:
        handed = run(bus2, "30 seconds", night=True, later=31.0)
        assert [d["rule"] for d in handed] == ["R2", "R1"]
    finally:
        bus2.close()


def test_by_day_the_decision_is_handed_on_at_once(bus: LocalBus) -> None:
    assert [d["rule"] for d in run(bus, "10 minutes", night=False)] == ["R1"]


SPLIT = """def_start
  event X event Y event A event B
def_end
rule_start
R1 when X then A within 60 seconds and B within 5 seconds
R2 when Y then not A within 30 seconds
rule_end
"""


def test_the_allowed_part_of_a_decision_is_handed_on_at_once_and_the_held_part_once_allowed(
    bus: LocalBus,
) -> None:
    t = bus.transport()
    node = ManagerNode(t, RuleSet.from_text(SPLIT), sim_time=True)
    handed = collect(bus, "/cosleec/obligations")
    for event in ("Y", "X"):
        t.publish("/cosleec/events", json.dumps({"event": event}))
    assert bus.wait_idle()
    r1 = [d for d in handed if d["rule"] == "R1"]
    assert [[o["event"] for o in d["obligations"]] for d in r1] == [["B"]]  # B at once, A held
    t.publish("/cosleec/clock", json.dumps({"t": 31.0}))
    assert bus.wait_idle()
    node.close()
    r1 = [d for d in handed if d["rule"] == "R1"]
    assert [[o["event"] for o in d["obligations"]] for d in r1] == [["B"], ["A"]]
    assert len({d["id"] for d in r1}) == 1  # two parts of one decision
