"""The clock watch alone: a virtual clock's moves judge, what they start waits to be claimed."""

from __future__ import annotations

from typing import Any

from cosleec.runtime.clock import MonotonicClock, VirtualClock
from cosleec.runtime.steps import Steps
from cosleec.runtime.watch import UNCLAIMED, ClockWatch


class Judge:
    """Stands for the Manager's judging: counts its calls, returns what it is told to."""

    def __init__(self) -> None:
        self.calls = 0
        self.started: list[Any] = []

    def __call__(self) -> list[Any]:
        self.calls += 1
        out, self.started = self.started, []
        return out


def watched() -> tuple[VirtualClock, Judge, ClockWatch, Steps]:
    clock, judge = VirtualClock(), Judge()
    steps = Steps(clock, run_id="test")
    watch = ClockWatch(judge, steps)
    watch.begin(clock)
    return clock, judge, watch, steps


def test_every_move_judges_and_what_it_started_is_claimed_once() -> None:
    clock, judge, watch, _ = watched()
    judge.started = ["a"]
    clock.advance(1)
    clock.set(5)
    assert judge.calls == 2
    assert watch.claim() == ["a"]
    assert watch.claim() == []  # claimed: gone


def test_a_real_clock_is_not_watched_and_a_second_begin_watches_once() -> None:
    judge = Judge()
    clock = VirtualClock()
    watch = ClockWatch(judge, Steps(clock, run_id="test"))
    watch.begin(MonotonicClock())
    clock.advance(1)
    assert judge.calls == 0
    watch.begin(clock)
    watch.begin(clock)
    clock.advance(1)
    assert judge.calls == 1


def test_a_stopped_watch_or_a_closed_or_broken_manager_judges_nothing() -> None:
    clock, judge, watch, steps = watched()
    steps.closed = True
    clock.advance(1)
    steps.closed, steps.broken = False, RuntimeError("disk full")
    clock.advance(1)
    assert judge.calls == 0
    steps.broken = None
    watch.stop()
    watch.stop()  # twice: nothing
    clock.advance(1)
    assert judge.calls == 0


def test_only_the_latest_are_kept_for_a_run_that_never_claims() -> None:
    clock, judge, watch, _ = watched()
    judge.started = list(range(UNCLAIMED))
    clock.advance(1)
    judge.started = ["last"]
    clock.advance(1)
    kept = watch.claim()
    assert len(kept) == UNCLAIMED and kept[0] == 1 and kept[-1] == "last"
