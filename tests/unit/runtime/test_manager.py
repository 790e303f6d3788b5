"""The CO-SLEEC runtime: mapping, context, layers, dispatch, obligations, transparency."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from cosleec.cop import explain, run_with
from cosleec.runtime import BindingError, ContextError, Manager, Task, VirtualClock, hedge
from cosleec.runtime import read_audit as read

CURTAINS = """
def_start
  event CurtainOpenRequest event OpenCurtains event Refuse event ExplainWhy event WarnUser
  measure userUndressed : boolean
  measure userDistressed : scale(low, medium, high)
def_end
rule_start
  R1 when CurtainOpenRequest then OpenCurtains within 30 seconds
     unless userUndressed then Refuse and ExplainWhy
     unless userDistressed >= high then WarnUser and OpenCurtains within 10 seconds
rule_end
"""


def manager(text: str = CURTAINS, **kw: object) -> tuple[Manager, VirtualClock]:
    clock = VirtualClock()
    return Manager.from_text(text, clock=clock, **kw), clock  # type: ignore[arg-type]


class Curtains(Task):
    rule = "R1"

    def __init__(self) -> None:
        self.calls: list[str] = []

    def default(self, d):  # type: ignore[no-untyped-def]
        self.calls.append("default")
        self.event("OpenCurtains")

    @hedge(1)
    def refuse(self, d):  # type: ignore[no-untyped-def]
        self.calls.append("refuse:" + d.explanation)
        self.event("Refuse")
        self.event("ExplainWhy")

    @hedge("R1.2")
    def warn(self, d):  # type: ignore[no-untyped-def]
        self.calls.append("warn")
        self.event("WarnUser")


# ---------------------------------------------------------------- 1. mapping


def test_each_rule_is_a_layered_method_with_one_layer_per_clause() -> None:
    m, _ = manager()
    task = Curtains()
    m.bind(task).start()
    rule = m.ruleset.rule("R1")
    handler = m.implementations.handler(rule)
    r11, r12 = rule.layers
    assert (r11.name, r12.name) == ("R1.1", "R1.2")
    assert r11.group is r12.group and r11.group is not None  # one exclusive group per rule
    assert set(handler.layered.partials) == {r11, r12}  # type: ignore[attr-defined]
    # the Layer Manager activates the layer the context selects ...
    m.update(userUndressed=True, userDistressed="low")
    assert m.active_layers() == ["R1.1"] and m.layer_manager.composition().layers == (r11,)
    (d,) = m.event("CurtainOpenRequest")
    assert (d.clause, d.layer) == (1, "R1.1")
    # ... and the trigger runs, through COP, the variant of that layer
    assert run_with(rule.compositions[d.clause], explain, handler, d).chain == ("R1.1",)
    assert task.calls[0].startswith("refuse:")
    m.update(userDistressed="high")  # the last clause that holds wins
    assert m.active_layers() == ["R1.2"] and m.layer_manager.composition().layers == (r12,)
    m.event("CurtainOpenRequest")
    assert task.calls[-1] == "warn"
    m.update(userUndressed=False, userDistressed="low")
    assert m.active_layers() == [] and m.layer_manager.composition().layers == ()
    m.event("CurtainOpenRequest")
    assert task.calls[-1] == "default"


# ---------------------------------------------------------------- 2. context


@pytest.mark.parametrize(
    "update",
    [
        {"userUndressed": "yes"},
        {"nope": True},
        {"userDistressed": "extreme"},
        {"userDistressed": 2},
        {"userUndressed": False, "userDistressed": "extreme"},
    ],
)
def test_bad_updates_are_rejected_with_a_reason_and_change_nothing(update: dict[str, object]) -> None:
    m, _ = manager()
    m.update(userUndressed=True, userDistressed="low")
    before = m.values()
    seen = []
    m.subscribe(lambda e: seen.append(e))
    with pytest.raises(ContextError) as info:
        m.update(update)
    assert str(info.value)
    assert m.values() == before
    assert seen[-1].kind == "rejected" and m.stats["rejected"] == 1


def test_stale_values_become_unknown_and_the_fail_safe_choice_applies() -> None:
    m, clock = manager(max_age={"userUndressed": 5.0})
    m.update(userUndressed=False, userDistressed="low")
    assert m.event("CurtainOpenRequest")[0].clause == 0
    clock.advance(6)
    (d,) = m.event("CurtainOpenRequest")
    assert d.clause is None and d.missing == ("userUndressed",) and d.obligations == ()
    assert "undetermined" in d.explanation
    m2, clock2 = manager(max_age={"userUndressed": 5.0}, unknown="true")
    m2.update(userUndressed=False, userDistressed="low")
    clock2.advance(6)
    assert m2.event("CurtainOpenRequest")[0].clause == 1  # unknown read as true: the privacy clause


# ---------------------------------------------------------------- 3. layer manager


def test_only_rules_reading_a_changed_measure_are_reevaluated() -> None:
    rules = "\n".join(f"R{i} when E{i % 3} then F unless m{i} then G" for i in range(30))
    defs = " ".join(f"measure m{i} : boolean" for i in range(30))
    m, _ = manager(
        f"def_start event E0 event E1 event E2 event F event G {defs} def_end rule_start {rules} rule_end"
    )
    evaluated: list[str] = []
    original = m.layer_manager._compute

    def counting(rule, v):  # type: ignore[no-untyped-def]
        evaluated.append(rule.name)
        return original(rule, v)

    m.layer_manager._compute = counting  # type: ignore[method-assign]
    switches = m.update(m7=True)
    assert evaluated == ["R7"] and switches == [("R7", "?", "R7.1")]
    evaluated.clear()
    m.update(m7=True)
    assert evaluated == []  # unchanged value: nothing to do


FIREFIGHTER = """
def_start event CameraStart event SoundAlarm event GoHome event BatteryCritical
  measure personNearby : boolean measure temperature : numeric def_end
