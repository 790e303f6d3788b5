"""The Manager's journal: what it must not forget, kept in one SQLite file across crashes.

``Manager(..., journal="state.db")`` writes, in the same transaction as the state change
that caused them, every measure value, every obligation and prohibition still in force
(with its window), the counters that make ids unique (decisions, obligations, the causal
sequence, audit records), the implementations not yet run, and the length of the JSON
Lines audit log once the step's records are in it (written and flushed just before the
commit). A Manager started on the same journal restores all of it (:class:`Saved`), so a
``kill -9`` loses no obligation, forgets no prohibition and reuses no id; audit records
past the committed length are of a step that never happened, and are set aside.

SQLite in WAL mode with ``synchronous=NORMAL``: a commit survives the death of the
process at any instant; a power cut can lose the last commits (pass ``fsync=True`` for
``synchronous=FULL``, at a cost per step; the checkpointer's connections use the same). One
connection commits, under the Manager's lock. One Manager per journal: SQLite's ``unix-excl``
VFS locks the file for the process that opened it, and a process opens it once.

**The WAL is copied into the database off the step.** SQLite's own checkpoint runs inside
the commit that fills the WAL (every ~1000 pages), with its fsyncs, and the first write
after a checkpoint that copied it whole starts the WAL afresh, with an fsync of its header:
milliseconds on the steps that meet them. So the committing connection does not checkpoint
(``wal_autocheckpoint`` twice the limit below: a last resort), and a thread of the Journal,
on connections of its own, copies
the WAL (PASSIVE checkpoints, which never hold a commit back) every
:attr:`Journal.checkpoint_commits` commits and every :attr:`Journal.checkpoint_idle` seconds
while commits wait to be copied. Around each checkpoint it keeps a read transaction open, so
that no commit can be the write that starts the WAL afresh; it starts it afresh itself (a
small write, commits held back for its fsync) once the WAL is copied whole and holds
:attr:`Journal.checkpoint_restart` pages, or commits paused. A WAL that commits never let it
copy whole grows to :attr:`Journal.checkpoint_limit` pages (and what the commits add while
one checkpoint runs): then the rest is copied and the WAL started afresh with commits held
back, the only time a step waits for the checkpointer. A checkpoint that fails (a full disk,
a busy lock) is logged and tried again later, never raised into a step, and a kill in the
middle of one loses nothing (SQLite's guarantee; the kill campaign kills there too).
:meth:`Journal.close` stops and joins the thread before SQLite's last close copies the WAL
in. Without the thread (no connection or thread to be had) SQLite checkpoints as before.

**What it restores is all that was committed, or it refuses.** While a Manager runs, the
commits since it opened the journal are only in ``state.db-wal``: lose that file (deleted,
truncated, bytes changed -- SQLite silently ignores what it cannot read) or the ``.db``
(truncated, deleted, an old copy put back) and SQLite opens an older journal, or an empty
one, without a word. So the journal proves its state before the Manager uses it
(:func:`verify`), all of it at open and nothing per step:

- opening it marks it *running* in the main file (``meta.running``) and copies the WAL
  into it (a checkpoint); a clean :meth:`Journal.close` clears the mark. A main file marked
  running with no ``-wal`` file beside it lost its last commits (:attr:`Journal.suspect`);
  an empty or missing main file with a ``-wal`` file lost everything (:attr:`Journal.damage`,
  and SQLite would delete that ``-wal`` file: the journal is not touched);
- with the audit log beside it, the log says what was committed: each commit's records end
  where the journal says the log ended (:attr:`Saved.audit`), with the record numbered just
  before its next ``seq``; a kill between writing a step's records and committing it leaves
  the records of at most *one* step after that point (every record of a step carries the
  same ``run``, ``mono`` and ``wall``). Records of two steps or more after it, a log that
  does not continue where the journal stopped, or an empty journal beside a log that holds
  a journaled history (a ``restored`` record) mean the journal lost commits.

A journal in doubt is refused (JournalError naming the files and the two ways out: put the
journal and the audit log back from one backup, or ``Manager(..., reset_journal=True)``,
which empties the journal and records what was lost as a ``journal-reset`` audit record).
Without an audit log a truncated or corrupted ``-wal`` file cannot be told from a shorter
history: run with the audit log beside the journal. A loss of only the very last commit
looks like a kill before that commit, and is treated as one (its records set aside).
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import os
import sqlite3
import threading
import time
import urllib.parse
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosleec.errors import UserError
from cosleec.records import encode
from cosleec.runtime.audit import AuditLog

# ``meta`` and ``context`` are keyed by name WITHOUT ROWID: a row replaced stays in its page
# of the key's b-tree, where a rowid table moved it to a new rowid at the table's end and
# rewrote its index too (a step flipping 20 measures wrote 5.6 pages to the WAL, now 2.2;
# fewer pages per step, fewer checkpoint rounds and WAL restarts on the steps). Journals made
# before keep their rowid tables: the statements are the same for both.
_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS context (name TEXT PRIMARY KEY, value TEXT NOT NULL, stamp REAL NOT NULL) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS obligations (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS outbox (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
"""
_TABLES = ("meta", "context", "obligations", "outbox")

