"""The express lane (cosleec.runtime.express) decides exactly what the general path decides.

Each Manager is run twice on the same rules and trace -- once as built, once with
``COSLEEC_EXPRESS=0`` (the general path alone) -- and everything a user can see must be
equal: every record with its number and time, the decisions ``event`` returns, the calls
of the capabilities, the obligations outstanding and the counters. On generated rule sets
(the differential test's, with rules that some action also triggers, so that an event may
trigger and fulfil at once), where the general path alone must also meet the reference
semantics, as the differential test holds the default path to it; and on hand-made cases,
one per condition that sends a trigger to the general path, each checked to be taken by
the lane where it is quiet and refused where it is not.
"""

from __future__ import annotations

import json
import os
import re
import threading
import time
from typing import Any, NamedTuple
from unittest import mock

from cosleec import cop
from cosleec.runtime import ContextError, Manager, VirtualClock
from tests.unit.runtime.lookalike import Lookalike
from tests.unit.semantics.differential import Case, HandClock

HEADER = """def_start
  event T
  event A
  event B
  event C
  measure b: boolean
  measure n: numeric
  constant K = 2
def_end
rule_start
"""


def build(text: str, express: bool, **options: Any) -> Manager:
    """A Manager of ``text``, with the express lane as asked."""
    with mock.patch.dict(os.environ, {"COSLEEC_EXPRESS": "1" if express else "0"}):
        return Manager.from_text(text, **options)


def taken(m: Manager) -> int:
    """How many triggers the lane took (0 with it off)."""
    lane, plans = m._express, m._plans  # what the lane took is what these tests are about
    return (0 if lane is None else lane.taken) + (0 if plans is None else plans.taken)


def updated(m: Manager) -> int:
    """How many updates the lane took (0 with it off)."""
    lane = m._express
    return 0 if lane is None else lane.updated


class Lanes(NamedTuple):
    """What the lane took of a run: triggers and updates."""

    triggers: int
    updates: int


def run(
    text: str,
    trace: list[tuple[float, str | dict[str, Any] | None]],
    *,
    express: bool,
    watch: bool,
    **options: Any,
) -> tuple[dict[str, Any], Lanes]:
    """Everything visible of a run of ``trace`` (time, event | values | None for a tick): an
    update's switches, or why it was rejected, and the values and layers after it too."""
    clock = HandClock()
    m = build(text, express, clock=clock, **options)
    records: list[tuple[Any, ...]] = []
    if watch:
        m.subscribe(lambda ev: records.append((ev.seq, ev.kind, ev.time, ev.data)))
    calls: list[tuple[str, int, str]] = []
    body = re.sub(r"(when|not) \w+", "", text.split("rule_start")[1])
    for action in sorted(set(re.findall(r"\b[ABC]\b", body))):  # the responses' events
        m.capability(action)(lambda ob, d, a=action: calls.append((a, d.id, d.rule)))
    m.start()
    returned = []
    try:
        for t, what in trace:
            clock.set(t)
            if isinstance(what, dict):
                try:
                    switches = [tuple(s) for s in m.update(what)]
                except ContextError as e:
                    returned.append(["rejected", e.message, e.hint])
                else:
                    returned.append([switches, m.values(), m.rule_layers(), m.active_layers()])
            elif what is None:
                m.tick()
            else:
                returned.append([d.to_json() for d in m.event(what)])
        m.tick()
        seen = {
            "records": records,
            "returned": returned,
            "calls": calls,
            "outstanding": [t.to_json() for t in m.outstanding(prohibitions=True)],
            "stats": dict(m.stats),
        }
        return seen, Lanes(taken(m), updated(m))
    finally:
        m.close()


def same(text: str, trace: list[tuple[float, Any]], **options: Any) -> Lanes:
    """Assert that the lane changes nothing visible, watched and not; what it took unwatched."""
    lanes = Lanes(0, 0)
    for watch in (True, False):
        general, none = run(text, trace, express=False, watch=watch, **options)
        fast, lanes = run(text, trace, express=True, watch=watch, **options)
        assert none == (0, 0)
        assert fast == general, (text, trace, watch)
    return lanes


