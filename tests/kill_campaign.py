"""A kill -9 campaign: a scripted day against a Manager with a journal, killed at random points.

The day is played by a *life*: a process that opens the Manager (journal, audit log, a
VirtualClock), resumes the script where the last life stopped, and plays it to the end
unless it is killed with SIGKILL first. The parent (``tests/unit/runtime/test_kill_campaign.py``)
starts lives until one finishes the day, then compares the outcome with references run in
its own process. Run as ``python -m tests.kill_campaign CONFIG_JSON`` it is one life.

What a life writes besides the Manager's files, to ``progress.jsonl`` (one JSON object a
line, each with a single ``write(2)`` on an ``O_APPEND`` descriptor: a SIGKILL cannot lose
a line already written, and can at worst leave the last line torn, which readers skip):

- ``life``: a life started (run id, the step it resumes at, its clock);
- ``begin i`` before step ``i`` (with the last audit ``seq`` and the run id), ``done i``
  after it (with the kill points passed so far), ``answer i`` for a request step;
- ``cap start|done|skip`` around every capability call (decision id, event, outcome);
- ``dying``: the kill point about to kill this life; ``end``: the day is over.

**Replaying the step a kill interrupted.** A life resumes at the first step with no
``done`` line. If that step had begun, its state change may or may not be committed: the
Manager commits a step's effect (the event with its decisions and obligations, a refusal,
new measure values) in one journal transaction, *before* any implementation runs. So the
step was applied exactly when the run that began it committed some audit record after
the ``seq`` noted in ``begin`` -- which the new life can see, because opening the Manager
leaves in the audit log exactly the records the journal committed (the Manager writes a
step's records, then commits the step with the log's length; records past it are set
aside to ``audit.jsonl.uncommitted``, a torn line to ``audit.jsonl.torn``). An applied step is not
played again (its implementations are the Manager's business: an interrupted one is
recorded ``task-interrupted`` and not run again); a step with no committed record is
played again, which is harmless (a request that was allowed records nothing, setting
values no update applied changes nothing). ``advance`` steps move the clock to an
absolute time (``clock.set``) and tick, so playing one again is idempotent; a life that
resumes inside an ``advance`` starts its clock at the step's end, since the Manager may
already have committed at that time (a clock that starts earlier than the journal's last
commit would shift every saved window).

**What a kill may legitimately change.** Implementations are at-most-once: a capability
the kill cut short is not run again. The robot of these days reports what it did to the
Manager (it asks ``request(E)``, then reports ``event(E)``), so a lost action changes the
rest of the day (an obligation not fulfilled, a rule not triggered). The comparison
therefore uses two references, both run in the parent's process on the same script:
*uninterrupted* (no kill) and *with the same losses* (a capability call runs only if the
killed run made it -- it reported its event or its refusal, or finished). The killed day
must equal the second record for record, and every call it lost must be named by a
``task-interrupted`` record; when nothing was lost, the two references are the same run.

**Damaged files** (:data:`CORRUPTIONS`): a kill leaves the commits of the killed life in
``state.db-wal`` only. Deleted, truncated or with a byte changed, that file (or the ``.db``
truncated, or an old copy of both put back) makes SQLite open an older or an empty journal
without a word; the next life must be refused (JournalError naming the files), never start
from less than was committed, and with ``"reset": true`` in its configuration
(``Manager(..., reset_journal=True)``) start afresh after a ``journal-reset`` record.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import threading
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosleec.errors import UserError
from cosleec.runtime import AuditLog, Decision, Journal, Manager, Obligation, VirtualClock
from cosleec.runtime.journal import Change, _Background

ROOT = Path(__file__).resolve().parent.parent

Step = tuple[str, Any, str]
Record = dict[str, Any]

#: kill points a life passes; the parent picks one (and how many passes to let by) per life.
#: "timer" is the parent's: SIGKILL from outside after a random delay.
POINTS = (
    "in-step",  # a step began (its ``begin`` line is written), nothing of it done yet
    "between-steps",  # a step is done and noted, the next not begun
    "cap-entry",  # inside a capability, before it asks for its action
    "cap-allowed",  # inside a capability, its action allowed but not yet reported
    "cap-exit",  # inside a capability, its action reported (or refused), not yet returned
    "journal-before",  # a step's commit is about to start
    "journal-inside",  # inside the SQLite transaction of a commit (a progress handler)
    "journal-after",  # committed to the journal (its records already in the audit log)
    "audit-partial",  # part of a step's audit records written: the last line torn
    "audit-after",  # the audit records written, the step not yet over
    "checkpoint",  # the journal's checkpointer (its thread) copying the WAL: killed 0-8 ms into a round
)
RECOVERY = ("restored", "task-interrupted", "dropped", "uncommitted")  # records only a restart makes


# ---------------------------------------------------------------------- the days


@dataclass(frozen=True)
class Day:
    """A scripted day: rules, steps, and the events the robot only asks the user for."""

    name: str
    rules: str  # SLEEC text
    steps: list[Step]
    user_events: frozenset[str]

    def to_json(self) -> dict[str, Any]:
        """What a life reads from ``day.json``."""
        return {
            "name": self.name,
            "rules": self.rules,
            "steps": self.steps,
            "user_events": sorted(self.user_events),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Day:
        """The day a parent wrote with :meth:`to_json`."""
        steps: list[Step] = [(str(kind), arg, str(note)) for kind, arg, note in d["steps"]]
        return cls(d["name"], d["rules"], steps, frozenset(d["user_events"]))


WARD_RULES = """def_start
 event Shift event Patrol event Check event Log
 event Alarm event Ack event Escalate event Page
 event Visitor event Photo event Alert
 event Door event Lock event Tour
 event Call event Answer event Note event Callback
 measure night : boolean
 measure consent : boolean
 measure staff : numeric