log = logging.getLogger("cosleec.runtime")
_OPEN: set[str] = set()  # the journals open in this process (real paths): one Journal each
_OPEN_LOCK = threading.Lock()


class JournalError(UserError):
    """The journal cannot be opened, trusted or written (a path that is not writable, a full
    disk, a journal that lost commits: see the module docstring).

    A Manager whose journal fails stops deciding: every later call raises this error and
    :meth:`~cosleec.runtime.Manager.request` refuses, since its state can no longer be kept.
    ``reason`` is why a journal was refused (:meth:`Journal.refusal`), without the way out.
    """

    reason: str = ""


@dataclass
class Saved:
    """Everything a journal held when it was opened: restored by the Manager at start."""

    rules: str  # the digest of the rule set that wrote it
    run: str  # the run that wrote last
    lineage: str  # the run that created the journal: one history across restarts
    counters: dict[str, int]
    clock: float  # clock time of the last commit
    wall: float  # Unix time of the last commit
    context: dict[str, tuple[Any, float]]  # measure -> (value as users see it, clock time set)
    obligations: list[dict[str, Any]]  # obligation records (Tracked.to_json): pending, or missed and
    # still waiting for their late event
    outbox: list[dict[str, Any]]  # implementations decided but not known to have run, or (a
    # Manager node, dispatch=False) decisions not known to have been published
    audit: int | None = None  # the audit log's length (bytes) at the last commit; None: no log
    clock_kind: str = ""  # the class of the clock that wrote it (VirtualClock, MonotonicClock)
    boot: str = ""  # the machine's boot id when it was written (a monotonic clock's origin)


@dataclass
class Change:
    """What one step of the Manager changed, committed to the journal in one transaction."""

    context: dict[str, tuple[Any, float] | None] = field(default_factory=dict)  # None: now unknown
    obligations: dict[int, dict[str, Any] | None] = field(default_factory=dict)  # None: closed
    outbox: dict[int, dict[str, Any] | None] = field(default_factory=dict)  # None: done

    def __bool__(self) -> bool:
        return bool(self.context or self.obligations or self.outbox)


