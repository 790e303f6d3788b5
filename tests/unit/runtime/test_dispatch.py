"""Dispatch: each action of a decision runs on its own, and nothing starts once forbidden.

Issue 28, findings 2 and 3: an allowed action of a decision must run when one of its
siblings is held, and a prohibition that takes force between a decision and the start of
its implementation must stop the action it forbids (``request`` and dispatch agree at
the instant of dispatch: the ``checked`` field of ``task-done`` names it).
"""

from __future__ import annotations

from typing import Any

from cosleec.runtime import AuditLog, Manager, VirtualClock

SPLIT = """def_start
  event X event Y event A event B
def_end
rule_start
R1 when X then A within 60 seconds and B within 5 seconds
R2 when Y then not A within 30 seconds
rule_end
"""

SNAP = """def_start
  event Motion event Visitor event Snap
def_end
rule_start
R1 when Motion then Snap within {within}
R2 when Visitor then not Snap within 30 seconds
rule_end
"""


def kinds(records: list[Any], kind: str) -> list[dict[str, Any]]:
    return [r.data for r in records if r.kind == kind]


def final(records: list[Any]) -> dict[str, tuple[str, Any]]:
    """Each obligation's last state, by its item key."""
    out: dict[str, tuple[str, Any]] = {}
    for d in kinds(records, "obligation"):
        out[d["obligation"]["item"]] = (d["status"], d["at"])
    return out


def split_manager(**options: Any) -> tuple[Manager, VirtualClock, list[Any], list[tuple[str, float]]]:
    clock = options.pop("clock", None) or VirtualClock(0.0)
    m = Manager.from_text(SPLIT, clock=clock, **options)
    ran: list[tuple[str, float]] = []
    records: list[Any] = []
    m.subscribe(records.append)
    for event in ("A", "B"):

        def act(ob: Any, d: Any, event: str = event) -> None:
            ran.append((event, clock.now()))
            m.event(event)

        m.capability(event)(act)
    m.start()
    return m, clock, records, ran


def test_an_allowed_action_runs_while_its_sibling_is_held() -> None:
    m, clock, records, ran = split_manager()
    m.event("Y")  # A is forbidden for 30 s
    m.event("X")  # A within 60 s (held), B within 5 s (allowed: runs now)
    assert ran == [("B", 0.0)] and m.request("B").permitted is True and m.request("A").permitted is False
    (held,) = kinds(records, "held")
    assert held["events"] == ["A"] and held["by"] == ["R2"]
    (part,) = kinds(records, "dispatch")
    assert [o["event"] for o in part["decision"]["obligations"]] == ["B"]
    decision = next(d for d in kinds(records, "decision") if d["rule"] == "R1")
    assert decision["dispatch"] == "held"  # a Manager node hands on the parts, not the whole
    clock.set(10.0)
    m.tick()
    assert final(records)["R1:1"] == ("fulfilled", 0.0)  # B, not violated at 5 s
    clock.set(30.5)
    m.tick()
    assert ran == [("B", 0.0), ("A", 30.5)]  # the held action, once allowed; B not again
    assert [o["event"] for o in kinds(records, "dispatch")[1]["decision"]["obligations"]] == ["A"]
    assert final(records)["R1:0"] == ("fulfilled", 30.5)
    done = [d for d in kinds(records, "task-done") if d["decision"] == decision["id"]]
    assert [d["event"] for d in done] == ["B", "A"]  # an outcome per action
    m.close()


def test_a_decision_with_nothing_forbidden_runs_whole_as_decided() -> None:
    m, _clock, records, ran = split_manager()
    m.event("X")
    assert sorted(ran) == [("A", 0.0), ("B", 0.0)]
    assert kinds(records, "held") == [] and kinds(records, "dispatch") == []
    assert "dispatch" not in kinds(records, "decision")[0]
    m.close()


def test_a_held_action_of_a_split_decision_survives_a_restart_and_the_rest_does_not_run_again(
    tmp_path: Any,
) -> None:
    journal = tmp_path / "state.db"
    m, _clock, _records, ran = split_manager(journal=journal)
    m.event("Y")
    m.event("X")
    assert ran == [("B", 0.0)]
    m.close()
    clock2 = VirtualClock(5.0)
    m2, _, records2, ran2 = split_manager(journal=journal, clock=clock2)
    assert kinds(records2, "task-interrupted") == []  # held, not lost
    clock2.set(31.0)
    m2.tick()
    assert ran2 == [("A", 31.0)]  # A once allowed; B, which ran before the restart, not again
    m2.close()