def_end
rule_start
 W1 when Shift then Patrol within 30 seconds and Check within 1 minutes
   unless {night} then Patrol within 10 seconds
 W2 when Patrol then Log within 20 seconds
 W3 when Alarm then Ack within 1 minutes otherwise Escalate within 30 seconds otherwise Page within 10 seconds
 W4 when Visitor then not Photo within 5 minutes
   unless {consent}
 W5 when Alert then Photo within 10 seconds
 W6 when Door and ({staff} < 2) then Lock within 10 seconds
   unless {night} then Lock within 5 seconds and Alert within 5 seconds
 W7 when Tour then Photo within 10 minutes and Log within 20 seconds
 W8 when Call then Answer within 10 seconds else {Note within 1 minutes and Callback within 1 minutes}
rule_end
"""

#: a purpose-built day: two obligations per decision, a chain of rules triggered by the
#: robot's own actions, an ``otherwise`` whose fallback is missed too (a second
#: ``otherwise``), a late event, a prohibition that refuses requests (the driver's and the
#: robot's own) and one broken anyway, an undetermined decision, a failing action,
#: a decision dispatched in parts (one action runs at once, the other is held until allowed),
#: an ``else`` met in two events (a kill between them must not forget the first)
WARD_STEPS: list[Step] = [
    ("set", {"night": False, "consent": False}, "day shift, no consent to photos, staffing unknown"),
    ("event", "Shift", "W1: patrol (W2: log it) and check"),
    ("event", "Alarm", "W3: the user must acknowledge within a minute"),
    ("fail", "Escalate", "the escalation line is down"),
    ("advance", 70, "no acknowledgement: otherwise escalate (which fails)"),
    ("advance", 25, "escalation missed too: otherwise page (in time)"),
    ("event", "Ack", "the acknowledgement comes late"),
    ("recover", "Escalate", "the line is back"),
    ("event", "Visitor", "W4: no photos for 5 minutes"),
    ("request", "Photo", "a visitor asks for a photo: refused"),
    ("event", "Door", "W6: staffing unknown, undetermined"),
    ("set", {"staff": 1}, "one member of staff"),
    ("event", "Door", "W6: lock within 10 seconds"),
    ("set", {"night": True}, "night falls"),
    ("event", "Door", "W6.1: lock and alert (W5: photo, refused by W4)"),
    ("event", "Shift", "W1.1: patrol within 10 seconds"),
    ("advance", 30, "W5's photo is missed"),
    ("request", "Photo", "refused again"),
    ("event", "Photo", "a photo is taken anyway: W4 is violated"),
    ("event", "Door", "W6.1 again: lock and alert; the photo is allowed now"),
    ("set", {"consent": True}, "consent given"),
    ("event", "Visitor", "W4.1: no prohibition"),
    ("request", "Photo", "allowed"),
    ("event", "Alarm", "W3 again"),
    ("event", "Ack", "acknowledged in time"),
    ("set", {"consent": False}, "consent withdrawn"),
    ("event", "Visitor", "W4: no photos again"),
    ("event", "Tour", "W7: log at once; the photo is held until W4's ban ends (a decision in parts)"),
    ("request", "Photo", "refused: the prohibition counts its refusals"),
    ("event", "Call", "W8: the user should answer within 10 seconds, else a note and a call back"),
    ("event", "Note", "a note: one item of W8's else met, the obligation still pending"),
    ("advance", 20, "no answer: W8's own window closes, its else still open"),
    ("event", "Callback", "the call back completes W8's else: fulfilled"),
    ("advance", 400, "end of the day: every window closes, the prohibition was respected"),
]


def ward_day() -> Day:
    """The purpose-built day (:data:`WARD_STEPS`)."""
    return Day("ward", WARD_RULES, WARD_STEPS, frozenset({"Ack", "Answer"}))


def assistive_care_day() -> Day:
    """The demo's scripted day on the demo's rules (``cosleec demo``), played by this module's robot."""
    from cosleec.demo import rules_path
    from cosleec.demo.assistive_care import scenario
    from cosleec.demo.assistive_care.tasks import USER_EVENTS

    return Day("assistive-care", Path(rules_path()).read_text(encoding="utf-8"), scenario.STEPS, USER_EVENTS)