class Journal:
    """A SQLite journal of a Manager's state (see the module docstring).

    Opening one takes its lock (one Manager per journal) and looks at its files, writing
    nothing: ``damage`` says why nothing can be restored from them, ``suspect`` why what
    can be may be older than what was committed (None when the files look whole). The
    Manager decides (:func:`verify`), then calls :meth:`start` -- or :meth:`reset` first.

    Not thread-safe by itself: the Manager calls it under its lock (the connection is
    allowed to move between threads for that reason).
    """

    #: the checkpointer (see the module docstring): a round after this many commits, and
    #: this many seconds after the last round while commits wait to be copied
    checkpoint_commits = 64
    checkpoint_idle = 0.25
    #: pages (WAL frames) past which the WAL, all copied, is started afresh though commits
    #: go on; and past which, not all copied, the rest is copied with commits held back
    checkpoint_restart = 1500
    checkpoint_limit = 1600

    def __init__(self, path: str | Path, *, fsync: bool = False) -> None:
        self.path = Path(path)
        self.wal = self.path.with_name(self.path.name + "-wal")
        self.damage: str | None = None
        self.suspect: str | None = None
        self._fsync = fsync
        self._started = False  # marked running by this object: close() clears the mark
        self._lock = threading.Lock()  # a commit, or the checkpointer starting the WAL afresh
        self._bg: _Background | None = None  # the checkpointer, from start() to close()
        self._bg_stop: weakref.finalize[[], Journal] | None = None  # stops it if this is collected
        self._unlock = self._take_lock()
        try:
            self._open()
        except BaseException:
            self._unlock()
            raise

    def _take_lock(self) -> weakref.finalize[[str], Journal]:
        """Take the journal for this object in this process (other processes are kept out by
        SQLite's lock); what gives it back, once (also when this is dropped without close())."""
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise JournalError(
                f"cannot open the journal: {_reason(e)}",
                where=str(self.path),
                hint=_hint(e, self.path, "give a writable path to a journal file"),
            ) from None
        key = os.path.realpath(self.path)
        with _OPEN_LOCK:
            if key in _OPEN:
                raise JournalError(
                    "the journal is in use by another Manager",
                    where=str(self.path),
                    hint="stop the other Manager first, or give each Manager its own journal",
                )
            _OPEN.add(key)
        return weakref.finalize(self, _OPEN.discard, key)

    def _connect(self, timeout: float) -> sqlite3.Connection:
        """A connection to the journal through SQLite's ``unix-excl`` VFS: the first one takes
        the file for this process (no other process can open it while one is open), and the
        process's connections share the WAL's index in memory, with no lock (``fcntl``) per
        transaction and no ``-shm`` file, as in exclusive locking mode."""
        uri = f"file:{urllib.parse.quote(os.fspath(self.path))}?vfs=unix-excl"
        return sqlite3.connect(uri, uri=True, check_same_thread=False, isolation_level=None, timeout=timeout)

    def _open(self) -> None:
        """Look at the journal's files and open the committing connection (see ``__init__``)."""
        try:
            kept = self._kept()
            if kept.exists() and not self.wal.exists():  # a close killed while it kept the -wal file
                os.replace(kept, self.wal)
            existed = self.path.exists()
            size = self.path.stat().st_size if existed else 0
            self._had_wal = self.wal.exists()
            if size == 0 and self._had_wal:  # SQLite would delete that -wal file: do not even open it
                self._db = sqlite3.connect(":memory:", check_same_thread=False)
                self.damage = (
                    f"the journal's database file {self.path.name} is "
                    f"{'empty' if existed else 'missing'} but its {self.wal.name} file is there: "
                    "the database was truncated or deleted, and every commit it held is lost"
                )
                return
            self._db = self._connect(timeout=1.0)
        except (OSError, sqlite3.Error) as e:
            raise JournalError(
                f"cannot open the journal: {_reason(e)}",
                where=str(self.path),
                hint=_hint(e, self.path, "give a writable path to a journal file"),
            ) from None
        self._prepare()
        marked = self._marked()
        if marked is not None and not self._had_wal:
            self.suspect = (
                f"the journal {self.path.name} was left running (by process {marked.get('pid', '?')}) "
                f"and its {self.wal.name} file is gone: the commits since it opened were in that file"
            )

    def _prepare(self) -> None:
        """Lock the database (the first read takes it for this process) and put it in WAL mode."""
        try:
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute(f"PRAGMA synchronous={'FULL' if self._fsync else 'NORMAL'}")
        except sqlite3.OperationalError as e:
            self._db.close()
            busy = "locked" in str(e)
            raise JournalError(
                "the journal is in use by another Manager"
                if busy
                else f"cannot use the journal: {_reason(e)}",
                where=str(self.path),
                hint="stop the other Manager first, or give each Manager its own journal"
                if busy
                else _hint(e, self.path, "give the path of a cosleec journal, or a new file"),
            ) from None
        except sqlite3.Error as e:
            self._db.close()
            raise JournalError(
                f"this is not a cosleec journal: {e}",
                where=str(self.path),
                hint="give a new file for a new journal",
            ) from None

    def _marked(self) -> dict[str, Any] | None:
        """The running mark of the main file (None: closed cleanly, or a journal of before the mark)."""
        try:
            if not self._has("meta"):
                return None
            row = self._db.execute("SELECT value FROM meta WHERE key = 'running'").fetchone()
            mark = json.loads(row[0]) if row else None
        except (sqlite3.Error, ValueError):
            return None  # a damaged journal: load() says so
        return mark if isinstance(mark, dict) else {} if mark is not None else None

    def _kept(self) -> Path:
        """Where :meth:`close` keeps the ``-wal`` file while SQLite closes (see there)."""
        return self.wal.with_name(self.wal.name + ".kept")

    def _has(self, table: str) -> bool:
        return bool(self._db.execute("SELECT 1 FROM sqlite_master WHERE name = ?", (table,)).fetchone())

    def start(self) -> None:
        """Take the journal into use (after :meth:`load` and the Manager's check): create its
        tables, mark it running and copy the WAL into the main file, so that from now on the
        ``-wal`` file holds only this Manager's commits and its loss can be seen."""
        if self.damage is not None:
            raise self.refusal(self.damage)
        self._quiet()
        try:
            self._db.executescript(_SCHEMA)
            now = str(time.time())
            mark = json.dumps({"pid": os.getpid(), "opened": float(now)})
            self._db.executemany(
                "INSERT OR REPLACE INTO meta VALUES (?, ?)", [("opened", now), ("running", mark)]
            )
            busy, _, _ = self._db.execute("PRAGMA wal_checkpoint(TRUNCATE)").fetchone()
            if not busy:  # the WAL is empty: its first write, and the fsync of its header, is not a step's
                _start_afresh(self._db)
        except sqlite3.Error as e:
            raise JournalError(
                f"cannot use the journal: {_reason(e)}",
                where=str(self.path),
                hint=_hint(e, self.path, "give the path of a cosleec journal, or a new file"),
            ) from None
        if busy:
            raise JournalError(
                "cannot use the journal: its WAL could not be copied into the database",
                where=str(self.path),
                hint="make sure no other program has the journal open, then start the Manager again",
            )
        self._kept().unlink(missing_ok=True)  # a second name a killed close left: no longer needed
        self.suspect = None
        self._started = True
        self._bg = self._checkpointer()

    def _checkpointer(self) -> _Background | None:
        """Start the thread that copies the WAL into the database (see the module docstring).

        None when its connections cannot be had: SQLite then checkpoints in the commits, as
        it would by itself (a tail on the step, but a WAL that never stops growing is worse).
        """
        bg = _Background()
        try:
            for name in ("db", "ck"):
                db = self._connect(timeout=0)
                setattr(bg, name, db)
                db.execute(f"PRAGMA synchronous={'FULL' if self._fsync else 'NORMAL'}")  # as the commits
                db.execute("PRAGMA wal_autocheckpoint=0")
            page = int(bg.db.execute("PRAGMA page_size").fetchone()[0])
            # the WAL file shrinks back to this when started afresh (after a burst past it)
            bg.db.execute(f"PRAGMA journal_size_limit={self.checkpoint_restart * (page + 24) + 32}")
            bg.thread = threading.Thread(
                target=_checkpointing,
                args=(weakref.ref(self), bg, self.checkpoint_idle),
                name=f"cosleec journal checkpointer ({self.path.name})",
                daemon=True,  # a process that exits without close() is not held up by it
            )
            # SQLite's own checkpoint in the commits only past twice the limit: a last resort
            # for a thread that cannot keep up (a disk that takes seconds to fsync)
            self._db.execute(f"PRAGMA wal_autocheckpoint={2 * self.checkpoint_limit}")
            bg.thread.start()
        except (sqlite3.Error, RuntimeError) as e:  # (RuntimeError: no thread can be started)
            log.warning("journal %s: no checkpointer (%s): SQLite checkpoints in the commits", self.path, e)
            with contextlib.suppress(sqlite3.Error):
                self._db.execute("PRAGMA wal_autocheckpoint=1000")
            bg.close()
            return None
        self._bg_stop = weakref.finalize(self, bg.stop)  # a Journal dropped without close() stops it
        return bg

    def _quiet(self) -> None:
        """Stop the checkpointer and wait for it (it closes its connection): before close, a reset
        or a start uses the database alone. Never raises."""
        bg, self._bg = self._bg, None
        if bg is None:
            return
        bg.stop()
        if bg.thread is not None and bg.thread is not threading.current_thread():
            bg.thread.join()
        if self._bg_stop is not None:
            self._bg_stop.detach()

    def _checkpoint(self, bg: _Background) -> None:
        """One round of the checkpointer, in its thread, on its connections. Raises what SQLite raises.

        Copies what was committed into the database (PASSIVE, on ``bg.ck``: no commit waits
        for it), under a read transaction of ``bg.db``: a WAL copied whole is started afresh
        by the first write after it, with an fsync of its header, and the read keeps that
        write from being a commit's. Then ``bg.db`` starts it afresh itself -- a small write,
        the commits held back for its fsync -- when it holds ``checkpoint_restart`` pages, or
        at the next round if no commit came by then; else keeps the read until the next round
        (the commits in between go on at the end of the WAL). A WAL past ``checkpoint_limit``
        pages that the commits never let it copy whole: the rest is copied, and the WAL
        started afresh, with the commits held back.
        """
        if bg.commits == bg.copied:  # no commit since the WAL was copied whole
            if bg.frames and not bg.nudged:  # for a whole wait: start it afresh now
                self._restart(bg)
            return
        with self._lock:  # (no commit between the read's end and its new start, nor before ``seen``)
            _hold(bg.db)
            seen = bg.commits
        busy, bg.frames, copied = _passive(bg.ck)
        if not busy and copied == bg.frames:
            bg.copied = seen  # (those in the read: all it could copy)
            if bg.frames < self.checkpoint_restart or self._restart(bg):
                return  # the read kept until the next round, or started afresh
        _release(bg.db)  # commits came after what it copied: they go on at its end, none starts it afresh
        if bg.frames >= self.checkpoint_limit:
            with self._lock:  # the commits wait: copy the rest, then start it afresh
                busy, frames, copied = _passive(bg.ck)
                if not busy and copied == frames:
                    _start_afresh(bg.db)
                    bg.copied, bg.frames = bg.commits, 0

    def _restart(self, bg: _Background) -> bool:
        """Start the WAL afresh if it is still copied whole (commits held back); whether it was."""
        with self._lock:
            # (while bg.db's read lasts, this checkpoint copies nothing: it only says how long it is)
            busy, frames, copied = _passive(bg.ck)
            if busy or copied != frames:
                return False
            _release(bg.db)
            _start_afresh(bg.db)
            bg.frames = 0
            return True

    def load(self) -> Saved | None:
        """What the journal holds; None for a new journal; JournalError when it is damaged."""
        if self.damage is not None:
            raise self.refusal(self.damage)
        try:
            return self._load()
        except (ValueError, KeyError, TypeError, AttributeError, sqlite3.Error) as e:
            raise self.refusal(f"the journal is damaged ({type(e).__name__}: {str(e)[:200]})") from None

    def _load(self) -> Saved | None:
        db = self._db
        if not self._has("meta"):
            return None
        row = db.execute("SELECT value FROM meta WHERE key = 'state'").fetchone()
        if row is None:
            return None
        meta = json.loads(row[0])
        return Saved(
            rules=str(meta["rules"]),
            run=str(meta.get("run", "")),
            lineage=str(meta.get("lineage", "")),
            counters={k: int(v) for k, v in meta.get("counters", {}).items()},
            clock=float(meta["clock"]),
            wall=float(meta["wall"]),
            context={
                n: (json.loads(v), float(s))
                for n, v, s in db.execute("SELECT name, value, stamp FROM context")
            },
            obligations=[json.loads(r) for (r,) in db.execute("SELECT record FROM obligations ORDER BY id")],
            outbox=[json.loads(r) for (r,) in db.execute("SELECT record FROM outbox ORDER BY id")],
            audit=None if meta.get("audit") is None else int(meta["audit"]),
            clock_kind=str(meta.get("clock_kind", "")),
            boot=str(meta.get("boot", "")),
        )

    def refusal(self, reason: str, audit: AuditLog | None = None) -> JournalError:
        """The error of a journal that cannot be trusted: ``reason``, the files, the two ways out."""
        files = f"{self.path} and {self.wal.name}" + (f", with the audit log {audit.path}" if audit else "")
        error = JournalError(
            f"{reason}. Starting from this journal would forget what the Manager committed; nothing was restored",
            where=str(self.path),
            hint=f"put back {files} from one backup taken while the Manager was stopped; or, to start afresh "
            "on purpose and forget that state, pass reset_journal=True once (--reset-journal on the command "
            "line; the reset and what was lost are recorded in the audit log)",
        )
        error.reason = reason
        return error

    def reset(self) -> dict[str, Any]:
        """Forget everything the journal holds (``Manager(..., reset_journal=True)``), then
        :meth:`start` it afresh. Returns what it said it held (run, lineage, next record ``seq``,
        time of its last commit), as far as it can still be read: for the ``journal-reset`` record."""
        held = self._peek()
        self._quiet()
        try:
            if self.damage is not None:  # an empty main file: its orphaned -wal file goes
                self._db.close()
                self.wal.unlink(missing_ok=True)
                self._had_wal = False
                self._db = self._connect(timeout=1.0)
                self.damage = None
                self._prepare()
            self._db.execute("BEGIN IMMEDIATE")
            for table in _TABLES:
                self._db.execute(f"DROP TABLE IF EXISTS {table}")
            self._db.execute("COMMIT")
        except (OSError, sqlite3.Error) as e:
            raise JournalError(
                f"cannot reset the journal: {_reason(e)}",
                where=str(self.path),
                hint=_hint(e, self.path, "delete the journal's files by hand, then start with a new journal"),
            ) from None
        self.suspect = None
        self.start()
        return held

    def _peek(self) -> dict[str, Any]:
        if self.damage is not None:
            return {}
        try:
            row = self._db.execute("SELECT value FROM meta WHERE key = 'state'").fetchone()
            meta = json.loads(row[0]) if row else {}
            held = {
                "run": meta.get("run"),
                "lineage": meta.get("lineage"),
                "record": meta.get("counters", {}).get("record"),
                "wall": meta.get("wall"),
            }
            return {k: v for k, v in held.items() if v is not None}
        except (sqlite3.Error, ValueError, TypeError, AttributeError):
            return {}

    def commit(self, change: Change, meta: Mapping[str, Any], clock: float) -> None:
        """Write one step: its state change and ``meta`` (counters, the audit log's length), atomically.

        JournalError if the write fails (nothing of it is kept); a full disk is named as such.
        """
        db = self._db
        try:
            self._lock.acquire()  # (the checkpointer holds it only to start the WAL afresh)
            db.execute("BEGIN IMMEDIATE")
            try:
                for table, key, rows in (
                    (
                        "context",
                        "name",
                        [(n, _value(cv[0]), cv[1]) for n, cv in change.context.items() if cv],
                    ),
                    ("obligations", "id", [(k, _dumps(r)) for k, r in change.obligations.items() if r]),
                    ("outbox", "id", [(k, _dumps(r)) for k, r in change.outbox.items() if r]),
                ):
                    gone = [(k,) for k, v in getattr(change, table).items() if v is None]
                    if gone:
                        db.executemany(f"DELETE FROM {table} WHERE {key} = ?", gone)
                    if rows:
                        marks = ", ".join("?" * len(rows[0]))
                        db.executemany(f"INSERT OR REPLACE INTO {table} VALUES ({marks})", rows)
                state = _dumps({**meta, "clock": clock, "wall": time.time()})
                db.execute("INSERT OR REPLACE INTO meta VALUES ('state', ?)", (state,))
                db.execute("COMMIT")
                bg = self._bg
                if bg is not None:
                    bg.commits += 1
                    if not bg.commits % self.checkpoint_commits:
                        bg.wake.set()
            except BaseException:
                # SQLite has already rolled back after some errors (a full disk): a second
                # rollback would fail and hide the first error
                if db.in_transaction:
                    with contextlib.suppress(sqlite3.Error):
                        db.execute("ROLLBACK")
                raise
            finally:
                self._lock.release()
        except sqlite3.Error as e:
            raise JournalError(
                f"cannot write the journal: {_reason(e)}",
                where=str(self.path),
                hint=_hint(e, self.path, "restart the Manager: the journal has the last committed state"),
            ) from None

    def close(self) -> None:
        """Clear the running mark and close the database; the journal keeps what was committed.

        Never raises. SQLite copies the ``-wal`` file into the database and deletes it when it
        closes; it is kept (under a second name while SQLite closes, then put back) when the
        mark cannot be cleared (a full disk: the mark then meets its ``-wal`` file on the next
        start, as after a crash, and is not taken for a loss), and when the journal was only
        looked at (refused, or never started): what the next start sees is what this one saw.
        """
        self._quiet()  # before SQLite's last close copies the WAL in (and, unless kept, deletes it)
        keep = self._had_wal and not self._started
        if self._started:
            try:
                if self._db.in_transaction:
                    self._db.execute("ROLLBACK")
                self._db.execute("DELETE FROM meta WHERE key = 'running'")
            except sqlite3.Error:
                keep = True
        kept: Path | None = self._kept() if keep else None
        if kept is not None:
            try:
                kept.unlink(missing_ok=True)
                os.link(self.wal, kept)  # a second name for the same file: no space needed
            except OSError:
                kept = None
        with contextlib.suppress(sqlite3.Error):
            self._db.close()
        self._started = False
        if kept is not None:
            with contextlib.suppress(OSError):
                if self.wal.exists():  # SQLite did not delete it: the second name is not needed
                    kept.unlink()
                else:
                    os.replace(kept, self.wal)
        self._unlock()


