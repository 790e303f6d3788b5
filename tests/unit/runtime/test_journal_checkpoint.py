"""The journal's checkpointer (issue 32, "the journal off the tail"): the WAL is copied into
the database and started afresh by a thread of the Journal, never inside a step's commit,
and it stays bounded; a checkpoint that fails never fails a commit; a kill in the middle of
one loses nothing (see also the kill campaign's ``checkpoint`` kill point)."""

from __future__ import annotations

import gc
import logging
import os
import random
import signal
import sqlite3
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from cosleec.runtime import Journal
from cosleec.runtime.journal import Change, JournalError, _Background

PAGE = 4096 + 24  # a WAL frame: a page and its header


def commit(j: Journal, i: int, width: int = 1) -> None:
    """Commit step ``i``: ``width`` measures set to ``i``, counter ``i``."""
    change = Change(context={f"x{k}": (i, float(i)) for k in range(width)})
    j.commit(change, {"rules": "r", "counters": {"i": i}}, float(i))


def opened(path: Path, **thresholds: float) -> Journal:
    """A started journal at ``path``, its checkpointer's thresholds set."""
    j = Journal(path)
    for name, value in thresholds.items():
        setattr(j, name, value)
    j.load()
    j.start()
    return j


def wal_sequence(j: Journal) -> int:
    """The WAL header's first salt: it goes up by one each time the WAL starts afresh."""
    with j.wal.open("rb") as fh:
        header = fh.read(32)
    return int(struct.unpack(">I", header[16:20])[0])


def wait_for(what: object, timeout: float = 10.0) -> None:
    """Poll ``what()`` until true (the checkpointer runs on its own time)."""
    end = time.monotonic() + timeout
    while not what():  # type: ignore[operator]
        assert time.monotonic() < end, "the checkpointer did not get there"
        time.sleep(0.005)


class Idle(Journal):
    """A journal whose checkpointer does nothing: what the commits do alone."""

    def _checkpoint(self, bg: _Background) -> None:
        pass


def test_commits_never_checkpoint_the_wal_themselves(tmp_path: Path) -> None:
    j = Idle(tmp_path / "state.db")
    j.load()
    j.start()
    assert j._db.execute("PRAGMA wal_autocheckpoint").fetchone() == (2 * j.checkpoint_limit,)  # a last resort
    seq = wal_sequence(j)
    for i in range(1, 700):
        commit(j, i, width=3)
    # past SQLite's own checkpoint (1000 pages), which would copy the WAL and start it afresh
    assert j.wal.stat().st_size > 1100 * PAGE
    assert wal_sequence(j) == seq
    j.close()
    j = Journal(tmp_path / "state.db")
    saved = j.load()
    assert saved is not None and saved.counters == {"i": 699}
    assert saved.context["x2"] == (699, 699.0)
    j.close()


def test_the_first_commit_after_start_or_an_idle_checkpoint_does_not_start_the_wal_afresh(
    tmp_path: Path,
) -> None:
    j = opened(tmp_path / "state.db", checkpoint_idle=0.02)
    assert j._bg is not None
    seq = wal_sequence(j)  # start() copied the WAL and started it afresh itself
    commit(j, 1)
    assert wal_sequence(j) == seq
    for i in range(2, 50):
        commit(j, i)
    bg = j._bg
    wait_for(lambda: bg.copied == 49 and bg.frames == 0)  # copied whole, started afresh: idle
    seq = wal_sequence(j)
    assert seq > 0
    commit(j, 50)  # (before the checkpointer's restart, the commit did it: a new sequence number)
    assert wal_sequence(j) == seq
    j.close()
    assert not j.wal.exists()  # the last close copied it in and deleted it, as before
    j = Journal(tmp_path / "state.db")
    saved = j.load()
    assert saved is not None and saved.counters == {"i": 50} and j.suspect is None
    j.close()


@pytest.mark.parametrize("seed", range(3))
def test_no_commit_starts_the_wal_afresh_when_they_pause_now_and_then(tmp_path: Path, seed: int) -> None:
    # pauses of up to 10 ms: the checkpointer often copies the WAL whole between two commits,
    # and the first write after that starts it afresh, with an fsync: never a commit
    rng = random.Random(seed)
    j = Journal(tmp_path / "state.db")
    j._lock = threading.RLock()  # type: ignore[assignment]  # (held here around a commit and its reads)
    j.checkpoint_commits, j.checkpoint_idle, j.checkpoint_restart = 4, 0.01, 30
    j.load()
    j.start()
    salts = []
    for i in range(1, 301):
        with j._lock:  # the checkpointer starts it afresh under this lock
            salt = wal_sequence(j)
            commit(j, i)
            assert wal_sequence(j) == salt, f"commit {i} started the WAL afresh"
        salts.append(salt)
        time.sleep(rng.choice([0, 0, 0.001, 0.003, 0.01]))
    assert len(set(salts)) >= 3  # the checkpointer did, between them
    j.close()


