"""Manager.reload: new rules while the robot runs, swapped between two decisions.

What is kept (obligations of items the new rules still have, values of measures still
declared), what is withdrawn (everything of removed rules: never violated, no
``otherwise``), what is refused (nothing changes), what the audit and the journal say, and
that a reload to the same rules is invisible (a Manager that never reloaded is the oracle).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.runtime import (
    Decision,
    Manager,
    Obligation,
    ReloadError,
    RuleSet,
    Task,
    VirtualClock,
    hedge,
    read_audit,
)
from tests.unit.runtime.test_enforcement import DEFS, manager
from tests.unit.runtime.test_journal import RULES, again, die_after

R1 = "R1 when E then F within 5 seconds otherwise Help"
R2 = "R2 when G then not Rec within 10 seconds unless a"
R3 = "R3 when Z then Help within 3 seconds"


def spec(rules: str, defs: str = "") -> str:
    """The text test_enforcement's ``manager`` builds: its DEFS, ``defs``, then ``rules``."""
    return f"{DEFS}{defs} def_end rule_start {rules} rule_end"


def ruleset(rules: str, defs: str = "") -> RuleSet:
    return RuleSet.from_text(spec(rules, defs))


def kinds(log: Path, kind: str) -> list[dict[str, Any]]:
    return [r for r in read_audit(log) if r["kind"] == kind]


def statuses(log: Path, oid: int) -> list[str]:
    return [r["status"] for r in kinds(log, "obligation") if r["id"] == oid]


def noop(ob: Obligation, d: Decision) -> None:
    pass


# ---------------------------------------------------------------------------- kept


def test_a_kept_obligation_is_still_fulfilled_after_a_reload() -> None:
    m, clock = manager(f"{R1} {R2}", " event Z")
    m.event("E")
    (ob,) = m.outstanding()
    done = m.reload(ruleset(f"{R1} {R3}", " event Z"))
    assert (done.added, done.removed, done.changed, done.withdrawn) == (("R3",), ("R2",), (), ())
    assert m.outstanding() == [ob]  # the very obligation, in force
    clock.advance(5)  # its deadline instant: still inside the window
    m.event("F")
    assert ob.status == "fulfilled" and m.stats["violations"] == 0


def test_a_kept_obligation_is_still_violated_and_its_rules_new_otherwise_runs() -> None:
    ran: list[str] = []
    m, clock = manager(R1)
    m.capability("F")(noop)
    m.capability("Help")(lambda ob, d: ran.append("Help"))
    m.start()
    m.event("E")
    done = m.reload(
        ruleset(R1.replace("otherwise Help", "otherwise G")),
        capabilities={"G": lambda ob, d: ran.append("G")},
    )
    assert done.changed == ("R1",) and done.withdrawn == ()
    clock.advance(5)
    m.tick()
    assert ran == [] and m.stats["violations"] == 0  # at the deadline: not yet missed
    clock.advance(0.5)
    m.tick()
    assert m.stats["violations"] == 1 and ran == ["G"]  # the otherwise the rules say now (as a restart would)


def test_a_kept_obligation_keeps_the_window_it_was_decided_with() -> None:
    m, clock = manager("R4 when E then F within 5 seconds")
    m.event("E")
    m.reload(ruleset("R4 when E then F within 50 seconds"))
    (d,) = m.event("E")  # decided by the new text
    assert d.obligations[0].within_s == 50
    clock.advance(6)
    m.tick()
    assert m.stats["violations"] == 1  # the first one, by its own 5 s
    assert [t.hi for t in m.outstanding()] == [50.0]


# ---------------------------------------------------------------------------- withdrawn