class _Background:
    """What a Journal shares with its checkpointer's thread -- never the Journal itself, which
    the thread reaches through a weak reference: a Journal dropped without ``close()`` is
    collected as before, and its finalizer stops the thread."""

    db: sqlite3.Connection  # holds the WAL (a read transaction), starts it afresh
    ck: sqlite3.Connection  # checkpoints

    def __init__(self) -> None:
        self.wake = threading.Event()  # set every ``checkpoint_commits`` commits, and to stop
        self.stopping = False
        self.thread: threading.Thread | None = None
        self.commits = 0  # commits so far (counted under the journal's lock)
        self.copied = 0  # ``commits`` when the WAL was last copied whole
        self.frames = 0  # pages in the WAL at the last checkpoint, 0 once started afresh
        self.failures = 0  # rounds failed in a row
        self.nudged = False  # this round was woken (by commits), not by the end of its wait

    def stop(self) -> None:
        """Ask the thread to end (it does at once, or after the checkpoint it is in)."""
        self.stopping = True
        self.wake.set()

    def close(self) -> None:
        """Close the connections (the thread's last act)."""
        for name in ("db", "ck"):
            db = getattr(self, name, None)
            if db is not None:
                with contextlib.suppress(sqlite3.Error):
                    db.close()


def _checkpointing(ref: weakref.ref[Journal], bg: _Background, wait: float) -> None:
    """The checkpointer's thread: a round when woken or ``wait`` seconds after the last one,
    until stopped or its Journal is gone; then it closes its connections."""
    try:
        while True:
            bg.nudged = bg.wake.wait(wait)
            bg.wake.clear()
            next_wait = None if bg.stopping else _round(ref, bg)
            if next_wait is None:
                return
            wait = next_wait
    finally:
        bg.close()


