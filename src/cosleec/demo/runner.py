"""Run the assistive-care scenario in one process and show what the runtime does.

Used by ``cosleec demo`` (a readable terminal display, or JSON lines with ``--json``) and by
the end-to-end tests, which check every decision against ``scenario.EXPECTED``.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from rich.console import Console
from rich.text import Text

from cosleec.demo.assistive_care import scenario, tasks
from cosleec.demo.player import Step, play
from cosleec.demo.watch import PACE_S, Served, Watch
from cosleec.runtime import AuditLog, Manager, RuntimeEvent, VirtualClock


def rules_path() -> str:
    """Path of the demo's ``rules.sleec`` in the installed package; give it to a Manager or a node."""
    return str(resources.files("cosleec.demo.assistive_care").joinpath("rules.sleec"))


@dataclass
class Run:
    """What :func:`run` leaves: the (closed) Manager, the simulated robot, every runtime event in order."""

    manager: Manager
    robot: tasks.Robot
    events: list[RuntimeEvent] = field(default_factory=list)

    def decisions(self) -> list[dict[str, Any]]:
        """The decision records (JSON form), in order, for ``scenario.outcomes``."""
        return [e.data for e in self.events if e.kind == "decision"]

    def records(self) -> list[dict[str, Any]]:
        """Every runtime event as a line of the Manager's audit log has it, for :func:`cosleec.demo.outcomes`.

        Written and read back as JSON, as the audit log does, so a record of this run and
        one of a Manager node's ``--audit`` file compare as equals.
        """
        return [
            json.loads(json.dumps({"kind": e.kind, "time": e.time, **e.data}, default=str))
            for e in self.events
        ]


def run(
    steps: list[Step] | None = None,
    *,
    semantics: str = "last-wins",
    audit: str | None = None,
    journal: str | None = None,
    reset_journal: bool = False,
    on_step: Callable[[float, Step], None] | None = None,
    on_event: Callable[[RuntimeEvent], None] | None = None,
    view: Callable[[Manager], Served] | None = None,
    on_start: Callable[[Manager], None] | None = None,
    before_close: Callable[[Manager], None] | None = None,
) -> Run:
    """Play ``steps`` (the scripted day by default) against an embedded Manager on a virtual clock.

    The demo's tasks are bound and checked first. Step kinds: ``set``, ``event``,
    ``advance`` (then a tick), ``request``, and ``fail``/``recover`` to make a robot action
    fail or work again. ``on_step(now, step)`` runs before each step, ``on_event`` for
    every runtime event; ``audit`` names a JSON Lines audit trail and ``journal`` the
    Manager's SQLite journal (state kept across runs and crashes: a journal a previous run
    left is restored first; ``reset_journal`` starts afresh from one the Manager refused).
    ``view(manager)`` attaches a live view before the Manager starts (``cosleec demo --web``
    gives the web view's, :meth:`Watch.attach`) and the view is closed before the Manager;
    ``on_start(manager)`` runs once it is started and
    ``before_close(manager)`` after the last step (the web demo serves on there). The Manager
    is closed before returning, even when a step or a hook raises (Ctrl-C).
    """
    clock = VirtualClock()
    manager = Manager.from_file(
        rules_path(),
        clock=clock,
        semantics=semantics,
        audit=AuditLog(audit) if audit else None,
        journal=journal,
        reset_journal=reset_journal,
    )
    robot = tasks.install(manager)
    served = _start(manager, view)
    result = Run(manager, robot)

    def observe(ev: RuntimeEvent) -> None:
        result.events.append(ev)
        if on_event is not None:
            on_event(ev)

    manager.subscribe(observe)
    try:
        if on_start is not None:
            on_start(manager)
        play(scenario.STEPS if steps is None else steps, _actions(manager, robot, clock), clock.now, on_step)
        if before_close is not None:
            before_close(manager)
    finally:
        _close(served, manager)
    return result


def _start(manager: Manager, view: Callable[[Manager], Served] | None) -> Served | None:
    """Attach the live view, if any (before the start: it hears start's records), then start
    the Manager; when either fails, the view is stopped (its port freed) and the Manager closed."""
    served = None
    try:
        served = view(manager) if view is not None else None
        manager.start()
    except BaseException:
        _close(served, manager)
        raise
    return served


def _close(view: Served | None, manager: Manager) -> None:
    """Stop the live view, if any (its port is free again), then close the Manager."""
    try:
        if view is not None:
            view.close()
    finally:
        manager.close()


def _actions(manager: Manager, robot: tasks.Robot, clock: VirtualClock) -> dict[str, Callable[[Any], object]]:
    """What each kind of scenario step does to the demo's Manager and robot (``advance``: the
    virtual clock moves on, then a tick)."""

    def advance(seconds: float) -> None:
        clock.advance(seconds)
        manager.tick()

    return {
        "set": manager.update,
        "event": manager.event,
        "advance": advance,
        "request": manager.request,
        "fail": robot.failing.add,
        "recover": robot.failing.discard,
    }


# ---------------------------------------------------------------------- terminal display


def _fmt(v: Any) -> str:
    return ("true" if v else "false") if isinstance(v, bool) else str(v)