def schedule(steps: list[Step], start: float = 0.0) -> list[float]:
    """The clock time at which each step starts; one more entry: the time the day ends."""
    out = [start]
    for kind, arg, _ in steps:
        out.append(out[-1] + (float(arg) if kind == "advance" else 0.0))
    return out


def flatten(day: Day) -> list[Step]:
    """Every input the Manager of the uninterrupted day receives, in order: the script's and the robot's.

    For a Manager node, which only decides: the robot's requests and reports become steps
    of the script, so the day has the same decisions and outcomes without any task
    reporting (``advance`` steps stay relative; ``fail``/``recover`` are gone, their effect
    is in the robot's steps).
    """
    out: list[Step] = []
    clock = VirtualClock(0.0)
    m = Manager.from_text(day.rules, clock=clock)
    failing: set[str] = set()

    def capability(event: str) -> Callable[[Obligation, Decision], None]:
        def perform(ob: Obligation, d: Decision) -> None:
            if event in day.user_events or event in failing:
                return
            out.append(("request", event, f"the robot asks before {event} (decision {d.id})"))
            if m.request(event):
                out.append(("event", event, f"the robot reports {event} (decision {d.id})"))
                m.event(event)

        return perform

    for event in sorted(m.ruleset.responds):
        m.capability(event)(capability(event))
    m.start()
    for kind, arg, note in day.steps:
        if kind in ("set", "event", "request", "advance"):
            out.append((kind, arg, note))  # before the call: what the robot does during it comes after
        if kind == "set":
            m.update(arg)
        elif kind == "event":
            m.event(arg)
        elif kind == "request":
            m.request(arg)
        elif kind == "advance":
            clock.advance(float(arg))
            m.tick()
        elif kind == "fail":
            failing.add(arg)
        elif kind == "recover":
            failing.discard(arg)
    m.close()
    return out


# ---------------------------------------------------------------------- side files


class Progress:
    """The life's side file: one JSON object a line, each written by one ``write(2)``."""

    def __init__(self, path: Path) -> None:
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def __call__(self, record: Mapping[str, Any]) -> None:
        os.write(self.fd, (json.dumps(record, separators=(",", ":")) + "\n").encode())

    def close(self) -> None:
        os.close(self.fd)


def read_lines(path: Path) -> list[Record]:
    """The whole lines of a JSON Lines file (a torn last line, which a kill may leave, is skipped)."""
    if not path.exists():
        return []
    text = path.read_text(encoding="utf-8")
    return [json.loads(line) for line in text.split("\n")[:-1]]


# ---------------------------------------------------------------------- one life