def _round(ref: weakref.ref[Journal], bg: _Background) -> float | None:
    """One round; how long to wait for the next (longer after failures), None when the Journal is gone.

    A round that fails (a full disk, a lock held by another program) is logged, once until
    one succeeds, and tried again later: the commits go on, in the WAL.
    """
    journal = ref()
    if journal is None:
        return None
    try:
        journal._checkpoint(bg)
    except Exception as e:  # never raised into a step: the commits are safe in the WAL
        with contextlib.suppress(sqlite3.Error):
            _release(bg.db)
        bg.failures += 1
        if bg.failures == 1:
            log.warning("journal %s: a checkpoint failed, tried again later: %s", journal.path, _reason(e))
    else:
        if bg.failures:
            log.warning("journal %s: checkpoints work again", journal.path)
        bg.failures = 0
    return journal.checkpoint_idle * (1 << min(bg.failures, 5))


def _hold(db: sqlite3.Connection) -> None:
    """A read transaction on ``db`` from now: while it lasts, no write can start the WAL afresh."""
    _release(db)
    db.execute("BEGIN")
    db.execute("SELECT count(*) FROM meta").fetchone()


def _release(db: sqlite3.Connection) -> None:
    """End ``db``'s read transaction, if it has one."""
    if db.in_transaction:
        db.execute("COMMIT")