rule_start
  Rule4 when CameraStart then SoundAlarm unless personNearby then GoHome unless temperature > 35
  RuleC when BatteryCritical then CameraStart unless personNearby then GoHome unless temperature > 35 then SoundAlarm
rule_end
"""


@pytest.mark.parametrize(
    ("person", "temp", "last_wins", "nested"),
    [
        (False, 20, "SoundAlarm", "SoundAlarm"),
        (True, 20, "GoHome", "GoHome"),
        (False, 40, "", "SoundAlarm"),
        (True, 40, "", ""),
    ],
)
def test_semantics_last_wins_and_nested_on_the_reference_examples(
    person: bool, temp: int, last_wins: str, nested: str
) -> None:
    for semantics, want in (("last-wins", last_wins), ("nested", nested)):
        m, _ = manager(FIREFIGHTER, semantics=semantics)
        m.update(personNearby=person, temperature=temp)
        (d,) = m.event("CameraStart")
        assert " ".join(o.event for o in d.obligations) == want
        assert d.semantics == semantics


# ---------------------------------------------------------------- 4. tasks and capabilities


def test_completeness_check_lists_what_is_missing() -> None:
    m, _ = manager()

    class Partial(Task):
        rule = "R1"

        def default(self, d):  # type: ignore[no-untyped-def]
            pass

        @hedge(1)
        def refuse(self, d):  # type: ignore[no-untyped-def]
            pass

    m.bind(Partial())
    with pytest.raises(BindingError) as info:
        m.start()
    assert info.value.missing == [
        "R1.2: task Partial has no @hedge(2) implementation (unless userDistressed >= high)"
    ]
    m2, _ = manager()
    with pytest.raises(BindingError) as info2:
        m2.start()
    assert "R1: no task and no capability for response event OpenCurtains" in info2.value.missing
    with pytest.raises(BindingError):
        m2.bind(type("Bad", (Task,), {"rule": "R9"})())


def test_capability_style_composes_one_handler_per_event() -> None:
    m, _ = manager()
    done: list[str] = []
    for ev in ("OpenCurtains", "Refuse", "ExplainWhy", "WarnUser"):

        @m.capability(ev)
        def _(ob, d, ev=ev):  # type: ignore[no-untyped-def]
            done.append(ev)
            m.event(ev)

    m.start()
    m.update(userUndressed=True, userDistressed="high")
    m.event("CurtainOpenRequest")
    assert done == ["WarnUser", "OpenCurtains"]


def test_a_failing_task_yields_violations_not_a_stuck_manager() -> None:
    m, clock = manager()

    class Crashing(Curtains):
        def default(self, d):  # type: ignore[no-untyped-def]
            raise RuntimeError("motor fault")

    m.bind(Crashing()).start()
    m.update(userUndressed=False, userDistressed="low")
    m.event("CurtainOpenRequest")
    assert m.implementations.failures == 1
    clock.advance(31)
    m.tick()
    assert m.stats["violations"] == 1 and m.outstanding() == []


# ---------------------------------------------------------------- 5. consistency under races


def test_racing_updates_and_triggers_never_see_a_half_applied_update() -> None:
    text = """def_start event E event F event G measure a : numeric measure b : numeric def_end
      rule_start R when E then F unless a = b then G rule_end"""
    m, _ = manager(text)
    m.update(a=0, b=0)
    stop = threading.Event()

    def writer() -> None:
        i = 0
        while not stop.is_set():
            i += 1
            m.update(a=i, b=i)  # one atomic update: a == b always

    threads = [threading.Thread(target=writer, daemon=True) for _ in range(2)]
    for t in threads:
        t.start()
    decisions = []
    try:
        for _ in range(3000):
            decisions += m.event("E")
    finally:
        stop.set()
        for t in threads:
            t.join()
    assert all(d.values["a"] == d.values["b"] and d.clause == 1 for d in decisions)


# ---------------------------------------------------------------- 6. obligations


OBL = """
def_start event T event A event B event C event D event X measure ok : boolean def_end
rule_start
  W when T then A within 10 seconds otherwise B within 5 seconds otherwise C
  P when T then not X within 20 seconds otherwise D within 5 seconds
  I when T then C within [5 seconds, 8 seconds] else D
  U when T then D eventually