def test_a_removed_rules_obligation_is_withdrawn_never_violated_and_its_otherwise_never_runs(
    tmp_path: Path,
) -> None:
    log = tmp_path / "audit.jsonl"
    helped: list[int] = []
    m, clock = manager(f"{R1} {R2}", audit=log)
    m.capability("F")(noop)
    m.capability("Help")(lambda ob, d: helped.append(d.id))
    m.start()
    clock.set(3)
    m.event("E")  # obligation 1: F by 8, otherwise Help
    clock.set(4)
    done = m.reload(ruleset(R2))
    assert done.removed == ("R1",) and done.withdrawn == (1,)
    assert m.outstanding() == []
    clock.set(100)
    m.tick()
    m.event("F")  # no late event either: it was never missed
    m.close()
    assert helped == [] and m.stats["violations"] == 0
    assert statuses(log, 1) == ["pending", "withdrawn"]
    (w,) = [r for r in kinds(log, "obligation") if r["status"] == "withdrawn"]
    assert w["at"] == 4 and w["by"] is None and w["rule"] == "R1"
    (rec,) = kinds(log, "reloaded")
    assert rec["withdrawn"] == [1] and rec["seq"] == w["seq"] - 1  # the reload, then each withdrawal


def test_a_removed_rules_prohibition_no_longer_forbids_and_a_kept_ones_still_does() -> None:
    m, _ = manager(f"{R2} R5 when G then not Help within 10 seconds")
    m.update(a=False)
    m.event("G")
    assert not m.permission("Rec") and not m.permission("Help")
    done = m.reload(ruleset("R5 when G then not Help within 10 seconds"))
    assert done.withdrawn == (1,)
    assert m.permission("Rec").permitted
    assert m.permission("Help").rules == ("R5",)


def test_an_obligation_whose_item_the_changed_rule_no_longer_has_is_withdrawn() -> None:
    m, _ = manager("R4 when E then F within 5 seconds")
    (before,) = m.event("E")
    done = m.reload(ruleset("R4 when E then G within 5 seconds"))
    assert done.changed == ("R4",) and done.withdrawn == (1,)  # kept only while its item is there
    (after,) = m.event("E")
    assert [o.event for o in before.obligations] == ["F"] and [o.event for o in after.obligations] == ["G"]
    assert [t.event for t in m.outstanding()] == ["G"]


