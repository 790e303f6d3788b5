"""Steps alone: one lock, records numbered in order, each step committed with its records,
broken for good by a failed write, and delivered to observers in order, once."""

from __future__ import annotations

import errno
import json
import threading
from pathlib import Path
from typing import Any

import pytest

from cosleec.records import Kind, RuntimeEvent
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import VirtualClock
from cosleec.runtime.errors import ConfigurationError
from cosleec.runtime.journal import Change, Journal, JournalError
from cosleec.runtime.steps import Step, Steps


def steps(**kw: Any) -> tuple[Steps, VirtualClock, list[RuntimeEvent]]:
    clock = VirtualClock()
    s = Steps(clock, run_id="run1", **kw)
    heard: list[RuntimeEvent] = []
    s.subscribe(heard.append)
    return s, clock, heard


def lines(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def started(path: Path) -> Journal:
    journal = Journal(path)
    journal.start()
    return journal


META: dict[str, Any] = {"rules": "digest", "run": "run1", "counters": {}}


class Interrupted(BaseException):
    """What a Ctrl-C or a killed thread looks like to a commit."""


# ---------------------------------------------------------------------------- numbering


def test_records_are_numbered_in_order_across_steps_and_stamped_with_the_step_time() -> None:
    s, clock, heard = steps()
    with s.step() as one:
        one.emit(Kind.OCCURRENCE, {"event": "E"})
        one.emit(Kind.OCCURRENCE, {"event": "F"}, at=0.5)
    clock.advance(2.0)
    with s.step() as two:
        assert two.now == 2.0
        clock.advance(1.0)  # the step's time is read once, when it began
        two.emit(Kind.OCCURRENCE, {"event": "G"})
    assert [(ev.seq, ev.time, ev.data["event"]) for ev in heard] == [
        (1, 0.0, "E"),
        (2, 0.5, "F"),
        (3, 2.0, "G"),
    ]
    assert s.last_record == 3


def test_counters_are_used_up_one_at_a_time() -> None:
    s, _, _ = steps()
    assert [s.count("decision"), s.count("decision"), s.count("seq")] == [1, 2, 1]
    assert s.counters == {"decision": 3, "seq": 2, "record": 1}
    assert s.last_record == 0


def test_a_step_alone_numbers_its_records_from_one() -> None:
    step = Step(4.0)
    step.emit(Kind.OCCURRENCE, {})
    step.emit(Kind.OCCURRENCE, {})
    assert [(ev.seq, ev.time) for ev in step.events] == [(1, 4.0), (2, 4.0)]
    assert not step.changed()
    step.change.context["a"] = (True, 4.0)
    assert step.changed()


def test_recording_is_true_only_while_someone_reads_the_records(tmp_path: Path) -> None:
    clock = VirtualClock()
    s = Steps(clock, run_id="r")
    assert not s.recording
    stop = s.subscribe(lambda ev: None)
    assert s.recording
    stop()
    stop()  # harmless once gone
    assert not s.recording and s.observers == []
    s.keep(AuditLog(tmp_path / "audit.jsonl"))
    assert s.recording


def test_numbers_go_on_from_where_the_audit_log_ends(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    first = AuditLog(path)
    s = Steps(VirtualClock(), run_id="r", audit=first)
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "E"})
        step.emit(Kind.OCCURRENCE, {"event": "F"})
    first.close()
    log = AuditLog(path)
    again = Steps(VirtualClock(), run_id="r2", audit=log)
    assert again.counters["record"] == 3
    log.close()
    other = Steps(VirtualClock(), run_id="r3")
    other.keep(AuditLog(path))  # given one later (the Manager opens its log after the steps)
    assert other.counters["record"] == 3
    other.keep(None)
    assert other.counters["record"] == 3


# ---------------------------------------------------------------------------- commit


