"""Conflicts at runtime: E owed and forbidden at once. The Manager records the conflict,
resolves it by priority or lets the prohibition win, and never dispatches what ``request``
refuses."""

from __future__ import annotations

import logging
from typing import Any

import pytest

from cosleec.runtime import Manager, VirtualClock

CURTAINS = """def_start
  event CurtainOpenRequest
  event OpenCurtains
  event ApologiseToUser
  measure night: boolean
def_end
rule_start
R1 when CurtainOpenRequest then OpenCurtains within 1 minutes otherwise ApologiseToUser
R2 when CurtainOpenRequest and night then not OpenCurtains within {window}
rule_end
"""


def build(window: str = "10 minutes", **options: Any) -> tuple[Manager, VirtualClock, list[Any], list[float]]:
    """The curtain rules with a capability that opens the curtains (and reports it)."""
    clock = options.pop("clock", None) or VirtualClock(0.0)
    m = Manager.from_text(CURTAINS.format(window=window), clock=clock, **options)
    records: list[Any] = []
    opened: list[float] = []
    m.subscribe(records.append)

    @m.capability("OpenCurtains")
    def open_curtains(ob: Any, d: Any) -> None:
        opened.append(clock.now())
        m.event("OpenCurtains")

    @m.capability("ApologiseToUser")
    def apologise(ob: Any, d: Any) -> None:
        m.event("ApologiseToUser")

    m.start()
    return m, clock, records, opened


def kinds(records: list[Any], kind: str) -> list[dict[str, Any]]:
    return [r.data for r in records if r.kind == kind]


def final(records: list[Any]) -> dict[str, tuple[str, Any]]:
    """Each obligation's last state, by its item key."""
    out: dict[str, tuple[str, Any]] = {}
    for d in kinds(records, "obligation"):
        out[d["obligation"]["item"]] = (d["status"], d["at"])
    return out


def test_the_curtain_conflict_is_recorded_and_the_prohibition_wins() -> None:
    m, _clock, records, opened = build()
    m.update(night=True)
    m.event("CurtainOpenRequest")
    (c,) = kinds(records, "conflict")
    assert c["between"] == ["R1", "R2"] and c["clauses"] == [0, 0] and c["event"] == "OpenCurtains"
    assert c["resolution"] == "prohibition-wins" and c["winner"] == "R2"
    assert "R2 forbids OpenCurtains" in c["explanation"]
    assert opened == []  # the action is not dispatched ...
    assert m.request("OpenCurtains").permitted is False  # ... and request agrees
    states = final(records)
    assert states["R1:0"] == ("blocked", 0.0)  # violated by conflict, at once
    assert states["R1:0/o:0"] == ("fulfilled", 0.0)  # its otherwise ran: the robot apologised
    assert m.stats["conflicts"] == 1
    m.close()


def test_by_day_there_is_no_conflict_and_the_curtains_open() -> None:
    m, _clock, records, opened = build()
    m.update(night=False)
    m.event("CurtainOpenRequest")
    assert kinds(records, "conflict") == [] and opened == [0.0]
    assert final(records)["R1:0"] == ("fulfilled", 0.0)
    m.close()


def test_an_action_forbidden_for_part_of_its_window_waits_until_it_is_allowed() -> None:
    m, clock, records, opened = build("30 seconds")
    m.update(night=True)
    m.event("CurtainOpenRequest")
    assert kinds(records, "conflict") == [] and opened == []
    assert kinds(records, "held")[0]["by"] == ["R2"]
    clock.set(30.0)
    m.tick()
    assert opened == [] and m.request("OpenCurtains").permitted is False  # [t, t+30] is closed at both ends
    clock.set(30.5)
    m.tick()
    assert opened == [30.5]  # released as soon as the prohibition is over
    assert kinds(records, "dispatch")[0]["decision"]["rule"] == "R1"
    assert final(records)["R1:0"] == ("fulfilled", 30.5)
    assert final(records)["R2:0"] == ("respected", 30.0)
    m.close()


def test_cancellation_based_priority_cancels_the_lower_rule_at_once() -> None:
    m, _clock, records, opened = build(priorities=["R1 > R2"])
    m.update(night=True)
    m.event("CurtainOpenRequest")
    assert opened == [0.0] and m.request("OpenCurtains").permitted is True
    (c,) = kinds(records, "cancelled")
    assert c["rule"] == "R2" and c["by"] == "R1" and c["priority"] == "cancel"
    assert final(records)["R2:0"] == ("cancelled", 0.0)
    (conflict,) = kinds(records, "conflict")  # the conflict the cancellation settled is recorded
    assert conflict["resolution"] == "cancel" and conflict["winner"] == "R1"
    assert conflict["between"] == ["R1", "R2"]
    m.close()