def _passive(db: sqlite3.Connection) -> tuple[int, int, int]:
    """A PASSIVE checkpoint: (busy, pages in the WAL, pages of it now in the database)."""
    busy, frames, copied = db.execute("PRAGMA wal_checkpoint(PASSIVE)").fetchone()
    return int(busy), int(frames), int(copied)


def _start_afresh(db: sqlite3.Connection) -> None:
    """A write that starts a WAL copied whole afresh (its header written and fsynced: SQLite
    does it in the first write after such a checkpoint), so that no step's commit does."""
    db.execute("BEGIN IMMEDIATE")
    try:
        db.execute("INSERT OR REPLACE INTO meta VALUES ('checkpoint', ?)", (str(time.time()),))
        db.execute("COMMIT")
    except BaseException:
        if db.in_transaction:
            with contextlib.suppress(sqlite3.Error):
                db.execute("ROLLBACK")
        raise


def verify(journal: Journal, saved: Saved | None, audit: AuditLog | None) -> str | None:
    """Why ``saved`` (what ``journal`` holds) may be less than was committed; None when it is all.

    Reads at most the audit log's records of two steps after the journal's end, the record
    before it, and -- for an empty journal only -- back to the log's last ``restored`` record.
    """
    if journal.suspect is not None and not _complete(saved, audit):
        return journal.suspect
    if audit is None:
        return None
    if saved is None:  # (the log's last step may be a first life's, killed before its commit)
        last = audit.last_of("restored", before=audit.last_step()) if audit.size else None
        if last is None:
            return None  # a new journal, beside a new log or one no journaled Manager wrote
        lineage = last.get("lineage") or (last.get("run") if last.get("from") is None else None) or "unknown"
        return (
            f"the journal {journal.path.name} holds no state, but the audit log {audit.path.name} continues "
            f"a journaled history (lineage {lineage}, records up to seq {audit.last_seq})"
        )
    if saved.audit is None or audit.size < saved.audit:
        return None  # no log then, or a log shorter than committed: the Manager records the mismatch
    record = saved.counters.get("record", 1)
    if not _ends_at(saved, audit):
        return (
            f"the audit log {audit.path.name} does not continue where the journal {journal.path.name} stopped "
            f"(record seq {record - 1} of run {saved.run} ending at byte {saved.audit}): "
            "the log was changed, or belongs to another journal"
        )
    tail = audit.steps_after(saved.audit)
    steps = {(r.get("run"), r.get("mono"), r.get("wall")) for r in tail}
    if len(steps) > 1 or (tail and tail[0].get("seq") != record):
        return (
            f"the journal {journal.path.name} is older than the audit log {audit.path.name}: the log holds "
            f"committed records after the journal's last commit (seq {record - 1}, lineage {saved.lineage}) "
            f"up to seq {audit.last_seq}"
        )
    return None