def test_the_audit_lines_carry_the_run_the_rules_and_a_decisions_own_time(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    s = Steps(VirtualClock(3.0), run_id="run1", audit=AuditLog(path), rules=lambda: "0123456789abcdefXYZ")
    with s.step() as step:
        step.emit(Kind.DECISION, {"time": 1.5, "rule": "R1"})
        step.emit(Kind.OPTIONS, {})
        step.emit(Kind.CONTEXT, {"values": {}}, at=float("inf"))
    raw = path.read_text().splitlines()
    assert raw[0].count('"time"') == 1  # the decision's own time is the record's, not a second key
    assert raw[1].endswith('"rules":"0123456789abcdef"}')  # no data: the header closes the line
    recs = lines(path)
    assert [(r["seq"], r["kind"], r["time"]) for r in recs] == [
        (1, "decision", 1.5),
        (2, "options", 3.0),
        (3, "context", None),  # a time that is no finite number is written null
    ]
    assert {(r["run"], r["rules"]) for r in recs} == {("run1", "0123456789abcdef")}
    assert recs[0]["rule"] == "R1"


def test_a_step_that_raised_is_committed_with_its_records(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    journal = started(tmp_path / "journal.db")
    s, _, heard = steps(audit=AuditLog(path), journal=journal, meta=lambda: dict(META))
    with pytest.raises(RuntimeError, match="half way"), s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "E"})
        step.change.context["a"] = (True, 0.0)
        raise RuntimeError("half way")
    assert [r["event"] for r in lines(path)] == ["E"]
    saved = journal.load()
    assert saved is not None
    assert saved.context == {"a": (True, 0.0)}
    assert saved.audit == path.stat().st_size  # the change is kept with the log's new length
    assert [ev.data["event"] for ev in heard] == ["E"]
    assert not s.lock._is_owned()  # type: ignore[attr-defined]


def test_a_step_that_changed_nothing_writes_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    written: list[list[str]] = []

    def write_lines(self: AuditLog, ls: list[str]) -> int:
        written.append(list(ls))
        return 0

    monkeypatch.setattr(AuditLog, "write_lines", write_lines)
    committed: list[Change] = []
    journal = started(tmp_path / "journal.db")
    monkeypatch.setattr(Journal, "commit", lambda self, change, meta, clock: committed.append(change))
    s, _, _ = steps(audit=AuditLog(tmp_path / "audit.jsonl"), journal=journal)
    with s.step():
        pass
    assert written == [] and committed == []
    with s.step() as step:
        step.change.obligations[1] = None  # a change without records is committed too
    assert written == [[]] and len(committed) == 1


def test_before_commit_may_add_to_every_step_even_an_empty_one() -> None:
    s, _, heard = steps()
    calls: list[int] = []

    def before(step: Step) -> None:
        calls.append(len(step.events))
        if len(calls) == 1:
            step.emit(Kind.DISPATCH, {"decision": 1})

    s.before_commit = before
    with s.step():
        pass
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
    assert calls == [0, 1]
    assert [ev.kind for ev in heard] == [Kind.DISPATCH, Kind.OCCURRENCE]


# ---------------------------------------------------------------------------- broken


def no_space(self: AuditLog, lines: object) -> int:
    raise OSError(errno.ENOSPC, "No space left on device")


def test_a_failed_audit_write_breaks_the_steps_for_good(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "audit.jsonl"
    s, _, heard = steps(audit=AuditLog(path))
    monkeypatch.setattr(AuditLog, "write_lines", no_space)
    full = "cannot write the audit log: No space left on device"
    with pytest.raises(JournalError, match=full) as first, s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "E"})
    assert first.value.where == str(path)
    assert "free space" in first.value.hint
    assert s.broken is first.value
    assert heard == []  # a record not written is heard by nobody
    monkeypatch.undo()
    for _ in range(2):  # every later step, however the log does now
        with pytest.raises(JournalError, match="No space left") as later, s.step():
            pytest.fail("a broken Steps must not enter a step")
        assert later.value is not first.value
        assert (later.value.where, later.value.hint) == (first.value.where, first.value.hint)
    assert not s.lock._is_owned()  # type: ignore[attr-defined]


