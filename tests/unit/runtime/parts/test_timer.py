"""The timer alone: when it must wake, when a step pokes it, and its thread's life."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable

import pytest

from cosleec.lang import CONFLICT_AWARE
from cosleec.runtime.journal import JournalError
from cosleec.runtime.timer import Timer

from .build import Parts, parts

RULES = "R1 when E then F within 5 seconds R2 when G then not Rec within 3 seconds"


def timer(p: Parts, tick: Callable[[], object] | None = None) -> Timer:
    return Timer(p.core, p.enforcer, p.gate, tick or (lambda: None))


def asleep(t: Timer) -> Timer:
    """``t`` as if its thread were running (never started: only whether there is one matters)."""
    t.thread = threading.Thread(target=lambda: None)
    return t


def test_without_a_thread_nothing_is_ever_due() -> None:
    p = parts(RULES)
    p.fire("E")
    assert timer(p).due_at() is None


def test_with_a_thread_the_next_deadline_is_due() -> None:
    p = parts(RULES)
    t = asleep(timer(p))
    assert t.due_at() is None  # nothing in force
    p.clock.set(1.0)
    p.fire("E")
    assert t.due_at() == 6.0
    p.fire("G")
    assert t.due_at() == 4.0


def test_while_something_is_held_the_timer_is_always_woken() -> None:
    p = parts(f"{RULES} R3 when Help then Rec within 60 seconds")
    t = asleep(timer(p))
    p.fire("G")
    with p.core.steps.step() as step:
        assert p.gate.ready(p.trigger("Help", step), step.now, step) == []
    assert p.gate.held and t.due_at() == -math.inf


def test_while_conflict_aware_priorities_may_cut_the_timer_is_always_woken() -> None:
    p = parts(RULES, priorities=("R1 > R2",), semantics=CONFLICT_AWARE)
    assert asleep(timer(p)).due_at() == -math.inf


@pytest.mark.parametrize(
    ("thread", "sleeping_until", "due", "poked"),
    [
        (False, math.inf, -math.inf, False),  # no thread: nobody to wake
        (True, 10.0, None, False),  # nothing due
        (True, 10.0, 10.0, False),  # due when it wakes anyway
        (True, 10.0, 11.0, False),
        (True, 10.0, 9.5, True),  # due before it wakes
        (True, math.inf, -math.inf, True),  # the default: wake it whatever it sleeps until
    ],
)
def test_a_step_pokes_the_timer_only_when_something_is_due_before_it_wakes(
    thread: bool, sleeping_until: float, due: float | None, poked: bool
) -> None:
    t = timer(parts(RULES))
    if thread:
        asleep(t)
    t.due = sleeping_until
    if due == -math.inf:
        t.notify()
    else:
        t.notify(due)
    assert t._poke is poked


def test_the_timer_sleeps_until_the_first_of_deadline_expiry_cut_and_opening() -> None:
    p = parts(RULES, max_age={"a": 2.5})
    t = timer(p)
    assert t._next() is None
    p.fire("E")
    assert t._next() == 5.0  # F's deadline
    p.update(a=True)
    assert t._next() == 2.5  # a goes stale
    p.gate.held[1] = p.fire("E")[0]
    p.gate.seen = (0, 1.5)
    assert t._next() == 1.5  # a held action's interval opens


def test_the_timer_wakes_for_a_conflict_aware_cut_first() -> None:
    p = parts(
        "R1 when E then Rec within 5 seconds R2 when G then not Rec within 10 seconds",
        priorities=("R1 > R2",),
        semantics=CONFLICT_AWARE,
        lead=2.0,
    )
    p.fire("E")
    p.fire("G")
    assert timer(p)._next() == 3.0  # R1's deadline at 5, less the lead


def test_the_thread_ticks_and_stops() -> None:
    p = parts(RULES)
    ticked = threading.Event()
    t = timer(p, ticked.set)
    t.start()
    thread = t.thread
    t.start()  # once
    assert t.thread is thread and thread is not None
    assert ticked.wait(5)
    t.stop()
    assert not thread.is_alive()


def test_a_journal_failure_stops_the_thread_and_other_failures_do_not() -> None:
    p = parts(RULES)
    calls: list[int] = []
    twice = threading.Event()

    def failing() -> None:
        calls.append(1)
        if len(calls) >= 2:
            twice.set()
            raise JournalError("cannot write the journal")
        raise RuntimeError("a bug in judging deadlines")

    t = timer(p, failing)
    t.start()
    assert twice.wait(5)
    assert t.thread is not None
    t.thread.join(5)
    assert not t.thread.is_alive() and len(calls) == 2
