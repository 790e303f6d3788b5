"""SLEEC-TK's priority assertions (``examples/TIAGo/src-gen/TIAGo-priority-assertions.csp``,
branch ``priority``) as tests, under the semantics each names, for the reference semantics
and for the runtime alike.

TK counts time in ``tock``s of one minute; ``has trace`` means the trace conforms (nothing
violated, the rules can still be met), ``not ... has trace`` that it violates a rule. TK's
assertions about its ``PriCB_Broken`` process are about its CSP encoding, not the rules.
"""

from __future__ import annotations

from typing import Any

import pytest

from cosleec.lang import Reading, parse
from cosleec.runtime import Manager, VirtualClock
from cosleec.semantics import Step, judge

TIAGO = """def_start
    event UserFallen
    event CallSupport
    event SmokeDetected
    measure assentToSupportCalls: boolean
    measure alarmOn: boolean
def_end
rule_start
Rule3 when UserFallen and not assentToSupportCalls then not CallSupport within 10 minutes
Rule21 when SmokeDetected and alarmOn then CallSupport within 5 minutes
rule_end
"""
MINUTE = 60


def tk(*trace: str) -> list[Step]:
    """A TK trace as timed steps: each ``tock`` is one minute; a measure reading is set just
    before the event it follows in TK (which reads it right after the trigger)."""
    steps: list[Step] = []
    t = 0
    pending: list[str] = []
    for e in trace:
        if e == "tock":
            t += MINUTE
            steps.append(Step(t))
        elif "." in e:
            name, value = e.split(".")
            # TK reads a measure right after its trigger: set it before that event, same instant
            trigger = pending.pop()
            steps.pop()
            steps.append(Step(t, values={name: value == "true"}))
            steps.append(Step(t, event=trigger))
        else:
            pending.append(e)
            steps.append(Step(t, event=e))
    return steps


def runtime(steps: list[Step], semantics: str) -> dict[str, Any]:
    """The Manager fed the trace on a VirtualClock: verdicts by rule, and whether it conforms."""
    clock = VirtualClock(0.0)
    m = Manager.from_text(
        TIAGO, clock=clock, dispatch=False, priorities=["Rule21 > Rule3"], priority_semantics=semantics
    )
    status: dict[int, dict[str, Any]] = {}
    m.subscribe(lambda ev: status.__setitem__(ev.data["id"], ev.data) if ev.kind == "obligation" else None)
    m.start()
    for s in steps:
        clock.set(float(s.t))
        if s.values:
            m.update(dict(s.values))
        if s.event:
            m.event(s.event)
        if not s.values and not s.event:
            m.tick()
    m.close()
    bad = [d["rule"] for d in status.values() if d["status"] in ("violated", "blocked")]
    return {"conforms": not bad, "violated": sorted(bad)}


def verdict(steps: list[Step], semantics: str) -> dict[str, Any]:
    """The reference semantics on the trace, with ``Rule21 > Rule3``; checked equal to the runtime."""
    j = judge(
        parse(TIAGO),
        steps,
        Reading(priorities=frozenset({("Rule21", "Rule3")}), priority_semantics=semantics),
    )
    ref = {"conforms": j.conforms, "violated": sorted(v.rule for v in j.breaches)}
    assert runtime(steps, semantics) == ref
    return ref


FALL = ("UserFallen", "assentToSupportCalls.false")
SMOKE = ("SmokeDetected", "alarmOn.true")


def test_trace_4_is_a_trace_of_cancellation_based_priority() -> None:
    # assert PriCB(R21,R3) :[has trace [T]]:<UserFallen, assent.false, tock, tock, SmokeDetected, alarmOn.true, CallSupport>
    assert verdict(tk(*FALL, "tock", "tock", *SMOKE, "CallSupport"), "cancel")["conforms"]


def test_trace_4_is_not_a_trace_of_conflict_aware_priority() -> None:
    # assert not PriCA(R21,R3) :[has trace [T]]:<... same ...>: Rule3 is kept until Rule21's deadline
    assert verdict(tk(*FALL, "tock", "tock", *SMOKE, "CallSupport"), "conflict-aware") == {
        "conforms": False,
        "violated": ["Rule3"],
    }


@pytest.mark.parametrize("semantics", ["cancel", "conflict-aware"])
def test_trace_5_call_support_at_rule21s_deadline_is_a_trace_of_both(semantics: str) -> None:
    # assert PriCB(R21,R3) / PriCA(R21,R3) :[has trace [T]]:<..., SmokeDetected, alarmOn.true, tock x5, CallSupport>
    trace = tk(*FALL, "tock", "tock", *SMOKE, *["tock"] * 5, "CallSupport")
    assert verdict(trace, semantics)["conforms"]


def test_up_to_five_tocks_after_rule21_fires_under_cancellation() -> None:
    # assert PriCB(R21,R3) :[has trace [T]]:<UserFallen,assent.false,SmokeDetected,alarmOn.true,tock x5>
    assert verdict(tk(*FALL, *SMOKE, *["tock"] * 5), "cancel")["conforms"]


def test_no_sixth_tock_after_rule21_fires_under_cancellation() -> None:
    # assert not PriCB(R21,R3) :[has trace [T]]:<UserFallen,assent.false,SmokeDetected,alarmOn.true,tock x6>
    assert verdict(tk(*FALL, *SMOKE, *["tock"] * 6), "cancel") == {"conforms": False, "violated": ["Rule21"]}


def test_call_support_at_once_then_more_than_five_tocks_under_cancellation() -> None:
    # assert PriCB(R21,R3) :[has trace [T]]:<UserFallen,assent.false,tock x7,SmokeDetected,alarmOn.true,CallSupport,tock x6>
    trace = tk(*FALL, *["tock"] * 7, *SMOKE, "CallSupport", *["tock"] * 6)
    assert verdict(trace, "cancel")["conforms"]


def test_a_second_fall_while_rule3_monitors_is_an_activation_of_its_own() -> None:
    # TK: assert not PriCB(R21,R3) :[has trace [T]]:<SmokeDetected,alarmOn.true,CallSupport,UserFallen,assent.false,UserFallen>
    # holds only because a TK rule refuses its own trigger while it monitors (sleec-language.md
    # §11.5): a monitor cannot refuse what the world does, so cosleec starts a second activation
    # (§6.3) and the trace conforms -- a documented divergence, not a priority question.
    trace = tk(*SMOKE, "CallSupport", *FALL, "UserFallen")
    assert verdict(trace, "cancel")["conforms"]


def test_without_a_priority_the_rules_conflict_and_the_prohibition_wins() -> None:
    # FDR finds a deadlock without priorities; cosleec refuses Rule21's obligation (prohibition wins)
    j = judge(parse(TIAGO), tk(*FALL, "tock", "tock", *SMOKE))
    assert [(v.rule, v.status, v.at) for v in j.verdicts] == [
        ("Rule3", "pending", None),
        ("Rule21", "blocked", 120),
    ]
    assert [(c.rules, c.resolution) for c in j.conflicts] == [(("Rule21", "Rule3"), "prohibition-wins")]