rule_end
"""


def test_deadline_is_judged_by_reported_events_and_otherwise_fires_only_on_a_miss() -> None:
    m, clock = manager(OBL)
    m.event("T")
    clock.advance(10)
    m.event("A")  # at t+T exactly: inclusive
    clock.advance(100)
    m.tick()
    assert not [d for d in m.decisions if d.event == "otherwise" and d.rule == "W"]
    m.event("T")
    clock.advance(10.5)
    fallbacks = m.tick()
    assert [(d.rule, [o.event for o in d.obligations]) for d in fallbacks] == [("W", ["B"])]
    assert fallbacks[0].time == pytest.approx(120)  # the fallback starts at the deadline
    m.event("A")  # late: recorded, does not cancel the fallback
    w = [t for t in m.tracker.closed if t.rule == "W" and t.event == "A" and t.status == "violated"]
    assert w and w[0].late == [pytest.approx(120.5)]
    clock.advance(5)
    follow = m.tick()  # B missed too: the chain goes on to C
    assert [o.event for d in follow for o in d.obligations] == ["C"]


def test_prohibitions_refuse_requests_and_violations_start_otherwise() -> None:
    m, clock = manager(OBL)
    m.event("T")
    assert m.request("X").permitted is False and m.stats["refused"] == 1
    clock.advance(3)
    m.event("X")  # happened anyway
    x = next(t for t in m.tracker.closed if t.event == "X")
    assert (x.status, x.outcome_at, x.refused) == ("violated", 3, 1)
    d = next(d for d in m.decisions if d.event == "otherwise" and d.rule == "P")
    assert d.time == 3 and [o.event for o in d.obligations] == ["D"]
    clock.advance(30)
    m.tick()
    assert m.request("X").permitted is True


def test_interval_else_and_eventually() -> None:
    m, clock = manager(OBL)
    m.event("T")
    clock.advance(2)
    m.event("C")  # before the interval opens: neither fulfils nor violates
    i = next(t for t in m.tracker.active if t.rule == "I")
    assert i.status == "pending"
    clock.advance(4)
    m.event("D")  # the else alternative fulfils it
    assert i.status == "fulfilled" and i.by == "D"
    u = [t for t in m.tracker.closed if t.rule == "U"]
    assert u and u[0].hi is None and u[0].status == "fulfilled"  # eventually: no deadline; D counts


def test_untimed_obligations_stay_pending_unless_configured() -> None:
    text = "def_start event T event A def_end rule_start R when T then A rule_end"
    m, clock = manager(text)
    m.event("T")
    clock.advance(1000)
    m.tick()
    assert [t.event for t in m.outstanding()] == ["A"]
    m2, clock2 = manager(text, untimed="immediate")
    m2.event("T")
    clock2.advance(2)
    m2.tick()
    assert m2.stats["violations"] == 1


# ---------------------------------------------------------------- 7. transparency


def test_explanations_and_audit_log(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager(audit=str(log))
    m.bind(Curtains()).start()
    m.update(userUndressed=True, userDistressed="low")
    (d,) = m.event("CurtainOpenRequest")
    assert d.explanation == (
        "R1: Refuse and ExplainWhy [clause 1 (unless userUndressed)], because userUndressed was true; "
        "userDistressed >= high was false (userDistressed = low)"
    )
    m.close()
    records = read(log)
    kinds = [r["kind"] for r in records]
    assert kinds[:5] == [
        "options",
        "context",
        "layers",
        "event",
        "decision",
    ]  # options: start() says how it runs
    assert records[0]["semantics"] == "last-wins" and records[0]["priorities"] == []
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    assert {r["run"] for r in records} == {m.run_id} and {r["rules"] for r in records} == {
        m.ruleset.digest[:16]
    }
    dec = records[4]
    assert dec["rule"] == "R1" and dec["layer"] == "R1.1" and dec["values"]["userUndressed"] is True
    assert [c["value"] for c in dec["conditions"]] == [True, True, False]
    assert {r["status"] for r in records if r["kind"] == "obligation"} == {"pending", "fulfilled"}


def test_audit_log_loses_nothing_when_the_process_dies(tmp_path: Path) -> None:
    log = tmp_path / "crash.jsonl"
    script = f"""
