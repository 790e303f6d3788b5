"""Restore alone: a core started on a real journal takes back what was committed, or refuses."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest

from cosleec.records import Kind
from cosleec.runtime.clock import MonotonicClock, boot
from cosleec.runtime.errors import ConfigurationError
from cosleec.runtime.journal import Journal, JournalError, Saved
from cosleec.runtime.restore import Restore, open_journal

from .build import Parts, journaled, parts

RULES = "R1 when E then F within 5 seconds and not Rec within 10 seconds"


def first_life(path: Path, rules: str = RULES, **kw: Any) -> Parts:
    """A core on a new journal at ``path``: a value, then E at 3 s (its decision never run); closed."""
    p = parts(rules, **kw)
    journal = journaled(p, path)
    assert p.kinds() == ["restored"] and p.heard[0].data == {
        "from": None,
        "lineage": "test",
        "rules_changed": False,
    }
    p.update(a=True)
    p.clock.set(3.0)
    p.fire("E")
    journal.close()
    return p


def test_a_new_journal_restores_nothing_and_says_so(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    (restored,) = p.of(Kind.RESTORED)
    assert restored == {"from": None, "lineage": "test", "rules_changed": False}


def test_what_was_committed_is_taken_back(tmp_path: Path) -> None:
    before = first_life(tmp_path / "journal.db")
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    assert p.clock.now() == 3.0  # virtual time goes on from the last commit
    assert p.core.context.values == {"a": True}
    assert [(t.id, t.event, t.lo, t.hi, t.status) for t in p.core.tracker.active] == [
        (1, "F", 3.0, 8.0, "pending"),
        (2, "Rec", 3.0, 13.0, "pending"),
    ]
    assert p.core.steps.counters == {**before.core.steps.counters, "record": 8}
    assert p.core.tracker.next_id == 3
    assert [ev.kind for ev in p.heard] == [Kind.TASK_INTERRUPTED, Kind.RESTORED]
    assert [ev.seq for ev in p.heard] == [6, 7]  # record numbers go on
    assert p.heard[0].data == {
        "decision": 1,
        "rule": "R1",
        "event": "E",
        "reason": "the Manager stopped before it was known to have run",
    }
    assert p.heard[1].data == {
        "from": "test",
        "lineage": "test",
        "rules_changed": False,
        "context": ["a"],
        "obligations": 2,
        "dropped": 0,
        "interrupted": 1,
        "shift": 0.0,
    }


def test_a_decision_perhaps_never_run_is_not_run_again(tmp_path: Path) -> None:
    first_life(tmp_path / "journal.db")
    p = parts(RULES)
    journal = journaled(p, tmp_path / "journal.db")
    journal.close()
    again = parts(RULES)
    journaled(again, tmp_path / "journal.db")
    assert again.of(Kind.TASK_INTERRUPTED) == []  # the first restart took it out of the outbox


def test_what_the_rules_no_longer_have_is_dropped(tmp_path: Path) -> None:
    first_life(tmp_path / "journal.db")
    p = parts("R1 when E then F within 5 seconds", base="def_start event E event F")
    journaled(p, tmp_path / "journal.db")
    assert [d["what"] for d in p.of(Kind.DROPPED)] == [
        "measure a: the rules no longer declare it",
        "obligation 2 (R1: not Rec within 10 s): the rules no longer have it",
    ]
    (restored,) = p.of(Kind.RESTORED)
    assert (restored["rules_changed"], restored["obligations"], restored["dropped"]) == (True, 1, 2)
    assert [t.id for t in p.core.tracker.active] == [1]


def test_a_held_decision_is_held_again(tmp_path: Path) -> None:
    path = tmp_path / "journal.db"
    rules = "R1 when E then not Rec within 10 seconds R2 when G then Rec within 60 seconds"
    p = parts(rules)
    journal = journaled(p, path)
    p.fire("E")
    p.clock.set(1.0)
    with p.core.steps.step() as step:
        assert p.gate.ready(p.trigger("G", step), step.now, step) == []
    journal.close()
    again = parts(rules)
    journaled(again, path)
    assert list(again.gate.held) == [2]
    assert [d["decision"] for d in again.of(Kind.TASK_INTERRUPTED)] == [1]  # R1's, not the held one
    again.clock.set(12.0)
    with again.core.steps.step() as step:
        (part,) = again.gate.ready(again.enforcer.advance(step.now, step), step.now, step)
    assert [o.event for o in part.decision.obligations] == ["Rec"]


def test_a_decision_perhaps_never_published_is_published_again(tmp_path: Path) -> None:
    first = parts(RULES)
    first.core.dispatch = False
    journal = journaled(first, tmp_path / "journal.db")
    first.fire("E")
    journal.close()
    p = parts(RULES)
    p.core.dispatch = False
    journaled(p, tmp_path / "journal.db")
    (record,) = p.gate.undelivered
    assert (record["id"], record["rule"]) == (1, "R1")
    assert p.of(Kind.TASK_INTERRUPTED) == []


def test_a_journal_written_on_another_kind_of_clock_is_refused(tmp_path: Path) -> None:
    first_life(tmp_path / "journal.db")
    p = parts(RULES)
    p.core.steps.clock = MonotonicClock()
    with pytest.raises(
        JournalError, match="written on a VirtualClock and this Manager runs on a MonotonicClock"
    ):
        journaled(p, tmp_path / "journal.db")


def test_resetting_a_journal_that_lost_nothing_is_refused(tmp_path: Path) -> None:
    first_life(tmp_path / "journal.db")
    p = parts(RULES)
    journal = Journal(tmp_path / "journal.db")
    p.core.steps.journal = journal
    with pytest.raises(ConfigurationError, match="there is nothing to reset"):
        open_journal(p.core, p.gate, p.enforcer, reset=True)
    journal.close()


# ---------------------------------------------------------------------------- a monotonic clock after a reboot


def saved(**kw: Any) -> Saved:
    fields: dict[str, Any] = {
        "rules": "",
        "run": "before",
        "lineage": "first",
        "counters": {"decision": 5, "seq": 9, "record": 40, "obligation": 12},
        "clock": 100.0,
        "wall": time.time() - 30.0,
        "context": {},
        "obligations": [],
        "outbox": [],
        "clock_kind": "MonotonicClock",
        "boot": "another boot",
    }
    return Saved(**{**fields, **kw})


def test_after_a_reboot_obligations_fall_due_sooner_and_prohibitions_hold_on() -> None:
    before = parts(RULES)
    before.fire("E")  # at 0: F until 5, not Rec until 10
    records = [t.to_json() for t in before.core.tracker.active]
    p = parts(RULES)
    p.core.steps.clock = MonotonicClock()
    now = p.core.steps.clock.now()
    with p.core.steps.step() as step:
        restore = Restore(p.core, p.gate, p.enforcer, saved(clock=5.0, obligations=records), step)
        restore.run()
    down = 30.0  # the wall clock says it was down 30 s
    assert restore.hold == pytest.approx(now - 5.0, abs=1.0)
    assert restore.shift == pytest.approx(now - 5.0 - down, abs=1.0)
    f, rec = sorted(p.core.tracker.active, key=lambda t: t.id)
    assert f.hi == pytest.approx(5.0 + restore.shift) and rec.hi == pytest.approx(10.0 + restore.hold)
    assert p.core.steps.counters == {"decision": 5, "seq": 9, "record": p.core.steps.counters["record"]}
    assert p.core.tracker.next_id == 12


def test_the_same_boot_on_a_monotonic_clock_shifts_nothing() -> None:
    p = parts(RULES)
    p.core.steps.clock = MonotonicClock()
    with p.core.steps.step() as step:
        restore = Restore(p.core, p.gate, p.enforcer, saved(clock=1.0, boot=boot()), step)
        restore.run()
    assert (restore.shift, restore.hold) == (0.0, 0.0)


def test_ids_never_go_back_even_when_the_journal_counted_less() -> None:
    p = parts(RULES)
    for _ in range(3):
        p.fire("E")
    with p.core.steps.step() as step:
        Restore(
            p.core, p.gate, p.enforcer, saved(counters={"decision": 2}, clock_kind="VirtualClock"), step
        ).run()
    assert p.core.steps.counters["decision"] == 4


def test_obligation_ids_go_on_even_when_nothing_was_pending() -> None:
    p = parts(RULES)
    with p.core.steps.step() as step:
        Restore(p.core, p.gate, p.enforcer, saved(clock_kind="VirtualClock", clock=0.0), step).run()
    assert p.core.tracker.next_id == 12  # the journal's counter, though it restored no obligation


def test_a_saved_value_the_rules_no_longer_accept_is_dropped() -> None:
    p = parts(RULES)
    with p.core.steps.step() as step:
        state = saved(context={"a": (3, 0.0), "n": (2.5, 1.0)}, clock_kind="VirtualClock", clock=0.0)
        Restore(p.core, p.gate, p.enforcer, state, step).run()
    assert p.core.context.values == {"n": 2.5}
    (dropped,) = p.of(Kind.DROPPED)
    assert dropped["what"].startswith("measure a: a is boolean; got int 3")