@dataclass(frozen=True)
class Plan:
    """Where a life is killed: at the ``hit``-th pass of kill point ``point``.

    ``ops`` chooses inside the point: the SQLite instructions a ``journal-inside`` kill lets
    run, the characters of its records an ``audit-partial`` kill writes.
    """

    point: str
    hit: int
    ops: int = 1

    def to_json(self) -> dict[str, Any]:
        """Its JSON form, for a life's configuration."""
        return {"point": self.point, "hit": self.hit, "ops": self.ops}


class Killer:
    """Counts the kill points a life passes; kills the life (SIGKILL) at the one its :class:`Plan` names."""

    def __init__(self, plan: Plan | None, log: Progress) -> None:
        self.plan = plan
        self.log = log
        self.hits: Counter[str] = Counter()

    def armed(self, point: str) -> bool:
        """Count a pass of ``point``; True when the plan kills here (the caller chooses how)."""
        self.hits[point] += 1
        return self.plan is not None and self.plan.point == point and self.hits[point] == self.plan.hit

    def point(self, point: str) -> None:
        """Count a pass of ``point`` and die there if the plan says so."""
        if self.armed(point):
            self.die(point)

    def die(self, where: str) -> None:
        """Note where, then SIGKILL this process."""
        self.log({"k": "dying", "point": where, "hit": self.hits[where.split(" ")[0]]})
        os.kill(os.getpid(), signal.SIGKILL)


class KillingJournal(Journal):
    """A journal whose commits pass kill points: before, inside the SQLite transaction, after;
    and whose checkpointer runs a round after every commit (and starts the WAL afresh past a
    few pages, or copies the rest with commits held back past a few more), so that a life
    meets every path of it, and dies in the middle of one (``checkpoint``) -- in the lives
    killed there, by the timer, and the lives that end the day."""

    checkpoint_commits = 1
    checkpoint_idle = 0.005
    checkpoint_restart = 8
    checkpoint_limit = 24

    def __init__(self, path: Path, killer: Killer) -> None:
        super().__init__(path)
        self.killer = killer
        if killer.plan is not None and killer.plan.point != "checkpoint":
            # a life planned to die elsewhere copies the WAL only as the default does after
            # ``checkpoint_commits`` commits, or past twice ``checkpoint_limit`` pages (more
            # than a life makes) -- as SQLite did, after 1000 pages: a damaged -wal file then
            # loses the commits of several steps, and must be refused (a WAL copied after
            # every commit holds one step at most, and losing it is rightly taken for a kill
            # before its commit)
            self.checkpoint_idle = 3600.0
            for name in ("checkpoint_commits", "checkpoint_restart", "checkpoint_limit"):
                setattr(self, name, getattr(Journal, name))

    def commit(self, change: Change, meta: Mapping[str, Any], clock: float) -> None:
        """Commit one step, passing the kill points around and inside it."""
        self.killer.point("journal-before")
        inside = self.killer.armed("journal-inside")
        if inside:
            assert self.killer.plan is not None
            # the connection is the journal's own: a progress handler runs inside its statements
            self._db.set_progress_handler(lambda: self.killer.die("journal-inside"), self.killer.plan.ops)
        super().commit(change, meta, clock)
        if inside:  # the commit took fewer instructions than chosen: die just after it
            self.killer.die("journal-inside (after the commit)")
        self.killer.point("journal-after")

    def _checkpoint(self, bg: _Background) -> None:
        """A round of the checkpointer; the chosen one dies ``ops % 8000`` microseconds into it
        (its fsyncs take milliseconds: most such kills land inside the checkpoint, or its restart)."""
        if (bg.commits != bg.copied or bg.frames) and self.killer.armed("checkpoint"):  # a round with work
            assert self.killer.plan is not None
            delay = (self.killer.plan.ops % 8000) / 1e6
            threading.Timer(delay, self.killer.die, ("checkpoint",)).start()
        super()._checkpoint(bg)


