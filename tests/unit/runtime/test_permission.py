"""Manager.request and Manager.permission: the answer, with the rules that forbid and a reason a
person can read. ``request`` is a real attempt (a refusal is counted and recorded);
``permission`` is a question (nothing is recorded or counted).

Each test pins one part of the answer; the comments say which one-character change to the
runtime it would catch.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cosleec.runtime import ContextError, Permission, read_audit
from tests.unit.runtime.test_enforcement import manager

WATCH = "R2 when E then not Rec within 10 seconds unless a"


def refused(log: Path) -> list[dict[str, object]]:
    return [r for r in read_audit(log) if r["kind"] == "refused"]


def test_a_permitted_event_says_so_counts_nothing_and_records_nothing(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager(WATCH, audit=log)
    p = m.permission("Rec")
    assert p == Permission("Rec", True, (), "Rec is permitted: no prohibition in force forbids it now")
    assert bool(p) is True and m.request("Rec") == p
    m.close()
    assert m.stats["refused"] == 0 and refused(log) == []


def test_a_forbidden_event_names_the_rule_its_window_end_and_the_decision_that_forbids_it(
    tmp_path: Path,
) -> None:
    log = tmp_path / "audit.jsonl"
    m, clock = manager(WATCH, audit=log)
    clock.set(150)
    m.update(a=False)
    m.event("E")
    p = m.permission("Rec")
    assert not p and p.permitted is False and p.rules == ("R2",)
    assert p.reason == (
        "Rec is forbidden by R2 for another 10 s (R2: not Rec within 10 s [default], because a was false)"
    )
    assert p.for_people == "I can't rec for another 10 seconds, because a is no."
    assert m.request("Rec") == p  # the same answer; the question was not counted, the attempts are
    assert not m.request("Rec")
    m.close()
    assert m.stats["refused"] == 2
    first, second = refused(log)
    assert first["reason"] == p.reason and first["by"] == ["R2"] and first["obligations"] == [1]
    assert "source" not in first and second["reason"] == p.reason


def test_without_the_decision_in_history_the_reason_describes_the_prohibition() -> None:
    m, clock = manager(WATCH + " R1 when F then G", history=1)
    m.update(a=False)
    m.event("E")
    clock.advance(2)
    m.event("F")  # the only decision kept now
    assert (
        m.permission("Rec").reason
        == "Rec is forbidden by R2 for another 8 s (R2: not Rec within 10 s, in force for 2 s)"
    )


def test_two_rules_forbidding_are_both_named_each_with_its_window() -> None:
    m, clock = manager(WATCH + " R3 when F then not Rec within 1 minutes")
    m.update(a=False)
    m.event("E")
    clock.advance(5)
    m.event("F")
    p = m.permission("Rec")
    assert p.rules == ("R2", "R3")
    assert "by R2 for another 5 s (R2: not Rec within 10 s" in p.reason
    assert " and by R3 for another 1 min (R3: not Rec within 60 s" in p.reason
    assert p.for_people == "I can't rec for another 1 minute, because a is no."  # the longer: R3's


def test_two_prohibitions_of_one_rule_name_it_once_and_are_both_counted(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, clock = manager(WATCH, audit=log)
    m.update(a=False)
    m.event("E")
    clock.advance(4)
    m.event("E")
    p = m.request("Rec")
    assert p.rules == ("R2",)
    # one phrase per rule, with the window that ends last: the reason does not grow per trigger
    assert (
        p.reason
        == "Rec is forbidden by R2 for another 10 s (R2: not Rec within 10 s [default], because a was false)"
    )
    assert sorted(t.refused for t in m.tracker.active) == [1, 1]
    m.close()
    (r,) = refused(log)
    assert r["by"] == ["R2", "R2"] and r["obligations"] == [1, 2]


@pytest.mark.parametrize(
    ("at", "permitted"),
    [
        (10.0, False),  # the window's end instant is still inside it (`not E within T`: [t, t+T])
        (math.nextafter(10.0, math.inf), True),  # the next representable instant is past it
        (0.0, False),  # and its start instant is inside it too
    ],
)
def test_the_prohibition_window_includes_its_end_instant_and_nothing_after(
    at: float, permitted: bool
) -> None:
    m, clock = manager(WATCH)
    m.update(a=False)
    m.event("E")  # at 0: forbidden in [0, 10]
    clock.set(at)
    p = m.permission("Rec")
    assert p.permitted is permitted
    assert p.rules == (() if permitted else ("R2",))


def test_after_the_window_the_event_is_permitted_again_and_the_prohibition_was_respected() -> None:
    m, clock = manager(WATCH)
    m.update(a=False)
    m.event("E")
    clock.set(11)
    assert m.permission("Rec").permitted
    (t,) = list(m.tracker.closed)
    assert t.status == "respected" and t.refused == 0


def test_the_source_is_kept_in_the_refused_record(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager(WATCH, audit=log)
    m.update(a=False)
    m.event("E")
    assert not m.request("Rec", source="/camera/record (guarded)")
    assert not m.request("Rec", source="x" * 1000)
    m.close()
    first, second = refused(log)
    assert first["source"] == "/camera/record (guarded)"
    assert str(second["source"]).startswith("x" * 200) and len(str(second["source"])) < 230  # clipped


def test_a_source_that_is_not_a_string_is_a_mistake() -> None:
    m, _ = manager(WATCH)
    with pytest.raises(TypeError, match="source"):
        m.request("Rec", source=3)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        m.request("Rec", "a topic")  # type: ignore[misc]  # keyword only: never read as the event
    with pytest.raises(TypeError, match=r"records nothing; for a real attempt, call request\(name, source"):
        m.permission("Rec", source="a topic")  # a question names no one: who attempts calls request


def test_an_unknown_event_under_refuse_is_not_permitted_and_says_what_was_meant(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager(WATCH, unknown_events="refuse", audit=log)
    p = m.request("Reec")
    assert p == Permission("Reec", False, (), "Reec is not an event the rules declare (did you mean Rec?)")
    assert m.permission("Reec") == p  # the question: the same answer, not recorded
    m.close()
    (r,) = [r for r in read_audit(log) if r["kind"] == "rejected"]
    assert r["what"] == "request" and m.stats["rejected"] == 1 and m.stats["refused"] == 0


def test_an_unknown_event_under_raise_raises_as_request_does() -> None:
    m, _ = manager(WATCH)
    with pytest.raises(ContextError, match="unknown event 'Reec'") as e:
        m.permission("Reec")
    assert "Rec" in e.value.hint and m.stats["rejected"] == 0  # a question: not counted
    with pytest.raises(ContextError):
        m.request("Reec")
    assert m.stats["rejected"] == 1


def test_a_closed_manager_permits_nothing_and_says_so() -> None:
    m, _ = manager(WATCH)
    m.close()
    assert m.permission("Rec") == Permission("Rec", False, (), "Rec is not permitted: the Manager is closed")
    assert not m.request("Rec") and m.request("Rec").reason == m.permission("Rec").reason


def test_a_manager_whose_audit_log_failed_permits_nothing_and_says_why(tmp_path: Path) -> None:
    m, _ = manager(WATCH, audit=tmp_path / "audit.jsonl")
    m.update(a=False)
    m.event("E")
    assert m.audit is not None
    m.audit._fh.close()  # as a full disk would: the refusal's record cannot be written
    p = m.request("Rec")  # before: JournalError out of request, from its own commit
    assert not p and p.rules == ()
    assert p.reason.startswith("Rec is not permitted: the Manager can no longer keep its state (")
    assert "cannot write the audit log" in p.reason
    assert not m.permission("F")  # from now on, even what no prohibition forbids
    assert not m.request("F") and m.request("F").reason == p.reason.replace("Rec", "F", 1)


def test_asking_permission_records_and_counts_nothing_one_attempt_counts_once(tmp_path: Path) -> None:
    # the miscount: three questions before one real attempt counted refused == 3
    log = tmp_path / "audit.jsonl"
    m, _ = manager(WATCH, audit=log)
    m.start(check=False)
    m.update(a=False)
    m.event("E")
    before = len(read_audit(log))
    for _ in range(3):
        assert not m.permission("Rec")
    assert len(read_audit(log)) == before and m.stats["refused"] == 0  # a question: nothing
    assert [t.refused for t in m.tracker.active] == [0]
    assert not m.request("Rec", source="arm")  # the attempt
    m.close()
    assert m.stats["refused"] == 1 and [r["source"] for r in refused(log)] == ["arm"]