def test_a_held_decision_of_a_removed_rule_is_withheld_and_never_runs(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    ran: list[str] = []
    m, clock = manager("R1 when E then F within 30 seconds R5 when G then not F within 10 seconds", audit=log)
    m.capability("F")(lambda ob, d: ran.append("F"))
    m.start()
    m.event("G")
    m.event("E")  # held: F is forbidden for 10 s more
    m.reload(ruleset("R5 when G then not F within 10 seconds"))
    clock.advance(60)
    m.tick()
    m.close()
    assert ran == []
    (w,) = kinds(log, "withheld")
    assert w["rule"] == "R1" and w["reason"] == "its rule R1 was removed by a reload"
    assert kinds(log, "reloaded")[0]["withheld"] == [w["decision"]]


def test_a_held_decision_runs_at_the_reload_that_withdraws_what_held_it() -> None:
    ran: list[str] = []
    m, _ = manager("R1 when E then F within 30 seconds R5 when G then not F within 10 seconds")
    m.capability("F")(lambda ob, d: ran.append("F"))
    m.start()
    m.event("G")
    m.event("E")
    assert ran == []
    m.reload(ruleset("R1 when E then F within 30 seconds"))
    assert ran == ["F"]  # no longer forbidden: it runs now, not at 10 s


def test_a_miss_of_a_removed_rule_no_longer_waits_for_its_late_event(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, clock = manager("R4 when E then F within 5 seconds", audit=log)
    m.event("E")
    clock.advance(6)
    m.tick()  # missed: a late F would still be reported, once
    m.reload(ruleset("R5 when E then G"))
    m.event("F")
    m.close()
    assert statuses(log, 1) == ["pending", "violated"]  # no late report after the reload
    assert [r["what"] for r in kinds(log, "dropped")] == [
        "obligation 1 (R4: F within 5 s): the rules no longer have it"
    ]


def test_a_kept_obligation_whose_item_moved_is_journaled_with_its_new_item(tmp_path: Path) -> None:
    import json
    import sqlite3

    m, _ = manager("R4 when E then F within 5 seconds", journal=tmp_path / "state.db")
    m.event("E")
    done = m.reload(ruleset("R4 when E then G within 5 seconds and F within 5 seconds"))
    assert done.withdrawn == () and [t.obligation.item for t in m.outstanding()] == ["R4:1"]
    m.close()
    db = sqlite3.connect(tmp_path / "state.db")
    ((row,),) = db.execute("SELECT record FROM obligations").fetchall()
    db.close()
    assert json.loads(row)["obligation"]["item"] == "R4:1"  # the journal holds what the Manager does


def test_a_decision_runs_with_the_implementation_bound_when_it_was_made() -> None:
    ran: list[str] = []

    class Old(Task):
        rule = "R1"

        def default(self, d: Decision) -> None:
            ran.append("old")

    class New(Old):
        def default(self, d: Decision) -> None:
            ran.append("new")

    rules = "R1 when E then F within 30 seconds R5 when G then not F within 10 seconds"
    m, clock = manager(rules)
    m.bind(Old())
    m.start()
    m.event("G")
    m.event("E")  # held until 10 s
    m.reload(ruleset(rules), tasks=[New()])
    clock.advance(11)
    m.tick()
    m.event("E")
    assert ran == ["old", "new"]


# ---------------------------------------------------------------------------- new rules, context, layers


def test_a_new_rule_triggers_after_the_reload_and_not_before() -> None:
    m, _ = manager(R1, " event Z")
    assert m.event("Z") == []
    m.reload(ruleset(f"{R1} {R3}", " event Z"))
    (d,) = m.event("Z")
    assert d.rule == "R3" and [o.event for o in d.obligations] == ["Help"]


def test_values_of_measures_still_declared_are_kept_others_dropped_new_ones_unknown(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager(R1, " measure level : scale(low, high) measure gone : boolean", audit=log)
    m.update(a=True, level="high", gone=True)
    done = m.reload(ruleset(R1, " measure level : scale(high, medium, low) measure c : boolean"))
    assert m.values() == {"a": True, "b": None, "level": "high", "c": None}  # high by name, not position
    m.close()
    assert [r["what"] for r in kinds(log, "dropped")] == ["measure gone: the rules no longer declare it"]
    (rec,) = kinds(log, "reloaded")
    assert rec["measures_added"] == ["c"] and rec["measures_removed"] == ["gone"]
    assert done.changed == ()


def test_a_kept_value_keeps_its_age_and_max_age_returns_with_its_measure() -> None:
    m, clock = manager(R1, " measure tmp : boolean", max_age={"a": 5.0, "tmp": 5.0})
    m.update(a=True)
    clock.advance(3)
    m.reload(ruleset(R1))  # tmp no longer declared: its max_age waits
    clock.advance(3)
    m.tick()
    assert m.values()["a"] is None  # set 6 s ago: stale (a reload does not make it new)
    m.reload(ruleset(R1, " measure tmp : boolean"))
    m.update(tmp=True)
    clock.advance(6)
    m.tick()
    assert m.values()["tmp"] is None  # aged again


def test_layers_are_recomputed_for_the_new_rules_under_the_current_context(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager("R1 when E then F unless a then G R9 when G then F unless a then Help", audit=log)
    m.update(a=True, b=False)
    assert m.active_layers() == ["R1.1", "R9.1"]
    m.reload(ruleset("R1 when E then F unless b then G R8 when E then G unless a then F"))
    assert m.active_layers() == ["R8.1"]
    (d,) = [d for d in m.event("E") if d.rule == "R8"]
    assert d.clause == 1
    m.close()
    last = kinds(log, "layers")[-1]
    assert last["active"] == ["R8.1"]
    assert last["switches"] == [
        {"rule": "R1", "from": "R1.1", "to": None},
        {"rule": "R8", "from": None, "to": "R8.1"},
        {"rule": "R9", "from": "R9.1", "to": None},
    ]


def test_a_priority_the_reload_adds_cancels_the_lower_activation_in_force(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager("R1 when E then F within 60 seconds R4 when G then Help within 60 seconds", audit=log)
    m.event("E")
    m.event("G")
    same = ruleset("R1 when E then F within 60 seconds R4 when G then Help within 60 seconds")
    m.reload(same, priorities=["R1 > R4"])
    assert [t.event for t in m.outstanding()] == ["F"]
    m.close()
    (c,) = kinds(log, "cancelled")
    assert c["rule"] == "R4" and c["by"] == "R1"
    assert kinds(log, "reloaded")[0]["priorities"] == [["R1", "R4"]]


# ---------------------------------------------------------------------------- refused


class R1Task(Task):
    rule = "R1"

    def default(self, d: Decision) -> None:
        pass

    @hedge(1)
    def unless_a(self, d: Decision) -> None:
        pass


class R9Task(Task):
    rule = "R9"

    def default(self, d: Decision) -> None:
        pass


def _kind_changes(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(R1, " measure level : scale(low, high)"), clock=VirtualClock(), audit=log)
    m.update(level="high")
    return m, ruleset(R1, " measure level : numeric"), {}, "measure level holds 'high' as a scale"


def _literal_lost(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(R1, " measure level : scale(low, high)"), clock=VirtualClock(), audit=log)
    m.update(level="high")
    return m, ruleset(R1, " measure level : scale(low, medium)"), {}, "(low, medium) does not have"


def _priority_of_a_removed_rule(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(f"{R1} {R2}"), clock=VirtualClock(), audit=log, priorities=["R1 > R2"])
    return m, ruleset(R1), {}, "priority R1 > R2: there is no rule 'R2'"


def _priority_given_for_a_missing_rule(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(f"{R1} {R2}"), clock=VirtualClock(), audit=log)
    return m, ruleset(R1), {"priorities": ["R2 > R1"]}, "there is no rule 'R2'"


def _task_of_a_lost_clause(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(f"{R1} unless a then G"), clock=VirtualClock(), audit=log)
    m.bind(R1Task())
    return m, ruleset(R1), {}, "rule R1 has no clause 1"


def _task_of_no_rule(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(R1), clock=VirtualClock(), audit=log)
    return m, ruleset(f"{R1} {R2}"), {"tasks": [R9Task()]}, "no rule named 'R9'"


def _unimplemented(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(R1), clock=VirtualClock(), audit=log)
    m.capability("F")(noop)
    m.capability("Help")(noop)
    m.start()  # checked the bindings: so is every reload
    return m, ruleset(f"{R1} R6 when E then Rec within 1 seconds"), {}, "no capability for response event Rec"


def _capability_of_no_response(log: Path) -> tuple[Manager, RuleSet, dict[str, Any], str]:
    m = Manager.from_text(spec(R1), clock=VirtualClock(), audit=log)
    return (
        m,
        ruleset(f"{R1} {R2}"),
        {"capabilities": {"Rec": noop}},
        "capability 'Rec': no rule's response names",
    )


Setup = Callable[[Path], tuple[Manager, RuleSet, dict[str, Any], str]]


def snapshot(m: Manager, log: Path) -> tuple[Any, ...]:
    return (
        dict(m.stats),
        [t.to_json() for t in sorted(m.tracker.active, key=lambda t: t.id)],
        m.values(),
        m.active_layers(),
        m.rules_hash,
        m.ruleset,
        m.context,
        m.layer_manager,
        m.implementations,
        m.priorities,
        dict(m.implementations.tasks),
        log.read_bytes(),
    )


@pytest.mark.parametrize(
    "setup",
    [
        _kind_changes,
        _literal_lost,
        _priority_of_a_removed_rule,
        _priority_given_for_a_missing_rule,
        _task_of_a_lost_clause,
        _task_of_no_rule,
        _unimplemented,
        _capability_of_no_response,
    ],
)
def test_a_reload_the_manager_cannot_take_is_refused_and_changes_nothing(
    tmp_path: Path, setup: Setup
) -> None:
    log = tmp_path / "audit.jsonl"
    m, new, kw, why = setup(log)
    m.update(a=False)
    m.event("E")  # something in force
    before = snapshot(m, log)
    with pytest.raises(ReloadError, match="reload refused, the rules in force stay") as e:
        m.reload(new, **kw)
    assert why in str(e.value) and e.value.hint
    assert snapshot(m, log) == before  # nothing changed, nothing recorded
    (d,) = m.event("E")  # still decided by the old rules
    assert d.rule == "R1" and m.rules_hash != new.digest


def test_what_would_be_refused_is_taken_once_the_reload_supplies_it() -> None:
    m = Manager.from_text(spec(f"{R1} {R2}"), clock=VirtualClock(), priorities=["R1 > R2"])
    m.capability("F")(noop)
    m.capability("Help")(noop)
    m.start()
    m.reload(ruleset(R1), priorities=[])  # the given priority goes with the rule
    new = ruleset(f"{R1} R6 when E then Rec within 1 seconds")
    ran: list[str] = []
    m.reload(new, capabilities={"Rec": lambda ob, d: ran.append("Rec")})
    m.event("E")
    assert ran == ["Rec"] and m.rules_hash == new.digest


def test_a_measure_without_a_value_may_change_its_type() -> None:
    m = Manager.from_text(spec(R1, " measure level : scale(low, high)"), clock=VirtualClock())
    m.reload(ruleset(R1, " measure level : numeric"))
    m.update(level=3.5)
    assert m.values()["level"] == 3.5


def test_a_reload_that_is_not_a_ruleset_is_a_type_error() -> None:
    m, _ = manager(R1)
    with pytest.raises(TypeError, match="RuleSet"):
        m.reload(spec(R1))  # type: ignore[arg-type]


# ---------------------------------------------------------------------------- audit


def test_the_reloaded_record_has_both_hashes_and_what_changed(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    old = ruleset(f"{R1} {R2}", " event Z")
    m = Manager(old, clock=VirtualClock(), audit=log)
    assert m.rules_hash == old.digest
    m.update(a=False)
    m.event("G")  # prohibition 1, of R2
    new = ruleset(f"{R1.replace('5 seconds', '6 seconds')} {R3}", " event Z")
    done = m.reload(new)
    assert (done.previous_hash, done.current_hash) == (old.digest, new.digest) and m.rules_hash == new.digest
    again_done = m.reload(ruleset(f"{R1.replace('5 seconds', '6 seconds')} {R3}", " event Z"))
    assert again_done.previous_hash == again_done.current_hash == new.digest
    assert (again_done.added, again_done.removed, again_done.changed, again_done.withdrawn) == (
        (),
        (),
        (),
        (),
    )
    m.close()
    first, second = kinds(log, "reloaded")
    assert first["previous_hash"] == old.digest and first["current_hash"] == new.digest
    assert second["previous_hash"] == second["current_hash"] == new.digest and second["withdrawn"] == []
    assert (first["added"], first["removed"], first["changed"], first["withdrawn"]) == (
        ["R3"],
        ["R2"],
        ["R1"],
        [1],
    )
    records = read_audit(log)
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    at = records.index(first)
    assert {r["rules"] for r in records[:at]} == {old.digest[:16]}
    assert {r["rules"] for r in records[at:]} == {new.digest[:16]}  # the reload's own records on


# ---------------------------------------------------------------------------- journal

NEW = RULES.replace(
    " R2 when Watch then not Rec within 10 minutes unless consent\n",
    " R3 when Watch then Help within 1 minutes\n",
)
KILLED_AFTER_A_RELOAD = """
from cosleec.runtime import RuleSet
m.update(consent=False); m.event("Watch"); m.event("Trigger")  # 1: not Rec (R2), 2: Act (R1)
done = m.reload(RuleSet.from_file({new!r}))
assert done.withdrawn == (1,) and done.removed == ("R2",), done
m.event("Watch")  # 3: Help (R3)
"""


def _killed_after_a_reload(tmp_path: Path) -> None:
    (tmp_path / "new.sleec").write_text(NEW)
    die_after(tmp_path, KILLED_AFTER_A_RELOAD.format(new=str(tmp_path / "new.sleec")))


def test_a_restart_with_the_new_rules_after_a_kill_keeps_what_the_reload_kept(tmp_path: Path) -> None:
    _killed_after_a_reload(tmp_path)
    (tmp_path / "rules.sleec").write_text(NEW)
    m = again(tmp_path, 101).start()
    assert m.request("Rec").permitted is True  # the withdrawn prohibition is not resurrected
    assert sorted((t.rule, t.event) for t in m.outstanding()) == [("R1", "Act"), ("R3", "Help")]
    m.close()
    records = read_audit(tmp_path / "audit.jsonl")
    (rec,) = [r for r in records if r["kind"] == "reloaded"]
    assert rec["current_hash"] == RuleSet.from_text(NEW).digest
    restored = [r for r in records if r["kind"] == "restored" and r["from"]][-1]
    assert restored["rules_changed"] is False and restored["obligations"] == 2 and restored["dropped"] == 0
    assert [r["status"] for r in records if r["kind"] == "obligation" and r["id"] == 1] == [
        "pending",
        "withdrawn",
    ]


def test_a_restart_with_the_old_rules_after_a_reload_is_a_restart_with_changed_rules(tmp_path: Path) -> None:
    _killed_after_a_reload(tmp_path)  # rules.sleec still holds the old rules
    m = again(tmp_path, 101).start()
    assert m.request("Rec").permitted is True  # R2 is back, but what it once imposed was withdrawn
    assert [(t.rule, t.event) for t in m.outstanding()] == [("R1", "Act")]
    m.close()
    records = read_audit(tmp_path / "audit.jsonl")
    restored = [r for r in records if r["kind"] == "restored" and r["from"]][-1]
    assert restored["rules_changed"] is True and restored["obligations"] == 1
    assert [r["what"] for r in records if r["kind"] == "dropped"] == [
        "obligation 3 (R3: Help within 60 s): the rules no longer have it"
    ]


def test_a_journal_reopened_after_a_reload_restores_what_the_reload_left_and_drops_nothing(
    tmp_path: Path,
) -> None:
    log, journal = tmp_path / "audit.jsonl", tmp_path / "state.db"
    old = ruleset(f"{R1} {R2} R6 when E then Rec within 30 seconds", " measure gone : boolean")
    new = ruleset(f"{R1} {R3}", " event Z")
    m = Manager(old, clock=VirtualClock(), audit=log, journal=journal)
    m.update(a=False, gone=True)
    m.event("G")  # 1: not Rec (R2), withdrawn by the reload
    m.event("E")  # 2: F (R1), kept; 3: Rec (R6), held while R2 forbids it, then withdrawn
    assert len(m._gate.held) == 1
    done = m.reload(new)
    assert done.withdrawn == (1, 3) and m._gate.held == {}
    kept = [t.to_json() for t in m.tracker.active]
    m.close()
    m = Manager(new, clock=VirtualClock(), audit=log, journal=journal)
    assert [t.to_json() for t in m.tracker.active] == kept
    assert m.values() == {"a": False, "b": None}
    m.close()
    restored = kinds(log, "restored")[-1]
    assert restored["rules_changed"] is False and restored["obligations"] == 1
    assert restored["dropped"] == 0  # the reload took the measure and the prohibition out of the journal
    assert restored["interrupted"] == 0 and kinds(log, "task-interrupted") == []  # and the withheld decision


# ---------------------------------------------------------------------------- threads


def test_reloads_while_other_threads_decide_and_judge_deadlines_keep_every_record(tmp_path: Path) -> None:
    log, journal = tmp_path / "audit.jsonl", tmp_path / "state.db"
    both, one = ruleset(f"{R1} {R2}"), ruleset(R1)
    clock = VirtualClock()
    m = Manager(both, clock=clock, audit=log, journal=journal, dispatch=False).start(timer=True)
    m.update(a=False)
    stop = threading.Event()
    errors: list[BaseException] = []

    def work() -> None:
        try:
            while not stop.is_set():
                m.event("E")
                m.event("G")
                m.permission("Rec")
                clock.advance(0.7)
                m.tick()
        except BaseException as e:  # pragma: no cover - reported below
            errors.append(e)

    workers = [threading.Thread(target=work) for _ in range(2)]
    for w in workers:
        w.start()
    try:
        for i in range(40):
            m.reload(one if i % 2 == 0 else both)
            time.sleep(0.002)
    finally:
        stop.set()
        for w in workers:
            w.join(10)
    assert errors == []
    pending, final_rules = sorted(t.id for t in m.tracker.active), m.ruleset
    assert all(t.rule in final_rules.by_name for t in m.tracker.active)
    m.close()
    records = read_audit(log)
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    final: dict[int, list[str]] = {}
    for r in records:
        if r["kind"] == "obligation" and not r["late"]:
            final.setdefault(r["id"], []).append(r["status"])
    assert all(s[0] == "pending" and len(s) <= 2 for s in final.values())
    withdrawn = {r["id"] for r in records if r["kind"] == "obligation" and r["status"] == "withdrawn"}
    rules_of = {r["id"]: r["rule"] for r in records if r["kind"] == "obligation"}
    assert withdrawn and {rules_of[i] for i in withdrawn} == {"R2"}
    assert withdrawn == {i for r in records if r["kind"] == "reloaded" for i in r["withdrawn"]}
    violated = sum(
        1 for r in records if r["kind"] == "obligation" and r["status"] == "violated" and not r["late"]
    )
    assert violated == m.stats["violations"]
    reopened = Manager(final_rules, clock=VirtualClock(clock.now()), journal=journal, dispatch=False)
    assert sorted(t.id for t in reopened.tracker.active) == pending  # the journal kept exactly that
    reopened.close()


# ---------------------------------------------------------------------------- a Manager that never reloaded

A = (
    "R1 when E then F within 5 seconds otherwise Help within 3 seconds "
    "R2 when G then not F within 4 seconds unless a "
    "R3 when E and b then not Rec within 6 seconds unless a then Rec within 2 seconds"
)
X = "R9 when Z then G within 2 seconds unless c"
XDEFS = " event Z measure c : boolean"
BEFORE = st.one_of(
    st.tuples(st.just("event"), st.sampled_from(["E", "F", "G", "Rec", "Help"])),
    st.tuples(st.just("update"), st.sampled_from(["a", "b"]), st.booleans()),
    st.tuples(st.just("advance"), st.sampled_from([0.5, 1.0, 2.0, 3.0, 4.0, 5.0])),
    st.tuples(st.just("request"), st.sampled_from(["F", "Rec"])),
)
AFTER_ADDED = st.one_of(
    BEFORE,
    st.tuples(st.just("event"), st.just("Z")),
    st.tuples(st.just("update"), st.just("c"), st.booleans()),
)


def play(m: Manager, clock: VirtualClock, op: tuple[Any, ...]) -> Any:
    if op[0] == "event":
        return [d.to_json() for d in m.event(op[1])]
    if op[0] == "update":
        return m.update({op[1]: op[2]})
    if op[0] == "advance":
        clock.advance(op[1])
        return [d.to_json() for d in m.tick()]
    return m.permission(op[1])


def observed(m: Manager) -> tuple[Any, ...]:
    return (
        dict(m.stats),
        [t.to_json() for t in sorted(m.tracker.active, key=lambda t: t.id)],
        m.active_layers(),
        sorted(m._gate.held),
    )


@settings(max_examples=120, deadline=None)
@given(
    direction=st.sampled_from(["same", "added", "removed"]),
    before=st.lists(BEFORE, max_size=12),
    after=st.data(),
)
def test_a_reload_is_invisible_to_what_the_rules_both_have_in_common(
    direction: str, before: list[tuple[Any, ...]], after: st.DataObject
) -> None:
    # the oracle: a Manager started with the rules the other reloads to, fed the same inputs;
    # "added": X's trigger never occurs before the reload, "removed": never at all
    start, end = {
        "same": ((A, ""), (A, "")),
        "added": ((A, ""), (f"{A} {X}", XDEFS)),
        "removed": ((f"{A} {X}", XDEFS), (A, "")),
    }[direction]
    c1, c2 = VirtualClock(), VirtualClock()
    m1 = Manager.from_text(spec(*start), clock=c1, dispatch=False)
    m2 = Manager.from_text(spec(*end), clock=c2, dispatch=False)
    for op in before:
        assert play(m1, c1, op) == play(m2, c2, op)
    kept = observed(m1)
    done = m1.reload(ruleset(*end))
    assert m1.rules_hash == m2.rules_hash
    if direction == "same":
        assert done.withdrawn == () and observed(m1) == kept  # a no-op on what is in force
    assert observed(m1) == observed(m2)
    ops = after.draw(st.lists(AFTER_ADDED if direction == "added" else BEFORE, max_size=12))
    for op in ops:
        assert play(m1, c1, op) == play(m2, c2, op)
    assert observed(m1) == observed(m2) and m1.values() == m2.values()