def test_conflict_aware_priority_keeps_the_lower_rule_until_the_higher_one_needs_the_action() -> None:
    m, clock, records, opened = build(priorities=["R1 > R2"], priority_semantics="conflict-aware")
    m.update(night=True)
    m.event("CurtainOpenRequest")
    (c,) = kinds(records, "conflict")
    assert c["resolution"] == "conflict-aware" and c["winner"] == "R1"
    assert opened == [] and m.request("OpenCurtains").permitted is False
    clock.set(59.0)
    m.tick()
    assert opened == []
    clock.set(60.0)  # R1's deadline: R2 is cancelled, the curtains open, R1 is met in time
    m.tick()
    assert opened == [60.0]
    assert final(records)["R2:0"] == ("cancelled", 60.0)
    assert final(records)["R1:0"] == ("fulfilled", 60.0)
    m.close()


def test_a_lead_gives_the_robot_time_before_the_deadline() -> None:
    m, clock, _records, opened = build(
        priorities=["R1 > R2"], priority_semantics="conflict-aware", priority_lead=5.0
    )
    m.update(night=True)
    m.event("CurtainOpenRequest")
    clock.set(55.0)
    m.tick()
    assert opened == [55.0]
    m.close()


def test_the_higher_prohibition_cancels_the_lower_obligation() -> None:
    m, clock, records, opened = build(priorities=["R2 > R1"])
    m.update(night=True)
    m.event("CurtainOpenRequest")
    clock.set(120.0)
    m.tick()
    assert opened == [] and final(records)["R1:0"] == ("cancelled", 0.0)
    assert m.stats["violations"] == 0  # a cancelled obligation is not violated, its otherwise never runs
    m.close()