def test_a_step_that_raised_and_could_not_be_written_raises_the_failure(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    s, _, _ = steps(audit=AuditLog(tmp_path / "audit.jsonl"))
    monkeypatch.setattr(AuditLog, "write_lines", no_space)
    with pytest.raises(JournalError), s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
        raise RuntimeError("the step's own failure")
    assert s.broken is not None


def test_a_failed_journal_commit_breaks_the_steps(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    journal = started(tmp_path / "journal.db")
    s, _, _ = steps(journal=journal, meta=lambda: dict(META))
    failure = JournalError("cannot write the journal: disk I/O error", where="j", hint="h")

    def fail(self: Journal, change: Change, meta: object, clock: float) -> None:
        raise failure

    monkeypatch.setattr(Journal, "commit", fail)
    with pytest.raises(JournalError) as e, s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
    assert e.value is failure and s.broken is failure
    with pytest.raises(JournalError, match="disk I/O error"), s.step():
        pass


def test_an_interrupted_commit_breaks_the_steps(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    journal = started(tmp_path / "journal.db")
    s, _, _ = steps(journal=journal, meta=lambda: dict(META))

    def interrupted(self: Journal, change: Change, meta: object, clock: float) -> None:
        raise Interrupted

    monkeypatch.setattr(Journal, "commit", interrupted)
    with pytest.raises(Interrupted), s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
    assert isinstance(s.broken, JournalError)
    assert str(s.broken).startswith("a journal commit was interrupted (Interrupted)")
    assert s.broken.where == str(journal.path)


def test_a_closed_steps_refuses_with_a_configuration_error() -> None:
    s, _, _ = steps()
    s.closed = True
    with pytest.raises(ConfigurationError, match="this Manager is closed"), s.step():
        pass


def test_a_step_waiting_behind_one_that_broke_the_steps_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    s, _, _ = steps(audit=AuditLog(tmp_path / "audit.jsonl"))
    monkeypatch.setattr(AuditLog, "write_lines", no_space)
    entered = threading.Event()
    outcome: list[BaseException | None] = []

    def waiter() -> None:
        entered.wait()
        try:
            with s.step():
                outcome.append(None)
        except BaseException as e:
            outcome.append(e)

    t = threading.Thread(target=waiter)
    t.start()
    with pytest.raises(JournalError), s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
        entered.set()  # the other thread now waits for the lock this step holds
        t.join(0.2)
    t.join(5)
    assert len(outcome) == 1 and isinstance(outcome[0], JournalError)


# ---------------------------------------------------------------------------- delivery


def test_observers_hear_every_record_once_in_order_across_threads() -> None:
    s = Steps(VirtualClock(), run_id="r")
    heard: list[int] = []
    overlapping: list[int] = []
    busy = threading.Lock()

    def observer(ev: RuntimeEvent) -> None:
        if not busy.acquire(blocking=False):
            overlapping.append(ev.seq)  # two deliveries at once
            return
        try:
            heard.append(ev.seq)
        finally:
            busy.release()

    s.subscribe(observer)
    start = threading.Barrier(4)

    def work() -> None:
        start.wait()
        for _ in range(100):
            with s.step() as step:
                step.emit(Kind.OCCURRENCE, {})
                step.emit(Kind.OCCURRENCE, {})

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(30)
    assert overlapping == []
    assert heard == list(range(1, 801))


def test_records_are_delivered_after_the_lock_is_released() -> None:
    s, _, _ = steps()
    owned: list[bool] = []
    s.subscribe(lambda ev: owned.append(s.lock._is_owned()))  # type: ignore[attr-defined]
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
        assert owned == []  # nothing is heard before the step is over
    assert owned == [False]


def test_an_observer_that_raises_is_removed_and_its_removal_recorded() -> None:
    s, _, heard = steps()
    calls: list[int] = []

    def fragile(ev: RuntimeEvent) -> None:
        calls.append(ev.seq)
        raise ValueError("boom")

    s.subscribe(fragile)
    after: list[RuntimeEvent] = []
    s.subscribe(after.append)
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "E"})
        step.emit(Kind.OCCURRENCE, {"event": "F"})
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "G"})
    assert calls == [1]  # removed at its first failure: never called again
    assert fragile not in s.observers
    removed = [ev for ev in heard if ev.kind == Kind.OBSERVER_REMOVED]
    assert len(removed) == 1
    assert removed[0].seq == 3  # a step of its own, after the step it failed in
    assert removed[0].data["reason"] == "ValueError: boom"
    assert removed[0].data["observer"].endswith("fragile")
    assert [ev.seq for ev in after] == [1, 2, 3, 4]  # the others hear everything, the removal too


def test_no_removal_is_recorded_once_the_steps_are_closed() -> None:
    s, _, heard = steps()

    def closing(ev: RuntimeEvent) -> None:
        s.closed = True
        raise ValueError("closing")

    s.subscribe(closing)
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {})
    assert closing not in s.observers
    assert [ev.kind for ev in heard] == [Kind.OCCURRENCE]


def test_an_observer_that_takes_a_step_hears_its_records_after_the_current_ones() -> None:
    s, _, heard = steps()

    def reacting(ev: RuntimeEvent) -> None:
        if ev.data.get("event") == "E":
            with s.step() as step:
                step.emit(Kind.OCCURRENCE, {"event": "reaction"})

    s.subscribe(reacting)
    with s.step() as step:
        step.emit(Kind.OCCURRENCE, {"event": "E"})
        step.emit(Kind.OCCURRENCE, {"event": "F"})
    assert [ev.data["event"] for ev in heard] == ["E", "F", "reaction"]
