"""An event with the measure values observed with it (one sensor message that gives both):
the values are applied as one update just before the event, with no step between, so the
rules decide on them; if they are rejected, the event does not happen either."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from cosleec.runtime import ContextError, Manager, VirtualClock

RULES = """def_start event Approach event Keep event Refuse measure near : boolean measure n : numeric def_end
rule_start R1 when Approach then Keep within 5 seconds unless near then Refuse rule_end
"""


def manager() -> Manager:
    m = Manager.from_text(RULES, clock=VirtualClock(), dispatch=False)
    m.start(check=False)
    return m


def test_the_rules_decide_on_the_values_that_came_with_the_event() -> None:
    m = manager()
    m.update(near=False)
    (d,) = m.event("Approach", values={"near": True})
    assert (d.rule, d.clause) == ("R1", 1)  # not the default the value before would have chosen
    assert m.values()["near"] is True


def test_rejected_values_mean_the_event_did_not_happen() -> None:
    m = manager()
    m.update(near=False)
    with pytest.raises(ContextError):
        m.event("Approach", values={"near": "yes"})
    assert m.stats["events"] == 0 and m.stats["decisions"] == 0
    assert m.values()["near"] is False


def test_no_other_update_comes_between_the_values_and_their_event() -> None:
    m = manager()
    m.update(near=False)
    others: list[threading.Thread] = []

    def meddle(ev: Any) -> None:  # as soon as near=True is recorded, another thread says False
        if ev.kind == "context" and ev.data["values"].get("near") is True and not others:
            t = threading.Thread(target=m.update, kwargs={"near": False})
            others.append(t)
            t.start()
            t.join(0.3)  # it gets its turn now unless the event holds the Manager until it happened

    m.subscribe(meddle)
    (d,) = m.event("Approach", values={"near": True})
    others[0].join()
    assert d.clause == 1 and d.values["near"] is True
    assert m.values()["near"] is False  # the other update came, after the event


def test_an_unknown_event_takes_none_of_its_values() -> None:
    m = manager()
    m.update(near=False)
    with pytest.raises(ContextError, match="unknown event"):
        m.event("Nope", values={"near": True})
    assert m.values()["near"] is False  # all or nothing
