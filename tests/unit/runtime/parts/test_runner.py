"""The runner alone: admitted jobs reach their implementations outside the lock, outcomes recorded."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from cosleec.records import Kind
from cosleec.runtime.decision import Decision
from cosleec.runtime.implementations import Ran
from cosleec.runtime.jobs import Job
from cosleec.runtime.model import Obligation
from cosleec.runtime.runner import FRAMES_PER_LEVEL, Runner, deepest

from .build import Parts, journaled, parts

RULES = "R1 when E then F within 5 seconds otherwise Help"


def decided(p: Parts, event: str = "E") -> list[Job]:
    with p.core.steps.step() as step:
        return p.gate.ready(p.trigger(event, step), step.now, step)


def test_a_job_runs_its_capability_outside_the_lock_and_its_outcome_is_recorded() -> None:
    p = parts(RULES)
    ran: list[tuple[str, int, bool]] = []

    @p.core.implementations.capability("F")
    def do_f(ob: Obligation, d: Decision) -> None:
        ran.append((ob.event, d.id, p.core.steps.lock._is_owned()))  # type: ignore[attr-defined]

    runner = Runner(p.core, p.gate)
    (job,) = decided(p)
    checked = p.core.steps.last_record
    runner.dispatch([job])
    assert ran == [("F", 1, False)]
    (done,) = p.of(Kind.TASK_DONE)
    assert done == {
        "rule": "R1",
        "decision": 1,
        "clause": 0,
        "what": "capability",
        "event": "F",
        "error": None,
        "checked": checked,
    }


def test_an_otherwise_runs_as_a_fallback() -> None:
    p = parts(RULES)
    ran: list[str] = []
    p.core.implementations.capability("Help")(lambda ob, d: ran.append(d.event))
    decided(p)
    p.clock.set(6.0)
    with p.core.steps.step() as step:
        (fallback,) = p.gate.ready(p.enforcer.advance(step.now, step), step.now, step)
    Runner(p.core, p.gate).dispatch([fallback])
    assert ran == ["otherwise"]


def test_a_failed_implementation_is_counted_and_recorded() -> None:
    p = parts(RULES)

    def broken(ob: Obligation, d: Decision) -> None:
        raise OSError("no gripper")

    p.core.implementations.capability("F")(broken)
    Runner(p.core, p.gate).dispatch(decided(p))
    (failed,) = p.of(Kind.TASK_FAILED)
    assert (failed["event"], failed["error"]) == ("F", "OSError: no gripper")
    assert p.core.stats.task_failures == 1


def test_outcomes_are_counted_but_not_recorded_when_nobody_records() -> None:
    p = parts(RULES, listen=False)
    runner = Runner(p.core, p.gate)
    (job,) = decided(p)
    last = p.core.steps.last_record
    runner.run(job.rule, job.decision, lambda: [Ran("task", None, "boom"), Ran("task", None)])
    assert p.core.stats.task_failures == 1
    assert p.core.steps.last_record == last


def test_nothing_runs_when_the_runtime_only_decides() -> None:
    p = parts(RULES)
    p.core.dispatch = False
    ran: list[int] = []
    p.core.implementations.capability("F")(lambda ob, d: ran.append(d.id))
    Runner(p.core, p.gate).dispatch(decided(p))
    assert ran == [] and p.of(Kind.TASK_DONE) == []


def test_a_job_the_gate_refuses_never_runs() -> None:
    p = parts(f"R2 when G then not F within 2 seconds {RULES}")
    ran: list[int] = []
    p.core.implementations.capability("F")(lambda ob, d: ran.append(d.id))
    jobs = decided(p)
    decided(p, "G")  # F is forbidden since the decision
    Runner(p.core, p.gate).dispatch(jobs)
    assert ran == [] and len(p.of(Kind.REFUSED)) == 1


def test_a_job_runs_with_the_implementations_bound_when_it_was_decided() -> None:
    p = parts(RULES)
    ran: list[str] = []
    p.core.implementations.capability("F")(lambda ob, d: ran.append("then"))
    (job,) = decided(p)
    job.implementations = p.core.implementations
    later = type(p.core.implementations)(p.core.ruleset)
    later.capability("F")(lambda ob, d: ran.append("now"))
    p.core.implementations = later  # a reload bound others since
    Runner(p.core, p.gate).dispatch([job])
    assert ran == ["then"]


@pytest.mark.parametrize(("max_depth", "runs"), [(0, 0), (1, 1), (3, 3)])
def test_max_depth_stops_a_trigger_loop_with_a_task_failed_record(max_depth: int, runs: int) -> None:
    p = parts(RULES)
    runner = Runner(p.core, p.gate, max_depth)
    (job,) = decided(p)
    calls: list[int] = []

    def again() -> list[Ran]:  # an implementation that triggers its own rule, forever
        calls.append(len(calls))
        runner.run(job.rule, job.decision, again)
        return [Ran("task", None)]

    runner.run(job.rule, job.decision, again)
    assert len(calls) == runs
    (failed,) = p.of(Kind.TASK_FAILED)
    assert failed["error"] == (
        f"not run: implementations triggered rules {max_depth} deep (max_depth={max_depth}); "
        "does an implementation of R1 trigger E again?"
    )
    assert len(p.of(Kind.TASK_DONE)) == runs
    assert p.core.stats.task_failures == 1


def test_the_depth_is_given_back_when_an_implementation_raises() -> None:
    p = parts(RULES)
    runner = Runner(p.core, p.gate, max_depth=1)
    (job,) = decided(p)

    def raising() -> list[Ran]:
        raise RuntimeError("escaped")

    with pytest.raises(RuntimeError):
        runner.run(job.rule, job.decision, raising)
    runner.run(job.rule, job.decision, lambda: [Ran("task", None)])
    assert len(p.of(Kind.TASK_DONE)) == 1


def test_deepest_keeps_frames_for_the_caller_and_is_at_least_one(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "getrecursionlimit", lambda: 1000)
    assert deepest() == (1000 - 200) // FRAMES_PER_LEVEL == 50
    monkeypatch.setattr(sys, "getrecursionlimit", lambda: 100)
    assert deepest() == 1


def test_a_journaled_outcome_clears_the_actions_in_flight(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    p.gate.running[1] = {1}
    (job,) = decided(p)
    Runner(p.core, p.gate).run(job.rule, job.decision, lambda: [Ran("task", None)], 0, [1])
    assert p.gate.running == {}