class Display:
    """Prints the scenario as it runs: context, layers, decisions and obligation outcomes."""

    def __init__(self, console: Console) -> None:
        self.out = console
        self.time = 0.0

    def step(self, t: float, step: Step) -> None:
        """Print the heading of one scenario step at time ``t`` (seconds), with its note."""
        self.time = t
        kind, arg, note = step
        icon = {"set": "▶", "event": "⚡", "advance": "⏱", "request": "?"}.get(kind, "·")
        head = Text(f"t={t:>5g}s ", style="dim")
        if kind == "event":
            head.append(f"{icon} {arg}", style="bold magenta")
        elif kind == "advance":
            head.append(f"{icon} +{arg:g}s", style="bold blue")
        elif kind == "request":
            head.append(f"{icon} may the robot {arg}?", style="bold")
        else:
            head.append(f"{icon} ", style="bold")
        head.append(f"  {note}", style="italic")
        self.out.print()
        self.out.print(head)

    def event(self, ev: RuntimeEvent) -> None:
        """Print one runtime event; pending obligations and ``task-failed`` events are not shown."""
        d = ev.data
        pad = "        "
        if ev.kind == "context":
            vals = " ".join(f"{k}={_fmt(v) if v is not None else '?'}" for k, v in d["values"].items())
            self.out.print(Text(pad + "context  ", style="cyan") + Text(vals))
        elif ev.kind == "layers":
            sw = ", ".join(
                f"{s['rule']}: {s['from'] or 'default'} → {s['to'] or 'default'}" for s in d["switches"]
            )
            act = ", ".join(d["active"]) or "none (every rule at its default)"
            self.out.print(Text(pad + "layers   ", style="green") + Text(sw + "   active: " + act))
        elif ev.kind == "decision":
            where = (
                "default"
                if d["clause"] == 0
                else d["layer"] or ("undetermined" if d["clause"] is None else "")
            )
            if d["event"] == "otherwise":
                where = "otherwise"
            line = Text(pad + "decision ", style="bold yellow")
            line.append(f"{d['rule']} [{where}] ", style="bold")
            obs = " and ".join(
                ("not " if o["negated"] else "")
                + o["event"]
                + (f" within {o['within_s']:g}s" if o["within_s"] is not None else "")
                for o in d["obligations"]
            )
            line.append("→ " + (obs or "nothing required"))
            self.out.print(line)
            self.out.print(Text(pad + "  why: " + d["explanation"], style="dim"))
        elif ev.kind == "obligation" and d["status"] != "pending":
            mark = {"fulfilled": ("✔", "green"), "violated": ("✘", "bold red"), "respected": ("✔", "green")}
            icon, style = mark.get(d["status"], ("·", ""))
            what = ("not " if d["negated"] else "") + d["event"]
            late = f", late at {d['late'][-1]:g}s" if d["late"] else ""
            self.out.print(
                Text(pad + f"{icon} {what} {d['status']} ({d['rule']}, at {d['at']:g}s{late})", style=style)
            )
        elif ev.kind == "refused":
            self.out.print(Text(pad + f"⛔ {d['event']} refused by {', '.join(d['by'])}", style="bold red"))
        elif ev.kind == "rejected":
            self.out.print(Text(pad + f"rejected: {d['reason']}", style="red"))


def main(
    as_json: bool = False,
    semantics: str = "last-wins",
    audit: str | None = None,
    journal: str | None = None,
    reset_journal: bool = False,
    view: Callable[[Manager], Served] | None = None,
    pace: float = PACE_S,
    on_done: Callable[[Run], None] | None = None,
) -> int:
    """``cosleec demo``: play the scripted day and show it (``as_json``: one JSON line per runtime event).

    ``on_done`` is called with the finished :class:`Run` (``cosleec demo --plot`` draws it).

    ``view(manager)`` attaches the live web view (the CLI gives ``cosleec.views``' factory for
    ``--web PORT``) and paces the day (a step every ``pace`` seconds), then serves on until
    Ctrl-C (:mod:`cosleec.demo.watch`).
    Returns 0: checking the decisions against ``scenario.EXPECTED`` is the tests' job.
    """
    hooks: dict[str, Any] = {"reset_journal": True} if reset_journal else {}
    watch = None
    if view is not None:
        watch = Watch(
            pace, lambda line: print(line, file=sys.stderr if as_json else sys.stdout, flush=True), view
        )
        hooks |= {"view": watch.attach, "on_start": watch.started, "before_close": watch.linger}
    if as_json:

        def emit(ev: RuntimeEvent) -> None:
            print(json.dumps({"kind": ev.kind, "time": ev.time, **ev.data}, default=str), flush=True)

        paced = watch.step if watch is not None else None
        done = run(semantics=semantics, audit=audit, journal=journal, on_step=paced, on_event=emit, **hooks)
        if on_done is not None:
            on_done(done)
        return 0
    console = Console(highlight=False)
    console.print(
        Text("cosleec demo: an assistive-care robot under SLEEC rules (virtual time)", style="bold")
    )
    console.print(Text(f"rules: {rules_path()}   semantics: {semantics}", style="dim"))
    display = Display(console)

    def step(t: float, s: Step) -> None:
        display.step(t, s)
        if watch is not None:
            watch.step(t, s)

    result = run(
        semantics=semantics, audit=audit, journal=journal, on_step=step, on_event=display.event, **hooks
    )
    _summary(console, result.manager, audit)
    if on_done is not None:
        on_done(result)
    return 0


def _summary(console: Console, m: Manager, audit: str | None) -> None:
    """The last lines of the terminal display: what the day came to, and where its audit trail is."""
    console.print()
    s = m.stats
    console.print(
        Text(
            f"{s['decisions']} decisions, {s['violations']} violations, {s['refused']} refused actions, "
            f"{len(m.outstanding())} obligations outstanding",
            style="bold",
        )
    )
    if audit:
        console.print(Text(f"audit trail: {audit}", style="dim"))