def snap_manager(within: str = "10 seconds") -> tuple[Manager, VirtualClock, list[Any], list[float]]:
    clock = VirtualClock(0.0)
    m = Manager.from_text(SNAP.format(within=within), clock=clock)
    records: list[Any] = []
    snapped: list[float] = []
    asked: list[bool] = []

    @m.capability("Snap")
    def snap(ob: Any, d: Any) -> None:
        asked.append(m.request("Snap").permitted)
        snapped.append(clock.now())
        m.event("Snap")

    def visitor_between(ev: Any) -> None:  # a Visitor occurs between the decision and its dispatch
        if ev.kind == "decision" and ev.data["rule"] == "R1" and not ev.data.get("violated"):
            m.event("Visitor")

    m.subscribe(records.append)
    m.subscribe(visitor_between)
    m.start()
    return m, clock, records, snapped


def test_a_prohibition_that_takes_force_before_the_start_stops_the_action() -> None:
    m, clock, records, snapped = snap_manager("60 seconds")
    m.event("Motion")
    assert snapped == [] and m.request("Snap").permitted is False  # dispatch and request agree
    (refused,) = [r for r in kinds(records, "refused") if r.get("source", "").startswith("dispatch")]
    assert refused["event"] == "Snap" and refused["by"] == ["R2"]
    assert kinds(records, "held")[0]["events"] == ["Snap"]
    clock.set(30.0)
    m.tick()
    assert snapped == []  # [t, t + 30] is closed at both ends
    clock.set(30.5)
    m.tick()
    assert snapped == [30.5] and final(records)["R1:0"] == ("fulfilled", 30.5)  # once allowed
    m.close()


def test_an_action_whose_window_a_later_prohibition_covers_is_withheld_not_run() -> None:
    m, clock, records, snapped = snap_manager("10 seconds")
    m.event("Motion")  # the Visitor's prohibition covers all of [0, 10]: a conflict it wins
    assert snapped == [] and m.request("Snap").permitted is False
    assert kinds(records, "conflict")[0]["winner"] == "R2"
    assert final(records)["R1:0"][0] == "blocked"
    assert kinds(records, "withheld")[0]["rule"] == "R1"
    clock.set(10.5)
    m.tick()
    assert snapped == []
    m.close()


def test_task_done_names_the_record_before_the_dispatch_was_admitted(tmp_path: Any) -> None:
    log = tmp_path / "audit.jsonl"
    clock = VirtualClock(0.0)
    m = Manager.from_text(SNAP.format(within="10 seconds"), clock=clock, audit=AuditLog(log))
    m.capability("Snap")(lambda ob, d: m.event("Snap"))
    m.start()
    m.event("Motion")
    m.close()
    from cosleec.runtime import read_audit

    records = read_audit(log)
    done = next(r for r in records if r["kind"] == "task-done")
    decision = next(r for r in records if r["kind"] == "decision")
    # admitted after the decision's step, before the Snap the capability reported
    snap = next(r for r in records if r["kind"] == "event" and r["event"] == "Snap")
    assert decision["seq"] <= done["checked"] < snap["seq"]


def test_a_manager_node_publishes_again_only_the_part_it_may_never_have_published(tmp_path: Any) -> None:
    """dispatch=False (the ROS Manager node): a part handed on but not known to be published
    before the process ended is published again after a restart -- only its own actions; the
    held one waits to be allowed, and a part known to be published is not published again."""
    journal = tmp_path / "state.db"

    def node_manager(now: float) -> tuple[Manager, list[Any]]:
        m = Manager.from_text(SPLIT, clock=VirtualClock(now), journal=journal, dispatch=False)
        records: list[Any] = []
        m.subscribe(records.append)
        return m.start(), records

    m, records = node_manager(0.0)
    m.event("Y")
    m.event("X")
    (part,) = kinds(records, "dispatch")  # B, handed on; the node died before publishing it
    decision = part["decision"]["id"]
    m.close()
    m2, _ = node_manager(1.0)
    again = [d for d in m2.undelivered if d["rule"] == "R1"]  # (R2's decision was never published either)
    assert [[o["event"] for o in d["obligations"]] for d in again] == [["B"]]
    assert m2.request("A").permitted is False
    m2.delivered(decision)  # published this time
    m2.tick()
    m2.close()
    m3, records3 = node_manager(31.0)
    assert [d for d in m3.undelivered if d["rule"] == "R1"] == []  # B is not published a third time
    m3.tick()
    (rest,) = kinds(records3, "dispatch")  # A, once allowed; the node dies before publishing it
    assert [o["event"] for o in rest["decision"]["obligations"]] == ["A"]
    m3.close()
    m4, records4 = node_manager(32.0)
    again = [d for d in m4.undelivered if d["rule"] == "R1"]
    assert [[o["event"] for o in d["obligations"]] for d in again] == [["A"]]  # published again, A only
    m4.tick()
    assert kinds(records4, "dispatch") == [] and kinds(records4, "task-interrupted") == []
    m4.delivered(decision)
    m4.tick()
    m4.close()
    m5, _ = node_manager(33.0)
    assert [d for d in m5.undelivered if d["rule"] == "R1"] == []  # known published: never again
    m5.close()