def trace_of(case: Case) -> list[tuple[float, Any]]:
    return [(float(s.t), s.values or s.event) for s in case.trace]


def rules(*lines: str) -> str:
    return HEADER + "\n".join(lines) + "\nrule_end\n"


QUIET = rules("R1 when T then A within 5 seconds unless {b} then B within 2 seconds")


def test_a_quiet_trigger_takes_the_lane_and_decides_as_the_general_path() -> None:
    trace = [(0.0, {"b": False, "n": 1}), (1.0, "T"), (2.0, "A"), (3.0, {"b": True}), (4.0, "T"), (5.0, "B")]
    assert same(QUIET, trace) == (2, 2)


def test_with_records_read_the_lane_and_the_plan_take_the_quiet_case_and_record_what_the_general_path_does(
    tmp_path: Any,
) -> None:
    # an observer, then the audit log: the lane takes the quiet update and the event's plan
    # the quiet trigger, each in a step of its own, record for record as the general path
    trace = [(0.0, {"b": False, "n": 1}), (1.0, "T"), (2.0, "A"), (3.0, {"b": True}), (4.0, "T"), (5.0, "B")]
    for reader in ("observer", "audit"):
        seen = []
        for express in (False, True):
            clock = HandClock()
            audit = tmp_path / f"{reader}-{express}.jsonl" if reader == "audit" else None
            m = build(QUIET, express, clock=clock, audit=audit)
            heard: list[tuple[Any, ...]] = []
            if reader == "observer":
                m.subscribe(lambda ev, heard=heard: heard.append((ev.seq, ev.kind, ev.time, ev.data)))
            ran: list[tuple[str, int]] = []
            for action in "AB":
                m.capability(action)(lambda ob, d, a=action, ran=ran: ran.append((a, d.id)))
            m.start()
            for t, what in trace:
                clock.set(t)
                if isinstance(what, dict):
                    m.update(what)
                else:
                    m.event(what)
            m.close()
            if audit is not None:
                lines = [json.loads(line) for line in audit.read_text().splitlines()]
                heard = [  # each line whole, but for when it was written and the run's id
                    (
                        r["seq"],
                        r["kind"],
                        r["time"],
                        {k: v for k, v in r.items() if k not in ("wall", "mono", "run")},
                    )
                    for r in lines
                ]
            plans = 0 if m._plans is None else m._plans.taken
            seen.append((heard, ran, m.stats["decisions"], plans, taken(m), updated(m)))
        general, planned = seen
        assert planned[:3] == general[:3], reader
        assert any(k == "task-done" for _, k, _, _ in planned[0]), reader  # the outcome is recorded
        assert any(k == "layers" for _, k, _, _ in planned[0]), reader  # a switch is recorded
        assert general[3:] == (0, 0, 0)
        assert planned[3:5] == (2, 2), f"{reader}: the plan took {planned[3]} of the 2 quiet triggers"
        assert planned[5] == 2, f"{reader}: the lane took {planned[5]} of the 2 quiet updates"


def test_a_trigger_waiting_for_the_lock_while_the_last_observer_leaves_records_nothing() -> None:
    # (found by a hostile review) the plan's trigger reads whether records are read before it
    # takes the lock: it must read it again under the lock, both ways -- else an occurrence
    # record nobody hears uses up a record number, and a later observer's numbers differ
    text = rules("R1 when T then A within 5 seconds")
    seen = []
    for express in (False, True):
        m = build(text, express, clock=HandClock())
        m.capability("A")(lambda ob, d: None)
        m.start()
        late: list[tuple[int, str]] = []
        waiting: list[threading.Thread] = []
        leave: list[Any] = []

        def observer(
            ev: Any, m: Manager = m, waiting: list[threading.Thread] = waiting, leave: list[Any] = leave
        ) -> None:
            if ev.kind == "context" and not waiting:  # (delivered under the event's outer lock)
                waiting.append(threading.Thread(target=m.event, args=("T",)))
                waiting[0].start()
                time.sleep(0.2)  # the trigger waits for the lock meanwhile
                leave[0]()  # the last observer leaves

        leave.append(m.subscribe(observer))
        m.event("T", {"b": False, "n": 1})
        waiting[0].join()
        m.subscribe(lambda ev, late=late: late.append((ev.seq, str(ev.kind))))
        m.event("T")
        m.close()
        seen.append(late)
    assert seen[0] == seen[1], seen