class KillingAuditLog(AuditLog):
    """An audit log whose writes pass kill points; ``seq`` is the last record written or found
    (after a restart set records aside, the last kept)."""

    def __init__(self, path: Path, killer: Killer) -> None:
        super().__init__(path)
        self.killer = killer
        if killer.plan is not None and killer.plan.point != "checkpoint":
            # a life planned to die elsewhere copies the WAL only as the default does after
            # ``checkpoint_commits`` commits, or past twice ``checkpoint_limit`` pages (more
            # than a life makes) -- as SQLite did, after 1000 pages: a damaged -wal file then
            # loses the commits of several steps, and must be refused (a WAL copied after
            # every commit holds one step at most, and losing it is rightly taken for a kill
            # before its commit)
            self.checkpoint_idle = 3600.0
            for name in ("checkpoint_commits", "checkpoint_restart", "checkpoint_limit"):
                setattr(self, name, getattr(Journal, name))
        self.seq = self.last_seq

    def write_lines(self, lines: Iterable[str]) -> int:
        """Write records (JSON texts), unless the plan tears them: part written, then SIGKILL."""
        lines = list(lines)
        if lines and self.killer.armed("audit-partial"):
            assert self.killer.plan is not None
            text = "".join(f"{line}\n" for line in lines)
            cut = 1 + self.killer.plan.ops % (len(text) - 1)  # never all of it
            with self.path.open("a", encoding="utf-8") as fh:
                fh.write(text[:cut])
            self.killer.die("audit-partial")
        end = super().write_lines(lines)
        if lines:
            self.seq = max(self.seq, int(json.loads(lines[-1])["seq"]))
            self.killer.point("audit-after")
        return end

    def cut(self, at: int) -> list[dict[str, Any]]:
        """Set aside what a restart finds uncommitted; ``seq`` goes back to the last record kept.

        Otherwise a ``begin`` line would name a ``seq`` the log no longer reaches, records
        this life commits could carry a ``seq`` below it, and the next life would play again
        a step this one applied (seed 2521208213).
        """
        records = super().cut(at)
        self.seq = self.last_seq
        return records


def committed_after(records: list[Record], run: str, seq: int) -> list[Record]:
    """The records run ``run`` committed after record ``seq``."""
    return [r for r in records if r.get("run") == run and r["seq"] > seq]


def live(
    workdir: Path, plan: Plan | None = None, only: set[tuple[int, str]] | None = None, reset: bool = False
) -> None:
    """One life: open the Manager in ``workdir``, resume the day, play it to the end (unless killed).

    ``only`` (the references) runs just the capability calls ``(decision, event)`` it holds;
    ``reset`` opens the journal with ``reset_journal=True`` (after a damaged journal was refused).
    """
    day = Day.from_json(json.loads((workdir / "day.json").read_text(encoding="utf-8")))
    steps = day.steps
    times = schedule(steps)
    past = read_lines(workdir / "progress.jsonl")
    log = Progress(workdir / "progress.jsonl")
    killer = Killer(plan, log)
    done = {int(r["step"]) for r in past if r["k"] == "done"}
    i = 0
    while i in done:
        i += 1
    begins = [r for r in past if r["k"] == "begin"]
    begun = begins[-1] if begins and begins[-1]["step"] == i else None
    resume_in_advance = begun is not None and steps[i][0] == "advance"
    clock = VirtualClock(times[i + 1] if resume_in_advance else times[i])
    audit = KillingAuditLog(workdir / "audit.jsonl", killer)
    m = Manager.from_file(
        workdir / "rules.sleec",
        clock=clock,
        journal=KillingJournal(workdir / "state.db", killer),
        audit=audit,
        **({"reset_journal": True} if reset else {}),
    )
    log({"k": "life", "run": m.run_id, "from": i, "clock": clock.now(), "pid": os.getpid()})
    failing: set[str] = set()

    def world(kind: str, arg: Any) -> None:
        if kind == "fail":
            failing.add(arg)
        elif kind == "recover":
            failing.discard(arg)

    for kind, arg, _ in steps[:i]:  # the robot's state is the script's, not the Manager's
        world(kind, arg)

    def capability(event: str) -> Callable[[Obligation, Decision], None]:
        def perform(ob: Obligation, d: Decision) -> None:
            key = {"decision": d.id, "event": event}
            if only is not None and (d.id, event) not in only:
                log({"k": "cap", "phase": "skip", **key})
                return
            log({"k": "cap", "phase": "start", **key, "seq": audit.seq, "run": m.run_id})
            killer.point("cap-entry")
            if event in day.user_events:
                outcome = "asked the user"
            elif event in failing:
                outcome = "failed"
            elif not m.request(event):
                outcome = "refused"
            else:
                killer.point("cap-allowed")
                m.event(event)
                outcome = "done"
            killer.point("cap-exit")
            log({"k": "cap", "phase": "done", **key, "outcome": outcome})

        return perform

    for event in sorted(m.ruleset.responds):
        m.capability(event)(capability(event))
    if begun is not None and not resume_in_advance:
        applied = committed_after(read_lines(workdir / "audit.jsonl"), begun["run"], begun["seq"])
        if applied:  # the step's state change was committed before the kill: not again
            if steps[i][0] == "request":
                log({"k": "answer", "step": i, "allowed": False, "from": "audit"})
            log({"k": "done", "step": i, "hits": dict(killer.hits), "applied": "before the kill"})
            i += 1
    m.start()
    for j in range(i, len(steps)):
        kind, arg, _ = steps[j]
        log({"k": "begin", "step": j, "seq": audit.seq, "run": m.run_id})
        killer.point("in-step")
        if kind == "set":
            m.update(arg)
        elif kind == "event":
            m.event(arg)
        elif kind == "request":
            log({"k": "answer", "step": j, "allowed": m.request(arg).permitted})
        elif kind == "advance":
            clock.set(times[j + 1])
            m.tick()
        else:
            world(kind, arg)
        log({"k": "done", "step": j, "hits": dict(killer.hits)})
        killer.point("between-steps")
    log({"k": "end", "run": m.run_id})
    m.close()
    log.close()