@pytest.mark.parametrize(
    ("thresholds", "commits", "pages"),
    [
        # without a limit, 16000 commits here are 64000 pages (260 MB); with it, 1600 and what
        # the commits add while one checkpoint's fsyncs run (thousands, on a busy machine)
        ({}, 16000, 10 * 1600),
        ({"checkpoint_commits": 8, "checkpoint_restart": 40, "checkpoint_limit": 120}, 5000, 6000),
    ],
    ids=["default", "small"],
)
def test_the_wal_stays_bounded_while_commits_never_pause(
    tmp_path: Path, thresholds: dict[str, int], commits: int, pages: int
) -> None:
    # the bound: the limit, and what the commits add while one checkpoint runs (its fsyncs:
    # milliseconds, hundreds of these commits)
    j = opened(tmp_path / "state.db", **thresholds)
    salt = wal_sequence(j)
    most = 0
    for i in range(1, commits + 1):
        commit(j, i, width=3)
        if not i % 16:
            most = max(most, j.wal.stat().st_size)
    assert j._bg is not None and j._bg.failures == 0
    assert most <= pages * PAGE, (most // PAGE, pages)
    assert wal_sequence(j) - salt >= commits * 4 // (
        j.checkpoint_limit + 4000
    )  # started afresh again and again
    j.close()
    j = Journal(tmp_path / "state.db")
    saved = j.load()
    assert saved is not None and saved.counters == {"i": commits}
    assert saved.context["x2"] == (commits, float(commits))
    j.close()


def test_commits_that_never_pause_below_the_limits_are_never_held_back(tmp_path: Path) -> None:
    j = opened(tmp_path / "state.db", checkpoint_commits=16, checkpoint_restart=10**6, checkpoint_limit=10**6)
    j.checkpoint_idle = 60  # (no pause long enough to start it afresh)
    salt = wal_sequence(j)
    for i in range(1, 3009):
        commit(j, i, width=3)
    assert j._bg is not None
    bg = j._bg
    wait_for(lambda: bg.copied == 3008)  # copied, in the background
    assert wal_sequence(j) == salt  # and never started afresh, which holds the commits back
    j.close()


class Failing(Journal):
    """A journal whose checkpoints fail (a full disk) until told otherwise."""

    failing = True
    rounds = 0

    def _checkpoint(self, bg: _Background) -> None:
        self.rounds += 1
        if self.failing:
            raise sqlite3.OperationalError("database or disk is full")
        super()._checkpoint(bg)


def test_a_failing_checkpoint_is_logged_once_and_never_fails_a_commit(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, "cosleec.runtime")
    j = Failing(tmp_path / "state.db")
    j.checkpoint_commits, j.checkpoint_idle = 4, 0.001
    j.load()
    j.start()
    for i in range(1, 41):
        commit(j, i)
    wait_for(lambda: j.rounds >= 3)
    failed = [r.getMessage() for r in caplog.records if "checkpoint failed" in r.getMessage()]
    assert len(failed) == 1 and "the disk is full" in failed[0]  # once, until one succeeds
    j.failing = False
    commit(j, 41)
    assert j._bg is not None
    bg = j._bg
    wait_for(lambda: bg.failures == 0 and bg.copied == 41)
    assert any("checkpoints work again" in r.getMessage() for r in caplog.records)
    j.close()
    j = Journal(tmp_path / "state.db")
    saved = j.load()
    assert saved is not None and saved.counters == {"i": 41}
    j.close()


def test_close_stops_the_thread_and_a_dropped_journal_stops_it_too(tmp_path: Path) -> None:
    def threads() -> list[threading.Thread]:
        return [t for t in threading.enumerate() if t.name.startswith("cosleec journal checkpointer")]

    before = threads()
    j = opened(tmp_path / "state.db")
    commit(j, 1)
    assert len(threads()) == len(before) + 1
    j.close()
    assert threads() == before
    j = opened(tmp_path / "state.db")
    j.reset()  # (starts it again: one thread, not two)
    j.start()
    assert len(threads()) == len(before) + 1
    commit(j, 1)
    (thread,) = set(threads()) - set(before)
    del j
    gc.collect()
    thread.join(5)
    assert not thread.is_alive()
    j = Journal(tmp_path / "state.db")  # its lock went with it
    assert j.load() is not None
    j.close()


def test_one_journal_one_manager_in_this_process_and_in_others(tmp_path: Path) -> None:
    j = opened(tmp_path / "state.db")
    with pytest.raises(JournalError, match="in use by another Manager"):
        Journal(tmp_path / "state.db")
    with pytest.raises(JournalError, match="in use by another Manager"):
        Journal(tmp_path / "." / "state.db")  # (the same file)
    other = subprocess.run(
        [
            sys.executable,
            "-c",
            f"from cosleec.runtime import Journal; Journal({str(tmp_path / 'state.db')!r})",
        ],
        capture_output=True,
        text=True,
    )
    assert "in use by another Manager" in other.stderr  # SQLite's lock, held by this process
    commit(j, 1)  # the refused ones took nothing from it
    j.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.db"]  # no -wal, no -shm, no lock file
    Journal(tmp_path / "state.db").close()