# each: rules, a trace whose last trigger is not quiet, and why the lane must leave it
NOT_QUIET = {
    "an unknown measure": (QUIET, [(1.0, "T")]),
    "a prohibition decided": (rules("R1 when T then not B within 5 seconds"), [(1.0, "T")]),
    "an interval that opens later": (rules("R1 when T then A within [2 seconds, 5 seconds]"), [(1.0, "T")]),
    "a window closed at its start": (
        rules("R1 when T then A within (1 - {n}) seconds"),
        [(0.0, {"b": False, "n": 3}), (1.0, "T")],
    ),
    "an inner choice": (
        rules(
            "R1 when T then A within 2 seconds unless b then "
            "{B within 2 seconds unless (n > K) then C within 1 seconds}"
        ),
        [(0.0, {"b": True, "n": 1}), (1.0, "T")],
    ),
    "an `else` branch": (rules("R1 when T then A within 2 seconds else B within 3 seconds"), [(1.0, "T")]),
    "the event is awaited": (
        rules("R1 when T then A within 5 seconds", "R2 when A then B within 5 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "T"), (2.0, "A")],
    ),
    "a late event awaited": (
        rules("R1 when T then A within 1 seconds", "R2 when A then B within 5 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "T"), (3.0, None), (4.0, "A")],
    ),
    "a prohibition in force": (
        rules("R1 when C then not B within 9 seconds", "R2 when T then A within 5 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "C"), (2.0, "T")],
    ),
    "a deadline due": (
        rules("R1 when C then B within 1 seconds", "R2 when T then A within 5 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "C"), (3.0, "T")],
    ),
}


def test_each_condition_that_is_not_quiet_sends_the_trigger_to_the_general_path() -> None:
    for why, (text, trace) in NOT_QUIET.items():
        quiet_before = same(text, trace[:-1]).triggers
        assert same(text, trace).triggers == quiet_before, why  # the last trigger was not taken


def test_a_held_action_sends_triggers_to_the_general_path() -> None:
    # R1's action waits for its interval: held; a quiet trigger meanwhile goes the general way
    text = rules("R1 when C then B within [2 seconds, 5 seconds]", "R2 when T then A within 5 seconds")
    trace = [(0.0, {"b": False, "n": 1}), (1.0, "C"), (1.5, "T"), (4.0, "B"), (5.0, "T")]
    assert same(text, trace).triggers == 1  # only the T after B ran


def test_priorities_a_journal_aging_values_and_spoken_values_send_triggers_to_the_general_path(
    tmp_path: Any,
) -> None:
    text = rules("R1 when T then A within 5 seconds", "R2 when T then B within 5 seconds")
    trace: list[tuple[float, Any]] = [(0.0, {"b": False, "n": 1}), (1.0, "T")]
    assert same(text, trace) == (1, 1)
    # declared priorities send triggers the general way; an update only when they are
    # conflict-aware (time passing is then never quiet), which this default is not
    assert same(text, trace, priorities=[("R1", "R2")]) == (0, 1)
    assert same(text, trace, priorities=[("R1", "R2")], priority_semantics="conflict-aware") == (0, 0)
    assert same(text, trace, max_age={"n": 10.0}) == (0, 0)
    lanes = []
    for express in (False, True):
        m = build(text, express, clock=VirtualClock(), journal=tmp_path / f"{express}.db", dispatch=False)
        m.start()
        m.update({"b": False, "n": 1})
        m.event("T")
        lanes.append((taken(m), updated(m)))
        m.close()
    assert lanes == [(0, 0), (0, 0)]
    spoken = tmp_path / "say.yaml"
    spoken.write_text("R1: 'the value is {n}'\n", encoding="utf-8")
    assert same(text, trace, explanations=spoken).triggers == 0


def test_updates_take_the_lane_only_when_quiet_and_change_what_the_general_path_changes() -> None:
    # rejected updates (a wrong type, an unknown measure, a misspelt one) go the general way,
    # which says why, and change nothing; a number that changes only its type (1 -> 1.0)
    # changes the value; an update that changes nothing switches nothing
    trace: list[tuple[float, Any]] = [
        (0.0, {"b": False, "n": 1}),
        (0.5, {"b": 3}),
        (0.6, {"bb": True}),
        (0.7, {"n": "x", "b": True}),
        (0.8, {Lookalike("b"): True}),
        (1.0, {"n": 1.0}),
        (1.5, {"b": True, "n": 2}),
        (2.0, {"b": True}),
        (2.5, "T"),
        (3.0, {"b": False}),
        (4.0, "T"),
    ]
    assert same(QUIET, trace) == (2, 5)  # the 4 rejected updates went the general way


# each: rules, a trace whose last update is not quiet, and why the lane must leave it
UPDATES_NOT_QUIET = {
    "a deadline due": (
        rules("R1 when C then B within 1 seconds unless {b} then A within 1 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "C"), (3.0, {"b": True})],
    ),
    "a held action": (
        rules("R1 when C then B within [2 seconds, 5 seconds] unless {b} then A within 9 seconds"),
        [(0.0, {"b": False, "n": 1}), (1.0, "C"), (1.5, {"b": True})],
    ),
}


def test_each_condition_that_is_not_quiet_sends_the_update_to_the_general_path() -> None:
    for why, (text, trace) in UPDATES_NOT_QUIET.items():
        quiet_before = same(text, trace[:-1]).updates
        assert quiet_before >= 1, why
        assert same(text, trace).updates == quiet_before, why  # the last update was not taken


def test_a_closed_manager_refuses_an_update_on_either_path() -> None:
    for express in (False, True):
        m = build(QUIET, express, clock=VirtualClock())
        m.update({"b": False, "n": 1})
        m.close()
        try:
            m.update({"b": True})
        except Exception as e:  # the general path's refusal, whichever lane was asked
            assert "closed" in str(e), e
        else:
            raise AssertionError("a closed Manager took an update")
        assert updated(m) == (1 if express else 0)


class _Reading:
    """A value whose ``repr`` counts its calls (a sensor reading that shows a sample number)."""

    shown = 0

    def __repr__(self) -> str:
        _Reading.shown += 1
        return f"<reading #{_Reading.shown}>"


def test_a_rejected_update_is_checked_once_and_recorded_with_the_reason_the_lane_found() -> None:
    # the lane found the update wrong: the general path records it without checking it
    # again, so user code that checking runs (a value's repr) runs as often on both paths
    seen = []
    for express in (False, True):
        m = build(QUIET, express, clock=VirtualClock())
        m.start(check=False)
        _Reading.shown = 0
        try:
            m.update({"n": _Reading()})
        except ContextError as e:
            seen.append((e.message, _Reading.shown, m.stats["rejected"], m.stats["updates"]))
        m.close()
    assert seen[0] == seen[1] == ("n is numeric; got _Reading <reading #1>", 2, 1, 0)


def test_an_event_not_named_by_a_string_is_refused_on_either_path(tmp_path: Any) -> None:
    # the lane must not take what only looks like a declared event, nor fail on an
    # unhashable name: the general path refuses both, recorded and counted
    seen = []
    for express in (False, True):
        for audit in (None, tmp_path / f"{express}.jsonl"):
            m = build(QUIET, express, clock=VirtualClock(), unknown_events="refuse", audit=audit)
            m.start(check=False)
            m.update({"b": False, "n": 1})
            outcome = []
            for name in (Lookalike("T"), ["T"]):
                try:
                    outcome.append(len(m.event(name)))  # type: ignore[arg-type]
                except Exception as e:
                    outcome.append(type(e).__name__)
            outcome.append((m.stats["events"], m.stats["rejected"], len(m.outstanding())))
            seen.append(outcome)
            m.close()
    assert seen[0] == seen[1] == seen[2] == seen[3]
    assert seen[0][-1] == (0, 2, 0)


def test_a_decision_after_a_change_of_semantics_says_the_semantics_it_was_made_under() -> None:
    # the decider keeps each rule clause's common fields: a change of semantics makes them again
    text = rules("R1 when T then A within 5 seconds unless {b} then B within 2 seconds")
    for express in (False, True):
        m = build(text, express, clock=VirtualClock())
        m.start(check=False)
        m.update({"b": True, "n": 1})
        (before,) = m.event("T")
        m.set_semantics("nested")
        (after,) = m.event("T")
        assert (before.semantics, after.semantics) == ("last-wins", "nested"), express
        assert before.to_json()["semantics"] == "last-wins" and after.to_json()["semantics"] == "nested"
        m.close()


def test_values_given_with_an_event_not_named_by_a_string_are_not_applied() -> None:
    # all or nothing: the event is refused, so its values are not applied either
    for express in (False, True):
        m = build(QUIET, express, clock=VirtualClock(), unknown_events="raise")
        m.start(check=False)
        m.update({"b": False, "n": 1})
        for name in (Lookalike("T"), ["T"]):
            try:
                m.event(name, {"b": True})  # type: ignore[arg-type]
            except Exception as e:
                assert "string" in str(e), (express, e)
            else:
                raise AssertionError("an event not named by a string was taken")
            assert m.values()["b"] is False, express
        m.close()


def test_a_clause_layer_active_globally_is_met_as_the_general_path_meets_it() -> None:
    """The robot's code has one of a rule's clause layers on globally when the event's plan is
    made: the plan must not try the rule's other clauses' layers then (their exclusive group
    would refuse them, and the trigger with them: fail open); it decides and runs as the
    general path does (a hostile review's case)."""
    text = rules(
        "R1 when T then A within 5 seconds unless {b} then B within 2 seconds unless {c} then C within 2 seconds"
    )
    text = text.replace("measure b: boolean", "measure b: boolean\n  measure c: boolean")
    seen = []
    for express in (True, False):
        m = build(text, express, clock=VirtualClock())
        calls: list[tuple[str, list[str]]] = []
        for e in "ABC":
            m.capability(e)(
                lambda ob, d, e=e, calls=calls: calls.append((e, [la.name for la in cop.active_layers()]))
            )
        m.start()
        m.update({"b": True, "c": True, "n": 1})  # R1.2 chosen
        r12 = m.ruleset.by_name["R1"].layers[1]
        cop.activate_globally(r12)
        try:
            got = [(d.id, d.layer) for d in m.event("T")]
            m.set_semantics("nested")  # (a new plan, made with the layer still on)
            got += [(d.id, d.layer) for d in m.event("T")]
        finally:
            cop.deactivate_globally(r12)
        seen.append((got, calls, m.stats["events"], m.stats["task_failures"], len(m.outstanding())))
        m.close()
    assert seen[0] == seen[1]
    assert seen[0][0][0] == (1, "R1.2") and seen[0][1][0] == ("C", ["R1.2"])


def test_a_planned_decision_is_the_general_path_s_field_for_field() -> None:
    """The plan makes the inline case's decision itself (Decision.from_trigger_fields, with the
    clause's obligations in its common fields): every field, the memos and what is made when
    first read included, must be the general path's -- one rule inline, two rules, a clause
    and the default, values unknown to the decision but not to the condition."""
    text = rules(
        "R1 when T and {b} then A within 5 seconds unless {b} then B within 2 seconds",
        "R2 when C then A within 3 seconds",
        "R3 when C then B within 4 seconds unless (n > K) then A within 1 seconds",
    )
    made = []
    for express in (True, False):
        m = build(text, express, clock=VirtualClock(3))  # (a clock that counts in whole seconds)
        m.start(check=False)
        m.update({"b": True, "n": 5})
        got = m.event("T") + m.event("C")
        m.update({"n": 1})
        got += m.event("C")
        fields = [{k: v for k, v in vars(d).items() if k != "_parts"} for d in got]
        parts = [(p[0].name, *p[1:]) for p in (vars(d)["_parts"] for d in got)]  # (each Manager's own rule)
        made.append((fields, parts, [(d.values, d.conditions, d.explanation) for d in got]))
        assert taken(m) == (3 if express else 0)
        m.close()
    assert made[0] == made[1]