def _ends_at(saved: Saved, audit: AuditLog) -> bool:
    """Does the journal's last commit end the log where it says, with its last record?"""
    if not saved.audit:
        return True
    rec = audit.record_before(saved.audit)
    return (
        rec is not None
        and rec.get("seq") == saved.counters.get("record", 1) - 1
        and rec.get("run") == saved.run
    )


def _complete(saved: Saved | None, audit: AuditLog | None) -> bool:
    """Does the audit log prove that ``saved`` is the last commit (nothing after it)?"""
    return (
        saved is not None
        and audit is not None
        and saved.audit is not None
        and audit.size == saved.audit
        and _ends_at(saved, audit)
    )


def lost(held: Mapping[str, Any], audit: AuditLog | None, reason: str) -> dict[str, Any]:
    """The ``journal-reset`` record's data: why, and the history given up (lineage, last ``seq``)."""
    lineage = held.get("lineage")
    if not lineage and audit is not None:
        last = audit.last_of("restored")
        lineage = None if last is None else last.get("lineage") or last.get("run")
    return {
        "reason": reason,
        "lineage": lineage,
        "last_seq": audit.last_seq if audit is not None else None,
        "journal": dict(held) or None,
    }


def _full(e: BaseException) -> bool:
    """Is ``e`` a full disk (or quota)?"""
    if isinstance(e, OSError):
        return e.errno in (errno.ENOSPC, errno.EDQUOT)
    return isinstance(e, sqlite3.Error) and (
        getattr(e, "sqlite_errorcode", None) == sqlite3.SQLITE_FULL or "disk is full" in str(e)
    )


def _reason(e: BaseException) -> str:
    """``e`` in words, a full disk named as such."""
    text = (e.strerror if isinstance(e, OSError) else None) or str(e)
    return f"the disk is full ({text})" if _full(e) else text


def _hint(e: BaseException, path: Path, otherwise: str) -> str:
    if _full(e):
        return (
            f"free space on the disk that holds {path.parent}, then start the Manager again: "
            "the journal keeps what it committed"
        )
    return otherwise


#: ``json.dumps(record, default=str, separators=(",", ":"))``, as the audit log writes it
#: (orjson where it writes alike: :func:`cosleec.records.encode.encode`)
_dumps: Callable[[Mapping[str, Any]], str] = encode
_plain = json.JSONEncoder().encode  # what ``json.dumps(x)`` gives, without its call's checks


def _value(x: object) -> str:
    """A measure's value as the journal keeps it (``json.dumps(x)``); a boolean without a call."""
    return "true" if x is True else "false" if x is False else _plain(x)
