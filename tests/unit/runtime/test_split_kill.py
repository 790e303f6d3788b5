"""A decision dispatched in parts, killed with SIGKILL while a part runs: at most once, and said.

A decision whose actions are not all allowed runs the allowed ones now and holds the
others (its journal outbox entry says ``held``, with the actions already handed on).
Each test kills a real process inside a capability and starts a new Manager on the same
journal: a part cut short by the kill is named by a ``task-interrupted`` record and never
runs again; what is still held runs once, when allowed; a part that finished is not
reported as interrupted.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

from cosleec.runtime import Manager, VirtualClock, read_audit

#: R1's decision on X: A held while R2 forbids it (30 s), B allowed at once
SPLIT = """def_start
  event X event Y event A event B
def_end
rule_start
R1 when X then A within 60 seconds and B within 5 seconds
R2 when Y then not A within 30 seconds
rule_end
"""


def die_in(tmp_path: Path, event: str, body: str) -> list[str]:
    """Run ``body`` in a new process with ``m`` and ``clock``, SIGKILLed inside ``event``'s
    capability (or after ``body``); the capabilities that started, in order."""
    (tmp_path / "rules.sleec").write_text(SPLIT)
    script = (
        textwrap.dedent(
            f"""
        import os, signal
        from cosleec.runtime import Manager, VirtualClock
        clock = VirtualClock(0.0)
        m = Manager.from_file({str(tmp_path / "rules.sleec")!r}, clock=clock,
                              journal={str(tmp_path / "state.db")!r}, audit={str(tmp_path / "audit.jsonl")!r})
        def capability(event):
            def act(ob, d):
                print(event, flush=True)
                if event == {event!r}:
                    os.kill(os.getpid(), signal.SIGKILL)
                m.event(event)
            return act
        for e in ("A", "B"):
            m.capability(e)(capability(e))
        m.start()
        """
        )
        + textwrap.dedent(body)
        + "\nos.kill(os.getpid(), signal.SIGKILL)\n"
    )
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert p.returncode == -9, p.stderr
    return p.stdout.split()


def again(tmp_path: Path, t: float) -> tuple[Manager, VirtualClock, list[str]]:
    """A new Manager on the killed one's journal at clock time ``t``, started; what it runs."""
    clock = VirtualClock(t)
    m = Manager.from_file(
        tmp_path / "rules.sleec", clock=clock, journal=tmp_path / "state.db", audit=tmp_path / "audit.jsonl"
    )
    ran: list[str] = []
    for event in ("A", "B"):

        def act(ob: Any, d: Any, event: str = event) -> None:
            ran.append(event)
            m.event(event)

        m.capability(event)(act)
    return m.start(), clock, ran


def interrupted(tmp_path: Path) -> list[tuple[int, str]]:
    return [
        (r["decision"], r["rule"])
        for r in read_audit(tmp_path / "audit.jsonl")
        if r["kind"] == "task-interrupted"
    ]


def test_the_allowed_part_cut_short_while_the_rest_is_held_is_recorded_and_the_rest_runs_once(
    tmp_path: Path,
) -> None:
    assert die_in(tmp_path, "B", 'm.event("Y"); m.event("X")') == ["B"]
    m, clock, ran = again(tmp_path, 1.0)
    assert interrupted(tmp_path) == [(2, "R1")]  # before: none, B lost without a word
    clock.set(31.0)
    m.tick()
    clock.set(100.0)
    m.tick()
    m.close()
    assert ran == ["A"]  # the held action, once allowed; B not again
    again(tmp_path, 101.0)[0].close()
    assert interrupted(tmp_path) == [(2, "R1")]  # said once, not at every restart


def test_the_held_part_cut_short_once_allowed_is_recorded_not_run_again(tmp_path: Path) -> None:
    started = die_in(tmp_path, "A", 'm.event("Y"); m.event("X"); clock.set(31.0); m.tick()')
    assert started == ["B", "A"]
    m, clock, ran = again(tmp_path, 31.0)
    clock.set(100.0)
    m.tick()
    m.close()
    assert ran == []  # before: A ran a second time
    assert interrupted(tmp_path) == [(2, "R1")]


def test_a_part_that_finished_before_the_kill_is_not_reported_interrupted(tmp_path: Path) -> None:
    started = die_in(tmp_path, "A", 'm.event("Y"); m.event("X")')  # killed after B's part finished
    assert started == ["B"]
    m, clock, ran = again(tmp_path, 1.0)
    assert interrupted(tmp_path) == []
    clock.set(31.0)
    m.tick()
    m.close()
    assert ran == ["A"]


def test_the_rest_of_a_decision_stopped_in_part_at_its_dispatch_is_recorded_when_cut_short(
    tmp_path: Path,
) -> None:
    # Y occurs between R1's decision and its dispatch (an observer): the dispatch stops A and
    # holds it, B runs as a part of the decision, and the kill cuts B short
    body = """
        def y_between(ev):
            if ev.kind == "decision" and ev.data["rule"] == "R1":
                m.event("Y")
        m.subscribe(y_between)
        m.event("X")
        """
    assert die_in(tmp_path, "B", body) == ["B"]
    m, clock, ran = again(tmp_path, 1.0)
    assert interrupted(tmp_path) == [(1, "R1")]  # before: none, B lost without a word
    clock.set(31.0)
    m.tick()
    m.close()
    assert ran == ["A"]
