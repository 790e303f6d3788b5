"""The kill -9 campaign, embedded: a scripted day, the Manager killed with SIGKILL at random
points, restarted each time, and the outcome checked against an uninterrupted run.

Each life of the day is a process (``python -m tests.kill_campaign``, see that module for
the driver, its side file and why replaying an interrupted step is safe) running an
embedded Manager with a journal and an audit log on a VirtualClock. The parent picks
where each life dies -- in a step or between steps, inside a capability (before it asks,
after it was allowed, after it acted), before, inside (a SQLite progress handler) or
after a journal commit, in the middle of writing the audit log (a torn line), after it,
during the restore of a previous kill, or from outside after a random delay -- and
restarts lives until one ends the day. Then it checks, against the uninterrupted run and
the run with the same at-most-once losses (:func:`tests.kill_campaign.verify`):

(a) no obligation lost: every obligation, its window and its final outcome are the same;
(b) no capability call, ``otherwise`` fallbacks included, ran twice, no ``otherwise`` was
    decided twice, and every call the kills lost is named by a ``task-interrupted`` record;
(c) no request the uninterrupted run refused was allowed, and no prohibition it kept was broken;
(d) every audit line is whole JSON and ``seq`` runs 1..N, each once (a torn line is set
    aside and its record written again, whole).
The whole normalised record stream must equal the run with the same losses, record by record.

Two days: the purpose-built ward day and the demo's assistive-care day. ``COSLEEC_KILLS``
kills for each (5 by default, in one day; ``COSLEEC_KILLS=200`` for a long run, at most 6
a day, about 90 s a day-kind on one core), seeded by ``COSLEEC_KILL_SEED`` (fixed by
default, ``random`` for a fresh one; printed either way, with where each kill landed).

Damaged files (:data:`tests.kill_campaign.CORRUPTIONS`: the ``-wal`` file deleted, truncated
or with a byte changed, the ``.db`` truncated, an old copy of both put back) after a kill:
the next life is refused with a JournalError naming the files, never started from less than
was committed; with ``reset_journal=True`` it starts afresh after a ``journal-reset`` record.
Each damage once on the ward day by default, ``COSLEEC_KILLS // 25`` times in a long run.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import pytest

from cosleec.runtime import Manager, VirtualClock, read_audit
from tests.kill_campaign import (
    CORRUPTIONS,
    POINTS,
    ROOT,
    Day,
    Plan,
    Played,
    assistive_care_day,
    keep_old,
    prepare,
    read_lines,
    reference,
    unique,
    verify,
    ward_day,
)
from tests.kill_campaign import calls_made as made
from tests.unit.runtime.test_journal import RULES  # the journal tests' rules: the findings replay them

KILLS = int(os.environ.get("COSLEEC_KILLS", "5"))
_seed = os.environ.get("COSLEEC_KILL_SEED", "20250611")
SEED = random.randrange(2**32) if _seed == "random" else int(_seed)
DAY_KILLS = 6  # at most this many kills in one day: a long campaign plays many days


def life(workdir: Path, plan: Plan | None, timer: float | None, reset: bool = False) -> tuple[int, str]:
    """Run one life to its end or its death; ``timer``: SIGKILL it after that many seconds;
    ``reset``: start it with ``reset_journal=True``."""
    config = json.dumps({"dir": str(workdir), "plan": plan.to_json() if plan else None, "reset": reset})
    p = subprocess.Popen(
        [sys.executable, "-m", "tests.kill_campaign", config],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        _, err = p.communicate(timeout=timer if timer is not None else 120)
    except subprocess.TimeoutExpired:
        os.kill(p.pid, signal.SIGKILL)  # the timer's kill (or a life that hangs)
        _, err = p.communicate()
        if timer is None:
            raise AssertionError(f"a life hung: {err[-2000:]}") from None
    return p.returncode, err


def choose(
    rng: random.Random, left: int, hits: Counter[str], seconds: float
) -> tuple[Plan | None, float | None]:
    """Where the next life dies: a kill point and which pass of it, or a timer (``left`` kills to go)."""
    kind = rng.choice([k for k in POINTS if hits[k] > 0] + ["timer"])
    if kind == "timer":
        return None, rng.uniform(0.0, seconds)
    span = max(1, round(2 * hits[kind] / (left + 1)))  # spread the day's kills over what is left of it
    ops = rng.randint(1, 150) if kind == "journal-inside" else rng.randint(1, 1 << 20)  # a commit runs 40-160
    return Plan(kind, rng.randint(1, span), ops), None


def campaign(
    day: Day, base: Path, kills: int, seed: int, report: Callable[[str], None]
) -> dict[str, Counter[str]]:
    """Play ``day`` with ``kills`` kills in all (over as many days as it takes) and verify each day."""
    rng = random.Random(f"{seed}/{day.name}")
    t0 = time.monotonic()
    code, err = life(prepare(day, base / "plain"), None, None)  # uninterrupted, and how long a life takes
    assert code == 0, err[-3000:]
    seconds = time.monotonic() - t0
    plain = Played.load(base / "plain")
    total = plain.hits_before(len(day.steps) + 1)
    totals: dict[str, Counter[str]] = {"kills": Counter(), "days": Counter()}
    n = 0
    while totals["kills"].total() < kills:
        n += 1
        assert n <= kills + 5, "the lives keep ending their days without being killed"
        workdir = prepare(day, base / f"day{n}")
        planned = min(DAY_KILLS, kills - totals["kills"].total())
        killed = 0
        for _ in range(planned + 50):
            left = planned - killed
            if left > 0:
                resume = Played.load(workdir).steps_done()
                hits = total - plain.hits_before(resume)
                plan, timer = choose(rng, left, hits + Counter(dict.fromkeys(POINTS, 2)), seconds)
            else:
                plan, timer = None, None
            code, err = life(workdir, plan, timer)
            progress = Played.load(workdir).progress
            if code == -signal.SIGKILL:
                killed += 1
                dying = [r for r in progress if r["k"] == "dying"]
                where = "timer" if timer is not None else dying[-1]["point"] if dying else "?"
                totals["kills"][where] += 1
                if not any(r["k"] == "end" for r in progress):
                    continue  # (killed while closing: the day is over all the same)
                break
            assert code == 0, f"seed {seed}, {workdir}: a life failed ({code}):\n{err[-3000:]}"
            break
        else:
            raise AssertionError(f"seed {seed}, {workdir}: the day never ended")
        played = Played.load(workdir)
        same = reference(day, base / f"day{n}-same", made(played))
        try:
            got = verify(day, played, plain, same)
        except AssertionError as e:
            raise AssertionError(f"seed {seed}: {e}") from None
        totals["days"].update({k: v for k, v in got.items()} | {"days": 1})
    report(
        f"{day.name}: seed {seed}, {totals['kills'].total()} kills in {totals['days']['days']} days "
        f"({time.monotonic() - t0:.1f} s); kill points: {dict(sorted(totals['kills'].items()))}; "
        f"recovered: {dict(totals['days'])}"
    )
    return totals


@pytest.mark.parametrize("make_day", [ward_day, assistive_care_day], ids=["ward", "assistive-care"])
def test_a_day_killed_at_random_points_ends_as_if_uninterrupted(
    make_day: Callable[[], Day], tmp_path: Path
) -> None:
    print(f"kill campaign: COSLEEC_KILL_SEED={SEED} COSLEEC_KILLS={KILLS}")
    totals = campaign(make_day(), tmp_path, KILLS, SEED, print)
    assert totals["kills"].total() == KILLS


# ---------------------------------------------------------------------- damaged files after a kill

ROUNDS = 1 if KILLS <= 5 else max(1, KILLS // 25)  # each damage, on as many killed days
#: where the second life dies: in the middle of the day, at least 6 passes in (the WAL then holds
#: the commits of several steps, so a damage loses more than one -- see test_journal.py for less)
LATE = ("in-step", "between-steps", "journal-before", "journal-inside", "journal-after", "audit-after")


def damaged_day(day: Day, workdir: Path, damage: str, rng: random.Random) -> str:
    """Two lives killed, the journal damaged, a life refused, then one started with ``reset_journal``."""
    prepare(day, workdir)
    first = Plan(rng.choice(POINTS[:2] + LATE[2:]), rng.randint(1, 4), rng.randint(1, 150))
    second = Plan(rng.choice(LATE), rng.randint(6, 10), rng.randint(1, 150))
    for n, plan in enumerate((first, second)):
        code, err = life(workdir, plan, None)
        assert code == -signal.SIGKILL, f"life {n + 1} ({plan}) was not killed: {code}\n{err[-2000:]}"
        if n == 0:
            keep_old(workdir)
    CORRUPTIONS[damage](workdir)
    records = read_lines(workdir / "audit.jsonl")
    lives = len([r for r in Played.load(workdir).progress if r["k"] == "life"])
    code, err = life(workdir, None, None)
    assert code == 3, f"{damage} after {first}, {second}: not refused ({code})\n{err[-2000:]}"
    refusal = err.split(": ", 2)[-1].split(". Starting from")[0]  # what it found, without the files' paths
    for name in ("JournalError", "state.db", "state.db-wal", "audit.jsonl", "reset_journal=True"):
        assert name in err, f"{damage}: the refusal does not name {name}:\n{err}"
    assert read_lines(workdir / "audit.jsonl") == records  # nothing of the history was cut or added
    assert len([r for r in Played.load(workdir).progress if r["k"] == "life"]) == lives  # never started
    code, err = life(workdir, None, None, reset=True)
    assert code == 0, f"{damage}: the reset life failed ({code})\n{err[-3000:]}"
    after = read_lines(workdir / "audit.jsonl")
    assert after[: len(records)] == records
    reset, restored = after[len(records)], after[len(records) + 1]
    assert reset["kind"] == "journal-reset" and reset["last_seq"] == records[-1]["seq"]
    lineage = [r["lineage"] for r in records if r["kind"] == "restored"][-1]
    assert reset["lineage"] == lineage  # the history given up
    assert restored["kind"] == "restored" and restored["from"] is None
    assert [r["seq"] for r in after] == list(range(1, len(after) + 1))
    assert any(r["k"] == "end" for r in Played.load(workdir).progress)
    return refusal


@pytest.mark.parametrize("damage", list(CORRUPTIONS))
def test_a_damaged_journal_is_refused_never_an_empty_start(damage: str, tmp_path: Path) -> None:
    rng = random.Random(f"{SEED}/{damage}")
    said = Counter(damaged_day(ward_day(), tmp_path / f"day{n}", damage, rng) for n in range(ROUNDS))
    print(f"{damage}: refused {ROUNDS} of {ROUNDS}, then reset (COSLEEC_KILL_SEED={SEED}): {dict(said)}")


# ---------------------------------------------------------------------- what the campaign found, one by one


def manager(tmp_path: Path, t: float) -> Manager:
    """A Manager on the journal and audit log in ``tmp_path`` at clock time ``t``, started.

    Closing it and opening another is what a kill right after a step does to the journal.
    """
    m = Manager.from_text(
        RULES, clock=VirtualClock(t), journal=tmp_path / "state.db", audit=tmp_path / "audit.jsonl"
    )
    m.capability("Act")(lambda ob, d: None)
    m.capability("Help")(lambda ob, d: None)
    return m.start()


def test_obligation_ids_go_on_after_a_restart_with_nothing_pending(tmp_path: Path) -> None:
    m = manager(tmp_path, 100)
    m.event("Trigger")
    m.event("Act")  # obligation 1 fulfilled: nothing pending when the Manager stops
    m.close()
    m = manager(tmp_path, 101)
    m.event("Trigger")
    assert [t.id for t in m.outstanding()] == [2]  # before: 1 again, two obligations #1 in the audit log
    m.close()


def test_a_prohibitions_refusals_survive_a_restart(tmp_path: Path) -> None:
    m = manager(tmp_path, 100)
    m.update(consent=False)
    m.event("Watch")
    assert m.request("Rec").permitted is False
    m.close()
    m = manager(tmp_path, 101)
    m.clock.set(800)  # type: ignore[attr-defined]
    m.tick()
    m.close()
    (respected,) = [r for r in read_audit(tmp_path / "audit.jsonl") if r.get("status") == "respected"]
    assert respected["refused"] == 1  # before: 0, the refusal counted only in the killed process


def test_layer_versions_go_on_after_a_restart(tmp_path: Path) -> None:
    m = manager(tmp_path, 100)
    m.update(consent=True)  # R2.1: layers version 1
    m.close()
    m = manager(tmp_path, 101)
    m.update(consent=False)
    m.close()
    versions = [r["version"] for r in read_audit(tmp_path / "audit.jsonl") if r["kind"] == "layers"]
    assert versions == [1, 2]  # before: [1, 1]


def test_a_late_event_after_a_restart_is_reported_late(tmp_path: Path) -> None:
    m = manager(tmp_path, 900)
    m.event("Trigger")
    m.clock.set(910)  # type: ignore[attr-defined]
    m.tick()  # Act is violated at 905 (and Help runs)
    m.close()
    m = manager(tmp_path, 911)
    m.event("Act")  # the uninterrupted Manager records it as late at 911
    m.close()
    late = [
        r["late"] for r in read_audit(tmp_path / "audit.jsonl") if r["kind"] == "obligation" and r["late"]
    ]
    assert late == [[911.0]]


def test_an_audit_record_names_its_time_once(tmp_path: Path) -> None:
    m = manager(tmp_path, 100)
    m.event("Trigger")
    m.clock.set(110)  # type: ignore[attr-defined]
    m.tick()  # the fallback is decided at 110 and starts at the deadline, 105
    m.close()
    lines = (tmp_path / "audit.jsonl").read_text().splitlines()
    records = [
        json.loads(line, object_pairs_hook=unique) for line in lines
    ]  # before: "time" twice, 110 and 105
    (fallback,) = [r for r in records if r.get("event") == "otherwise"]
    assert fallback["time"] == 105.0


def test_a_step_committed_after_a_restore_set_records_aside_is_not_played_again(tmp_path: Path) -> None:
    # seed 2521208213, ward day 1: the fourth life's restart set aside records 63-69 (a commit
    # the third life never made), wrote its own from 63, committed step 15 (Shift) as 67-69 and
    # died in its capability's records (a torn line). Its ``begin`` line gave seq 69, the log's
    # length before the cut, so the next life found nothing committed after it and played Shift
    # again: a second W1.1 decision, every later decision id one higher, and the campaign
    # reported calls "lost with no task-interrupted record" that the Manager had not lost
    day = ward_day()
    workdir = prepare(day, tmp_path / "day")
    for plan in (
        Plan("journal-before", 16),
        Plan("journal-inside", 4, 98),
        Plan("journal-inside", 12, 8),
        Plan("audit-partial", 4, 972024),
    ):
        code, err = life(workdir, plan, None)
        assert code == -signal.SIGKILL, f"{plan}: not killed ({code})\n{err[-2000:]}"
    code, err = life(workdir, None, None)
    assert code == 0, err[-3000:]
    played = Played.load(workdir)
    shifts = [r for r in played.records if r["kind"] == "event" and r["event"] == "Shift"]
    assert len(shifts) == 2  # steps 1 and 15, each once (before: 3)
    for begin in (r for r in played.progress if r["k"] == "begin"):  # what the log held when it began
        kept = [r for r in played.records if r["seq"] <= begin["seq"]]
        assert kept and kept[-1]["seq"] == begin["seq"]
    plain = reference(day, tmp_path / "plain")
    verify(day, played, plain, reference(day, tmp_path / "same", made(played)))