def test_start_warns_about_rules_that_can_conflict_unless_a_priority_settles_them(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        m, *_ = build()
    assert "R1:0 obliges OpenCurtains, R2:0 forbids it" in caplog.text
    assert [c.rules for c in m.possible_conflicts] == [("R1", "R2")]
    m.close()
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        m, *_ = build(priorities=["R2 > R1"])
    assert "conflict" not in caplog.text and m.possible_conflicts == []
    m.close()


@pytest.mark.parametrize(
    ("priorities", "message"),
    [
        (["R1 > R3"], "no rule 'R3'"),
        (["R1 > R1"], "above itself"),
        (["R1 > R2", "R2 > R1"], "cycle"),
    ],
)
def test_bad_priorities_are_configuration_errors(priorities: list[str], message: str) -> None:
    with pytest.raises(Exception, match=message):
        build(priorities=priorities)


def test_an_interval_obligation_is_enacted_when_its_window_opens_not_before() -> None:
    clock = VirtualClock(0.0)
    m = Manager.from_text(
        "def_start event T event E def_end rule_start R1 when T then E within [5 seconds, 10 seconds] rule_end",
        clock=clock,
    )
    ran: list[float] = []

    @m.capability("E")
    def do(ob: Any, d: Any) -> None:
        ran.append(clock.now())
        m.event("E")

    records: list[Any] = []
    m.subscribe(records.append)
    m.start()
    m.event("T")
    assert ran == [] and kinds(records, "held")[0]["opens"] == 5.0  # an E now would not count
    clock.set(5.0)
    m.tick()
    assert ran == [5.0] and final(records)["R1:0"] == ("fulfilled", 5.0)
    m.close()


def test_a_held_action_survives_a_restart_and_runs_once_allowed(tmp_path: Any) -> None:
    journal = tmp_path / "state.db"
    clock = VirtualClock(0.0)
    m, _, records, opened = build("30 seconds", journal=journal, clock=clock)
    m.update(night=True)
    m.event("CurtainOpenRequest")
    assert opened == [] and kinds(records, "held")
    m.close()  # the process ends while the action is held
    clock2 = VirtualClock(5.0)
    m2, _, records2, opened2 = build("30 seconds", journal=journal, clock=clock2)
    assert kinds(records2, "task-interrupted") == []  # held, not lost: it waits again
    assert m2.request("OpenCurtains").permitted is False and opened2 == []
    clock2.set(31.0)
    m2.tick()
    assert opened2 == [31.0] and m2.request("OpenCurtains").permitted is True
    assert final(records2)["R1:0"] == ("fulfilled", 31.0)
    m2.close()


def test_an_undetermined_higher_rule_cancels_nothing() -> None:
    # R2 > R1, but R2's condition reads a measure with no value: its fail-closed prohibition
    # holds (the prohibition wins), yet no activation of R2 exists to cancel R1 by priority
    m, _clock, records, opened = build(priorities=["R2 > R1"])
    m.event("CurtainOpenRequest")  # night unknown
    assert kinds(records, "cancelled") == []
    assert final(records)["R1:0"][0] == "blocked" and opened == []
    m.close()


def test_start_records_the_options_the_run_judges_by(tmp_path: Any) -> None:
    m, _clock, records, _ = build(
        priorities=["R1 > R2"], priority_semantics="conflict-aware", priority_lead=2.0
    )
    (o,) = kinds(records, "options")
    assert o == {
        "semantics": "last-wins",
        "unknown": "undetermined",
        "untimed": "none",
        "priorities": [["R1", "R2"]],
        "priority_semantics": "conflict-aware",
        "priority_lead": 2.0,
    }
    m.close()


class Drifting(VirtualClock):
    """A clock that moves a millisecond every time it is read (a busy real clock)."""

    def now(self) -> float:
        t = super().now()
        self.set(t + 0.001)
        return t


def test_an_occurrence_is_recorded_at_the_time_it_was_judged_at() -> None:
    clock = Drifting(0.0)
    m = Manager.from_text(
        "def_start event T event E def_end rule_start R1 when T then E within 1 seconds rule_end",
        clock=clock,
        dispatch=False,
    )
    records: list[Any] = []
    m.subscribe(records.append)
    m.start()
    m.event("T")
    m.event("E")
    (ob,) = [d for d in kinds(records, "obligation") if d["status"] == "fulfilled"]
    (e,) = [r for r in records if r.kind == "event" and r.data["event"] == "E"]
    assert e.time == ob["at"]  # a reader re-judging the log sees the same instant
    m.close()


@pytest.mark.parametrize("bad", [[("R1",)], [42], 7, [("R1", 2)]])
def test_malformed_priorities_are_configuration_errors(bad: Any) -> None:
    from cosleec.runtime import ConfigurationError

    with pytest.raises(ConfigurationError):
        build(priorities=bad)


def test_a_priority_declared_before_a_restart_acts_on_what_the_journal_restores(tmp_path: Any) -> None:
    rules = (
        "def_start event T0 event T1 event A event B def_end rule_start "
        "R1 when T0 then A within 50 seconds R2 when T1 then B within 50 seconds rule_end"
    )
    journal = tmp_path / "state.db"
    clock = VirtualClock(0.0)
    m = Manager.from_text(rules, clock=clock, dispatch=False, journal=journal)
    m.start()
    m.event("T0")
    clock.set(1.0)
    m.event("T1")
    m.close()  # both activations in force; R1 > R2 is declared for the next run
    m2 = Manager.from_text(
        rules, clock=VirtualClock(3.0), dispatch=False, journal=journal, priorities=["R1 > R2"]
    )
    m2.start()
    assert m2.stats["cancelled"] == 1  # R2's activation, cancelled as the journal was restored
    assert [t.rule for t in m2.outstanding()] == ["R1"]
    m2.close()


def test_conflict_aware_cuts_are_not_recomputed_while_nothing_in_force_changes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import cosleec.runtime.enforcer as manager_module

    rules = (
        "def_start event T event G event E event Q def_end rule_start "
        "R1 when T then E within 1000 seconds R2 when G then not E within 2000 seconds rule_end"
    )
    m = Manager.from_text(
        rules,
        clock=VirtualClock(0.0),
        dispatch=False,
        priorities=["R1 > R2"],
        priority_semantics="conflict-aware",
    )
    m.start()
    m.event("G")
    for _ in range(50):
        m.event("T")
    calls = []
    real = manager_module.forced
    monkeypatch.setattr(manager_module, "forced", lambda *a: calls.append(1) or real(*a))
    for _ in range(20):
        assert m.request("Q").permitted is True  # a step that changes nothing in force
    assert len(calls) <= 1  # not a scan of everything in force per step
    assert m.request("E").permitted is False and len(m._gate.held) == 50  # still held, and still right
    m.close()