import os
from cosleec.runtime import Manager, VirtualClock
m = Manager.from_text({CURTAINS!r}, clock=VirtualClock(), audit={str(log)!r}, dispatch=False)
m.update(userUndressed=False, userDistressed="low")
for _ in range(50):
    m.event("CurtainOpenRequest")
os._exit(1)  # no close, no flush at exit
"""
    subprocess.run([sys.executable, "-c", script], check=False)
    records = read(log)
    assert sum(r["kind"] == "decision" for r in records) == 50
    assert all(json.dumps(r) for r in records)


def test_a_decision_runs_its_own_clause_even_if_the_context_moves_before_dispatch() -> None:
    """The composition is taken with the decision, under the lock: an update that lands
    between the decision and its dispatch (here, from an observer) cannot swap the variant."""
    m, _ = manager()
    task = Curtains()
    m.bind(task).start()
    m.update(userUndressed=True, userDistressed="low")
    moved = []

    def move_on_decision(ev):  # type: ignore[no-untyped-def]
        if ev.kind == "decision" and not moved:
            moved.append(True)
            m.update(userUndressed=False)  # R1 is back at its default before the dispatch

    m.subscribe(move_on_decision)
    (d,) = m.event("CurtainOpenRequest")
    assert moved and d.clause == 1
    assert task.calls[-1].startswith("refuse:")  # the variant of clause 1, not the default
    assert m.active_layers() == []


def test_a_rules_layers_exclude_each_other_when_composed_by_hand() -> None:
    from cosleec.cop import ExclusionError, activate

    m, _ = manager()
    r11, r12 = m.ruleset.rule("R1").layers
    with pytest.raises(ExclusionError), activate(r11, r12):
        pass


def test_tasks_keep_the_callers_layers_and_can_activate_their_own() -> None:
    """A decision adds its clause's layer to what is active; it never replaces it."""
    from cosleec.cop import Layer, activate, activate_globally, deactivate_globally, layered

    quiet = Layer("Quiet")

    @layered
    def speak(msg: str) -> str:
        return msg.upper()

    @speak.variant(quiet)
    def _(msg: str, *, proceed: object) -> str:
        return msg.lower()

    heard: list[str] = []

    class Speaker(Curtains):
        def default(self, d):  # type: ignore[no-untyped-def]
            heard.append(speak("Hello"))
            with activate(quiet):
                heard.append(speak("Hello"))
            self.event("OpenCurtains")

    m, _ = manager()
    m.bind(Speaker()).start()
    m.update(userUndressed=False, userDistressed="low")
    m.event("CurtainOpenRequest")
    assert heard == ["HELLO", "hello"]  # the task's own activation takes effect
    activate_globally(quiet)
    try:
        m.event("CurtainOpenRequest")
    finally:
        deactivate_globally(quiet)
    assert heard[2:] == ["hello", "hello"]  # a layer active around the trigger stays active in the task