# ---------------------------------------------------------------------- the parent: lives and references


@dataclass
class Played:
    """What a day left in its directory: the audit log, the side file, and the directory."""

    dir: Path
    records: list[Record]
    progress: list[Record]

    @classmethod
    def load(cls, workdir: Path) -> Played:
        """Read a day's files (after its last life ended)."""
        return cls(workdir, read_lines(workdir / "audit.jsonl"), read_lines(workdir / "progress.jsonl"))

    def steps_done(self) -> int:
        """How many steps are done: the step the next life resumes at."""
        done = {int(r["step"]) for r in self.progress if r["k"] == "done"}
        i = 0
        while i in done:
            i += 1
        return i

    def hits_before(self, step: int) -> Counter[str]:
        """The kill points passed before ``step`` (in a run of one life: the uninterrupted reference)."""
        out: Counter[str] = Counter()
        for r in self.progress:
            if r["k"] == "done" and r["step"] < step:
                out = Counter(r["hits"])
        return out


def prepare(day: Day, workdir: Path) -> Path:
    """A fresh directory holding the day (``day.json``) and its rules."""
    workdir.mkdir(parents=True)
    (workdir / "day.json").write_text(json.dumps(day.to_json()), encoding="utf-8")
    (workdir / "rules.sleec").write_text(day.rules, encoding="utf-8")
    return workdir


def reference(day: Day, workdir: Path, only: set[tuple[int, str]] | None = None) -> Played:
    """The day played in this process by one life that is never killed (``only``: see :func:`live`)."""
    live(prepare(day, workdir), None, only)
    return Played.load(workdir)


def calls_made(played: Played) -> set[tuple[int, str]]:
    """The capability calls ``(decision, event)`` a killed day made: each that finished, and each
    cut short after its request was refused or its event reported (the first record its run
    committed after the call began says which)."""
    started: dict[tuple[int, str], Record] = {}
    finished: set[tuple[int, str]] = set()
    for r in played.progress:
        if r["k"] == "cap":
            key = (int(r["decision"]), str(r["event"]))
            if r["phase"] == "start":
                started[key] = r
            elif r["phase"] == "done":
                finished.add(key)
    out = set(finished)
    for key, r in started.items():
        if key not in finished:
            after = committed_after(played.records, r["run"], r["seq"])
            if after and after[0]["kind"] in ("event", "refused") and after[0]["event"] == key[1]:
                out.add(key)
    return out


def final_obligations(records: list[Record]) -> dict[int, tuple[Any, ...]]:
    """Each obligation's last record, as (rule, event, negated, start, window, status, at, by, late)."""
    out: dict[int, tuple[Any, ...]] = {}
    for r in records:
        if r["kind"] == "obligation":
            out[int(r["id"])] = (
                r["rule"],
                r["event"],
                r["negated"],
                r["start"],
                tuple(r["window"]),
                r["status"],
                r["at"],
                r["by"],
                tuple(r["late"]),
            )
    return out


