"""The gate alone: what a decision requires runs only when ``request`` would allow it."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cosleec.records import Kind
from cosleec.runtime.gate import Gate
from cosleec.runtime.jobs import Job
from cosleec.runtime.journal import JournalError
from cosleec.runtime.steps import Step

from .build import Parts, journaled, parts

BAN = "R1 when E then not Rec within 10 seconds"
HELD = f"{BAN} R2 when G then Rec within 60 seconds"
SPLIT = f"{BAN} R2 when G then Rec within 60 seconds and F within 60 seconds"


def ready(p: Parts, t: float, *events: str) -> list[Job]:
    """At ``t``: what fell due, then ``events`` occur; returns what the gate lets run."""
    p.clock.set(t)
    with p.core.steps.step() as step:
        jobs = p.enforcer.advance(step.now, step)
        for event in events:
            jobs += p.trigger(event, step)
        return p.gate.ready(jobs, step.now, step)


def events(job: Job) -> list[str]:
    return [o.event for o in job.decision.obligations]


# ---------------------------------------------------------------------------- ready


def test_with_nothing_forbidden_the_jobs_run_as_decided() -> None:
    p = parts("R2 when G then Rec within 60 seconds")
    with p.core.steps.step() as step:
        jobs = p.trigger("G", step)
        assert p.gate.ready(jobs, 0.0, step) is jobs


def test_an_action_forbidden_now_is_held_and_released_once_the_prohibition_ends() -> None:
    p = parts(HELD)
    ready(p, 0.0, "E")
    assert ready(p, 1.0, "G") == []
    (held,) = p.of(Kind.HELD)
    assert held == {"decision": 2, "rule": "R2", "events": ["Rec"], "by": ["R1"], "opens": None}
    assert p.of(Kind.DECISION)[-1]["dispatch"] == "held"
    assert list(p.gate.held) == [2]
    assert p.gate.opening is None  # it waits for a prohibition to end, no interval to open
    assert ready(p, 10.0) == []  # the prohibition's last instant: still forbidden
    (part,) = ready(p, 10.5)
    assert events(part) == ["Rec"] and part.decision.id == 2
    assert p.gate.held == {}
    assert p.of(Kind.DISPATCH)[-1]["decision"]["id"] == 2


def test_the_allowed_actions_of_a_decision_run_now_and_the_forbidden_ones_wait() -> None:
    p = parts(SPLIT)
    ready(p, 0.0, "E")
    (now,) = ready(p, 1.0, "G")
    assert events(now) == ["F"]
    (dispatched,) = p.of(Kind.DISPATCH)
    assert [o["event"] for o in dispatched["decision"]["obligations"]] == ["F"]
    assert p.of(Kind.HELD)[0]["events"] == ["Rec"]
    (later,) = ready(p, 11.0)
    assert events(later) == ["Rec"]  # F was handed on already: never again


def test_a_decision_some_of_whose_actions_were_refused_at_once_runs_the_rest_as_changed() -> None:
    p = parts(f"{BAN} R2 when G then Rec within 5 seconds and F within 60 seconds")
    ready(p, 0.0, "E")
    (part,) = ready(p, 1.0, "G")
    assert events(part) == ["F"]  # Rec was refused: never run
    assert p.of(Kind.DECISION)[1]["dispatch"] == "changed"
    assert [o["event"] for o in p.of(Kind.DISPATCH)[0]["decision"]["obligations"]] == ["F"]


def test_a_decision_whose_actions_were_all_handed_on_waits_for_nothing() -> None:
    p = parts(SPLIT)
    ready(p, 0.0, "E")  # something is forbidden: every job is examined
    p.clock.set(1.0)
    with p.core.steps.step() as step:
        (job,) = p.trigger("G", step)
        job.sent.update(t.id for t in job.items)
        assert p.gate.ready([job], step.now, step) == []
        assert step.events[-1].kind == Kind.OBLIGATION  # no dispatch, no held record
    assert p.gate.held == {}


def test_an_action_waits_for_its_interval_to_open() -> None:
    p = parts("R2 when G then Rec within [5 seconds, 60 seconds]")
    assert ready(p, 0.0, "G") == []
    (held,) = p.of(Kind.HELD)
    assert (held["opens"], held["by"]) == (5.0, [])
    assert p.gate.opening == 5.0
    assert ready(p, 4.5) == []
    assert len(p.of(Kind.HELD)) == 1  # examined again only once something can have changed
    (part,) = ready(p, 5.0)
    assert events(part) == ["Rec"] and p.gate.opening is None


def test_a_held_decision_whose_action_ended_meanwhile_is_withheld() -> None:
    p = parts(HELD)
    ready(p, 0.0, "E")
    ready(p, 1.0, "G")
    assert ready(p, 2.0, "Rec") == []  # Rec happened anyway: the obligation is met, nothing is owed
    (withheld,) = p.of(Kind.WITHHELD)
    assert withheld == {"decision": 2, "rule": "R2", "reason": "nothing it required is still owed"}
    assert p.gate.held == {}
    assert p.of(Kind.DECISION)[1]["dispatch"] == "held"  # its record said held, and stays so


def test_a_decision_whose_every_action_was_refused_at_once_is_withheld() -> None:
    p = parts(f"{BAN} R2 when G then Rec within 5 seconds otherwise Help")
    ready(p, 0.0, "E")
    (fallback,) = ready(p, 1.0, "G")
    assert fallback.decision.event == "otherwise" and events(fallback) == ["Help"]
    assert p.of(Kind.WITHHELD)[0]["decision"] == 2
    assert p.of(Kind.DECISION)[1]["dispatch"] == "withheld"  # a Manager node hands it on not at all


def test_look_again_examines_every_held_decision_at_the_next_step() -> None:
    p = parts("R2 when G then Rec within [5 seconds, 60 seconds]")
    ready(p, 0.0, "G")
    assert p.gate.seen == (p.core.tracker.ended, 5.0)
    p.gate.look_again()
    assert p.gate.seen == (-1, 0.0)


# ---------------------------------------------------------------------------- admit


def decided(p: Parts, rules_event: str = "G") -> Job:
    (job,) = ready(p, 0.0, rules_event)
    return job


def test_admit_lets_a_job_through_with_the_last_record_when_nothing_can_forbid_it() -> None:
    p = parts(HELD)
    job = decided(p)
    before = len(p.heard)
    assert p.gate.admit(job) == (job, p.core.steps.last_record)
    assert len(p.heard) == before


def test_admit_refuses_an_action_a_prohibition_that_took_force_since_forbids() -> None:
    p = parts(HELD)
    job = decided(p)
    ready(p, 1.0, "E")
    assert p.gate.admit(job) is None
    (refused,) = p.of(Kind.REFUSED)
    assert refused["by"] == ["R1"] and refused["event"] == "Rec"
    assert refused["source"] == "dispatch of decision 1 (R2)"
    assert refused["reason"] == p.answers.given("Rec", p.core.tracker.forbidding("Rec", 1.0)).reason
    assert p.core.stats.refused == 1 and job.items[0].refused == 1
    assert "dispatch" not in p.of(Kind.DECISION)[0]  # a record delivered before is never changed
    assert list(p.gate.held) == [1] and p.of(Kind.HELD)[0]["events"] == ["Rec"]
    assert p.gate.seen == (-1, 0.0)
    assert ready(p, 11.0) == []  # the prohibition began at 1: forbidden to 11, ends included
    (part,) = ready(p, 11.5)  # held again, and released once allowed
    assert events(part) == ["Rec"]


def test_admit_starts_the_allowed_part_and_holds_the_forbidden_one() -> None:
    p = parts(SPLIT)
    job = decided(p)
    ready(p, 1.0, "E")
    admitted = p.gate.admit(job)
    assert admitted is not None
    part, checked = admitted
    assert events(part) == ["F"] and checked == p.core.steps.last_record
    assert p.heard[-1].kind == Kind.DISPATCH  # the last record before it starts
    assert p.of(Kind.HELD)[0]["events"] == ["Rec"]


def test_admit_withholds_a_job_whose_actions_all_ended_since() -> None:
    p = parts("R2 when G then Rec within 60 seconds R1 when E then not F within 1 seconds")
    job = decided(p)
    ready(p, 0.5, "E", "Rec")  # something is banned (the slow path), and Rec was met meanwhile
    assert p.gate.admit(job) is None
    assert p.of(Kind.WITHHELD)[0]["decision"] == 1
    assert p.of(Kind.REFUSED) == []


def test_admit_withholds_a_job_whose_action_was_met_even_with_nothing_forbidden() -> None:
    p = parts("R2 when G then Rec within 60 seconds")
    job = decided(p)
    ready(p, 0.5, "Rec")
    assert p.core.tracker.bans == 0
    assert p.gate.admit(job) is None
    assert p.of(Kind.WITHHELD)[0]["decision"] == 1


@pytest.mark.parametrize("stop", ["broken", "closed"])
def test_admit_starts_nothing_once_the_steps_are_broken_or_closed(stop: str) -> None:
    p = parts(HELD)
    job = decided(p)
    if stop == "closed":
        p.core.steps.closed = True
    else:
        p.core.steps.broken = JournalError("cannot write the journal")
    assert p.gate.admit(job) is None


# ---------------------------------------------------------------------------- the outbox


def test_a_held_decision_keeps_an_outbox_entry_a_restart_reads(tmp_path: Path) -> None:
    p = parts(SPLIT)
    journaled(p, tmp_path / "journal.db")
    ready(p, 0.0, "E")
    p.clock.set(1.0)
    with p.core.steps.step() as step:
        p.gate.ready(p.trigger("G", step), step.now, step)
        entry = step.change.outbox[2]
    assert entry is not None
    assert {k: entry[k] for k in ("decision", "rule", "event", "held", "trigger", "sent", "running")} == {
        "decision": 2,
        "rule": "R2",
        "event": "G",
        "held": True,
        "trigger": True,
        "sent": [3],  # F, handed on
        "running": [3],  # and its outcome not recorded yet
    }
    again = Gate(p.core, p.answers)
    assert again.rehold(entry)
    assert again.held[2].sent == {3}
    assert [t.event for t in again.held[2].items] == ["Rec", "F"]
    assert not again.rehold({**entry, "rule": "R9"})  # its rule is gone


def test_a_released_part_is_in_flight_in_the_outbox_until_its_outcome_is_recorded(tmp_path: Path) -> None:
    p = parts(SPLIT)
    journaled(p, tmp_path / "journal.db")
    ready(p, 0.0, "E")
    ready(p, 1.0, "G")
    p.clock.set(11.5)
    with p.core.steps.step() as step:
        (part,) = p.gate.ready(p.enforcer.advance(step.now, step), step.now, step)
        entry = step.change.outbox[2]
    assert events(part) == ["Rec"]
    assert entry is not None and (entry["held"], entry["running"], entry["sent"]) == (False, [2, 3], [2, 3])


def test_a_published_decision_dispatched_in_parts_keeps_what_still_waits(tmp_path: Path) -> None:
    p = parts(SPLIT)
    journaled(p, tmp_path / "journal.db")
    ready(p, 0.0, "E")
    ready(p, 1.0, "G")
    p.gate.running.clear()  # (as if published at once, then told so)
    p.gate.delivered(2)
    step = Step()
    p.gate.before_commit(step)
    entry = step.change.outbox[2]
    assert entry is not None and entry["held"] is True


def test_landed_actions_leave_the_outbox_once_nothing_waits(tmp_path: Path) -> None:
    p = parts(SPLIT)
    journaled(p, tmp_path / "journal.db")
    p.gate.running[7] = {1, 2}
    step = Step()
    p.gate.landed(7, [1], step)
    assert p.gate.running == {7: {2}} and step.change.outbox == {}
    p.gate.landed(7, [2], step)
    assert p.gate.running == {} and step.change.outbox == {7: None}


def test_a_published_decision_leaves_the_outbox_with_the_next_commit(tmp_path: Path) -> None:
    p = parts(HELD)
    p.gate.delivered(3)
    assert not p.gate.pending_delivery  # no journal: nothing to clear
    journaled(p, tmp_path / "journal.db")
    p.gate.delivered(3)
    assert p.gate.pending_delivery
    step = Step()
    p.gate.before_commit(step)
    assert step.change.outbox == {3: None} and not p.gate.pending_delivery


def test_a_decision_published_again_after_a_restart_holds_only_what_is_still_owed() -> None:
    p = parts(SPLIT)
    job = decided(p)
    rec = {
        "decision": 1,
        "rule": "R2",
        "event": "G",
        "running": [t.id for t in job.items],
        "record": job.decision.to_json(),
    }
    job.items[1].status = "fulfilled"  # F was met meanwhile
    step = Step()
    p.gate.republish(rec, False, step)
    (published,) = p.gate.undelivered
    assert [o["event"] for o in published["obligations"]] == ["Rec"]
    assert p.gate.running == {1: {job.items[0].id}}
    assert step.change.outbox[1] == {**rec, "running": [job.items[0].id]}


def test_the_timer_sees_no_opening_while_nothing_is_held() -> None:
    p = parts(HELD)
    p.gate.seen = (0, 3.0)
    assert p.gate.opening is None
    p.gate.held[1] = decided(p)
    assert p.gate.opening == 3.0
    p.gate.seen = (0, math.inf)
    assert p.gate.opening is None