@pytest.mark.parametrize(
    ("unknown", "semantics", "values", "rule", "why"),
    [
        ("true", "last-wins", {"x": False}, 0, "because y was unknown"),
        ("true", "last-wins", {}, 0, "because y was unknown"),
        ("false", "nested", {"x": True}, 0, "because x was true; y was unknown"),
        ("false", "nested", {"x": True, "z": False}, 1, "because x was true; y was unknown"),
    ],
)
def test_explanations_name_the_unknown_values_the_policy_read(
    unknown: str, semantics: str, values: dict[str, bool], rule: int, why: str
) -> None:
    text = """def_start event T event A event B event C
      measure x : boolean measure y : boolean measure z : boolean def_end
    rule_start
      R1 when T then A unless x then B unless y then C
      R2 when T then A unless x then B unless y then C unless z then A
    rule_end"""
    m = Manager.from_text(text, dispatch=False, unknown=unknown, semantics=semantics)
    if values:
        m.update(values)
    assert m.event("T")[rule].explanation.endswith(why)


def test_layer_switches_come_in_rule_order_whatever_the_hash_seed() -> None:
    import os
    import subprocess
    import sys

    script = (
        "from cosleec.runtime import Manager\n"
        "defs = ' '.join(f'measure m{i} : boolean' for i in range(12))\n"
        "rules = ' '.join(f'R{i} when E then F unless m{i} then G' for i in range(12))\n"
        "m = Manager.from_text(f'def_start event E event F event G {defs} def_end rule_start {rules} rule_end')\n"
        "print([s.rule for s in m.update({f'm{i}': True for i in range(12)})])\n"
    )
    outs = {
        subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            check=True,
            env={**os.environ, "PYTHONHASHSEED": seed},
        ).stdout
        for seed in ("1", "2", "3")
    }
    assert outs == {str([f"R{i}" for i in range(12)]) + "\n"}


def test_a_binding_error_names_the_first_twenty_gaps_and_counts_the_rest() -> None:
    events = " ".join(f"event E{i} event A{i}" for i in range(30))
    rules = " ".join(f"R{i} when E{i} then A{i}" for i in range(30))
    m = Manager.from_text(f"def_start {events} def_end rule_start {rules} rule_end", clock=VirtualClock())
    with pytest.raises(BindingError) as info:
        m.start()
    assert len(info.value.missing) == 30
    text = str(info.value)
    assert "R19: no task and no capability for response event A19" in text
    assert "R20:" not in text
    assert "... and 10 more (BindingError.missing lists them all)" in text


def test_a_policy_that_reads_unknown_as_true_has_its_layer_active_before_any_value() -> None:
    text = (
        "def_start event E event A event B measure c : boolean def_end "
        "rule_start R when E then A unless c then B rule_end"
    )
    assert Manager.from_text(text, clock=VirtualClock(), unknown="true").active_layers() == ["R.1"]
    assert Manager.from_text(text, clock=VirtualClock(), unknown="false").active_layers() == []
    assert Manager.from_text(text, clock=VirtualClock()).active_layers() == []