def test_no_checkpointer_then_sqlite_checkpoints_in_the_commits(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    def no_thread(self: threading.Thread) -> None:
        raise RuntimeError("can't start new thread")

    monkeypatch.setattr(threading.Thread, "start", no_thread)
    j = opened(tmp_path / "state.db")
    assert j._bg is None and "no checkpointer" in caplog.text
    assert j._db.execute("PRAGMA wal_autocheckpoint").fetchone() == (1000,)
    j.close()


CHILD = """
import sys
from pathlib import Path
sys.path.insert(0, {tests!r})
from test_journal_checkpoint import commit
from cosleec.runtime import Journal
j = Journal(Path({path!r}))
j.checkpoint_commits, j.checkpoint_idle, j.checkpoint_restart, j.checkpoint_limit = 1, 0.001, 4, 16
saved = j.load()
j.start()
for i in range(saved.counters["i"] + 1 if saved else 1, 10**6):
    commit(j, i, width=20)
    print(i, flush=True)
"""


@pytest.mark.parametrize("seed", range(6))
def test_a_kill_while_the_checkpointer_copies_loses_no_commit(tmp_path: Path, seed: int) -> None:
    path = tmp_path / "state.db"
    code = CHILD.format(tests=str(Path(__file__).parent), path=str(path))
    last = 0
    for life in range(3):  # each life goes on from what the last one left
        p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
        assert p.stdout is not None
        first = p.stdout.readline()  # committing, the checkpointer at work
        time.sleep(random.Random(seed * 10 + life).uniform(0.02, 0.3))
        os.kill(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        printed = [int(n) for n in (first + out).split()]
        j = Journal(path)
        saved = j.load()
        assert saved is not None and j.suspect is None
        i = saved.counters["i"]
        # every printed commit is there, and at most the one the kill interrupted after it
        assert printed and printed[-1] <= i <= printed[-1] + 1, (printed[-1:], i)
        assert saved.context == {f"x{k}": (i, float(i)) for k in range(20)}
        assert i > last
        last = i
        j.close()


def wal_frames(j: Journal) -> int:
    """Frames written to the WAL since it last started afresh (its file only grows meanwhile)."""
    return (j.wal.stat().st_size - 32) // PAGE


def test_a_step_replacing_measures_writes_few_pages(tmp_path: Path) -> None:
    """``context`` and ``meta`` are WITHOUT ROWID tables: a replaced row stays in its page. With
    rowid tables a step replacing 20 of 1,200 measures wrote 5-6 pages (each row moved to the
    table's end and its index entry rewritten); now the measures' page or two and ``meta``'s."""
    j = opened(tmp_path / "state.db", checkpoint_commits=10**6, checkpoint_idle=600)
    names = [f"c{i}_{k}" for i in range(60) for k in range(20)]
    j.commit(Change(context={n: (False, 0.0) for n in names}), {"rules": "r"}, 0.0)
    for kind in ("meta", "context"):
        sql = j._db.execute("SELECT sql FROM sqlite_master WHERE name = ?", (kind,)).fetchone()[0]
        assert sql.endswith("WITHOUT ROWID")
    before = wal_frames(j)
    rng = random.Random(7)
    steps = 100
    for step in range(steps):
        rule = rng.randrange(60)
        change = Change(context={f"c{rule}_{k}": (step % 2 == 0, float(step)) for k in range(20)})
        j.commit(change, {"rules": "r", "counters": {"i": step}}, float(step))
    assert (wal_frames(j) - before) / steps <= 3
    j.close()


def test_a_journal_made_with_rowid_tables_is_restored_and_written(tmp_path: Path) -> None:
    """Journals made before the tables were WITHOUT ROWID keep theirs: the same statements
    read and write both, and nothing of what they hold is lost."""
    path = tmp_path / "state.db"
    db = sqlite3.connect(path)
    db.executescript(
        """
        CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
        CREATE TABLE context (name TEXT PRIMARY KEY, value TEXT NOT NULL, stamp REAL NOT NULL);
        CREATE TABLE obligations (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
        CREATE TABLE outbox (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
        """
    )
    db.close()
    j = opened(path)
    commit(j, 1, width=3)
    commit(j, 2, width=2)
    j.close()
    j = Journal(path)
    saved = j.load()
    assert saved is not None and saved.counters == {"i": 2}
    assert saved.context == {"x0": (2, 2.0), "x1": (2, 2.0), "x2": (1, 1.0)}
    sql = j._db.execute("SELECT sql FROM sqlite_master WHERE name = 'context'").fetchone()[0]
    assert "WITHOUT ROWID" not in sql  # (kept as it was made)
    j.close()