def answers(played: Played) -> dict[int, list[bool]]:
    """The answers to each request step, as many as were given (a step played again answers again)."""
    out: dict[int, list[bool]] = {}
    for r in played.progress:
        if r["k"] == "answer":
            out.setdefault(int(r["step"]), []).append(bool(r["allowed"]))
    return out


def unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose names are all different (``json.loads`` would keep the last of two)."""
    names = [k for k, _ in pairs]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate names {sorted(k for k in set(names) if names.count(k) > 1)}")
    return dict(pairs)


def verify(day: Day, killed: Played, plain: Played, same: Played) -> dict[str, Any]:
    """Check a killed day against the uninterrupted run (``plain``) and the run with its losses
    (``same``); AssertionError listing every problem. Returns what the day lost and recovered."""
    from cosleec.demo import first_difference, outcomes

    problems: list[str] = []
    # (d) every audit line whole JSON (each name once), and seq exactly 1..N
    raw = (killed.dir / "audit.jsonl").read_bytes()
    if not raw.endswith(b"\n"):
        problems.append("the audit log does not end with a whole line")
    lines = raw.split(b"\n")[:-1]
    seqs = []
    for n, line in enumerate(lines, 1):
        try:
            seqs.append(json.loads(line, object_pairs_hook=unique)["seq"])
        except (ValueError, KeyError) as e:
            problems.append(f"audit line {n} is not a whole record: {e}: {line[:120]!r}")
    if seqs != list(range(1, len(seqs) + 1)):
        dup = sorted(s for s, c in Counter(seqs).items() if c > 1)
        gap = sorted(set(range(1, max(seqs, default=0) + 1)) - set(seqs))
        problems.append(f"audit seq is not 1..{len(seqs)}: duplicated {dup[:10]}, missing {gap[:10]}")
    torn_path = killed.dir / "audit.jsonl.torn"
    torn = torn_path.read_text(encoding="utf-8").splitlines() if torn_path.exists() else []
    aside_path = killed.dir / "audit.jsonl.uncommitted"
    aside = (
        [json.loads(x) for x in aside_path.read_text(encoding="utf-8").splitlines()]
        if aside_path.exists()
        else []
    )
    for rec in aside:  # set aside: the records of a step whose commit never happened
        if int(rec["seq"]) > len(seqs) + 1:
            problems.append(f"an uncommitted record's seq {rec['seq']} is past the log's end ({len(seqs)})")
    # the script: every step done exactly once, the day over once
    done = Counter(int(r["step"]) for r in killed.progress if r["k"] == "done")
    if sorted(done) != list(range(len(day.steps))) or any(c != 1 for c in done.values()):
        problems.append(f"steps done: {sorted(done.items())}")
    if sum(r["k"] == "end" for r in killed.progress) != 1:  # (a kill after `end` ends the day all the same)
        problems.append("the day did not end exactly once")
    # (b) at most once: no capability call started twice, no otherwise decided twice
    calls = Counter(
        (int(r["decision"]), str(r["event"]))
        for r in killed.progress
        if r["k"] == "cap" and r["phase"] == "start"
    )
    twice = sorted(k for k, c in calls.items() if c > 1)
    if twice:
        problems.append(f"capability calls run more than once: {twice}")
    fallbacks = Counter(
        int(r["violated"]) for r in killed.records if r["kind"] == "decision" and r["event"] == "otherwise"
    )
    if any(c > 1 for c in fallbacks.values()):
        problems.append(
            f"otherwise decided more than once for obligations {sorted(k for k, c in fallbacks.items() if c > 1)}"
        )
    interrupted = {int(r["decision"]) for r in killed.records if r["kind"] == "task-interrupted"}
    lost = sorted(
        (int(r["decision"]), str(r["event"]))
        for r in same.progress
        if r["k"] == "cap" and r["phase"] == "skip"
    )
    unexplained = [k for k in lost if k[0] not in interrupted]
    if unexplained:
        problems.append(f"capability calls lost with no task-interrupted record: {unexplained}")
    # (a) no obligation lost: every obligation, its window and its outcome, as in the run with the same losses
    mine, theirs = final_obligations(killed.records), final_obligations(same.records)
    if mine != theirs:
        diff = [
            (k, theirs.get(k), mine.get(k))
            for k in sorted(mine.keys() | theirs.keys())
            if mine.get(k) != theirs.get(k)
        ]
        problems.append(f"obligations differ (id, expected, got): {diff[:5]}")
    if not lost and mine != final_obligations(plain.records):
        problems.append("nothing was lost, yet the obligations differ from the uninterrupted run")
    end = schedule(day.steps)[-1]
    pending = sorted(
        k for k, v in mine.items() if v[5] == "pending" and v[4][1] is not None and v[4][1] < end
    )
    if pending:  # (an obligation the kills left undone may still be pending, its deadline after the day)
        problems.append(f"obligations whose deadline passed never settled: {pending}")
    # (c) no forbidden action allowed: the answers, and no prohibition broken that the uninterrupted run kept
    got, want, plain_answers = answers(killed), answers(same), answers(plain)
    for step, said in sorted(got.items()):
        if len(set(said)) != 1 or [said[0]] != want.get(step):
            problems.append(
                f"request step {step} answered {said}, the run with the same losses {want.get(step)}"
            )
        if plain_answers.get(step) == [False] and said and said[0]:
            problems.append(f"request step {step} was allowed; the uninterrupted run refused it")
    if sorted(got) != sorted(want):
        problems.append(f"request steps answered: {sorted(got)}, expected {sorted(want)}")
    broken = Counter(v[:5] for v in mine.values() if v[2] and v[5] == "violated")
    kept = Counter(v[:5] for v in final_obligations(plain.records).values() if v[2] and v[5] == "violated")
    if broken - kept:
        problems.append(f"prohibitions broken that the uninterrupted run kept: {sorted(broken - kept)}")
    # and the whole record stream, normalised as the demo compares runs
    difference = first_difference(
        outcomes(r for r in same.records if r["kind"] not in RECOVERY),
        outcomes(r for r in killed.records if r["kind"] not in RECOVERY),
    )
    if difference is not None:
        problems.append("the record stream differs from the run with the same losses: " + difference)
    assert not problems, f"{day.name} in {killed.dir}:\n- " + "\n- ".join(problems)
    return {
        "lost": len(lost),
        "interrupted": len(interrupted),
        "torn": len(torn),
        "records": len(seqs),
        "restarts": sum(r["kind"] == "restored" and r.get("from") is not None for r in killed.records),
    }


# ---------------------------------------------------------------------- damaged files


def _flip(path: Path, at: int) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))


def _truncate(path: Path, size: int) -> None:
    os.truncate(path, size)


def _put_back(workdir: Path) -> None:
    for name in ("state.db", "state.db-wal"):
        shutil.copyfile(workdir / "old" / name, workdir / name)


#: what can happen to a killed life's journal, each a function of its directory (an old copy of
#: ``state.db`` and ``state.db-wal`` is in ``old/``, taken after the life before it was killed)
CORRUPTIONS: dict[str, Callable[[Path], None]] = {
    "wal deleted": lambda d: (d / "state.db-wal").unlink(),
    "wal truncated to 0": lambda d: _truncate(d / "state.db-wal", 0),
    "wal truncated to half": lambda d: _truncate(
        d / "state.db-wal", (d / "state.db-wal").stat().st_size // 2
    ),
    "wal header flipped": lambda d: _flip(d / "state.db-wal", 24),  # its checksum: the whole file is ignored
    "wal frame flipped": lambda d: _flip(d / "state.db-wal", (d / "state.db-wal").stat().st_size // 3),
    "db truncated to 0": lambda d: _truncate(d / "state.db", 0),
    "journal older than the log": _put_back,
}


def keep_old(workdir: Path) -> None:
    """Copy the journal's files (a killed life's) to ``old/``: the backup an operator might put back."""
    (workdir / "old").mkdir(exist_ok=True)
    for name in ("state.db", "state.db-wal"):
        shutil.copyfile(workdir / name, workdir / "old" / name)


def main(argv: list[str]) -> int:
    """``python -m tests.kill_campaign '{"dir": ..., "plan": ...}'``: one life."""
    config = json.loads(argv[0])
    plan = Plan(**config["plan"]) if config.get("plan") else None
    try:
        live(Path(config["dir"]), plan, reset=bool(config.get("reset")))
    except UserError as e:  # a journal refused: said as the command line says it, with its hint
        print(f"{type(e).__name__}: {e.render()}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
