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
``synchronous=FULL``, at a cost per step). One connection, used under the Manager's lock.
"""

from __future__ import annotations

import json
import sqlite3
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosleec.errors import UserError

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS context (name TEXT PRIMARY KEY, value TEXT NOT NULL, stamp REAL NOT NULL);
CREATE TABLE IF NOT EXISTS obligations (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS outbox (id INTEGER PRIMARY KEY, record TEXT NOT NULL);
"""


class JournalError(UserError):
    """The journal cannot be opened or written (a path that is not writable, a full disk).

    A Manager whose journal fails stops deciding: every later call raises this error and
    :meth:`~cosleec.runtime.Manager.request` refuses, since its state can no longer be kept.
    """


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

    Not thread-safe by itself: the Manager calls it under its lock (the connection is
    allowed to move between threads for that reason).
    """

    def __init__(self, path: str | Path, *, fsync: bool = False) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None, timeout=1.0)
        except (OSError, sqlite3.Error) as e:
            raise JournalError(
                f"cannot open the journal: {e}",
                where=str(path),
                hint="give a writable path to a journal file",
            ) from None
        try:
            # one Manager per journal: the first write takes a lock held until close
            self._db.execute("PRAGMA locking_mode=EXCLUSIVE")
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute(f"PRAGMA synchronous={'FULL' if fsync else 'NORMAL'}")
            self._db.executescript(_SCHEMA)
            self._db.execute("INSERT OR REPLACE INTO meta VALUES ('opened', ?)", (str(time.time()),))
        except sqlite3.OperationalError as e:
            self._db.close()
            busy = "locked" in str(e)
            raise JournalError(
                "the journal is in use by another Manager" if busy else f"cannot use the journal: {e}",
                where=str(path),
                hint="stop the other Manager first, or give each Manager its own journal"
                if busy
                else "give the path of a cosleec journal, or a new file",
            ) from None
        except sqlite3.Error as e:
            self._db.close()
            raise JournalError(
                f"this is not a cosleec journal: {e}",
                where=str(path),
                hint="give a new file for a new journal",
            ) from None

    def load(self) -> Saved | None:
        """What the journal holds; None for a new journal; JournalError when it is damaged."""
        try:
            return self._load()
        except (ValueError, KeyError, TypeError, AttributeError, sqlite3.Error) as e:
            raise JournalError(
                f"the journal is damaged ({type(e).__name__}: {str(e)[:200]}); nothing was restored",
                where=str(self.path),
                hint="restore it from a backup (with its -wal file), or give a new file to start afresh",
            ) from None

    def _load(self) -> Saved | None:
        db = self._db
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

    def commit(self, change: Change, meta: Mapping[str, Any], clock: float) -> None:
        """Write one step: its state change and ``meta`` (counters, the audit log's length), atomically.

        JournalError if the write fails (nothing of it is kept).
        """
        db = self._db
        try:
            db.execute("BEGIN IMMEDIATE")
            try:
                for table, key, rows in (
                    (
                        "context",
                        "name",
                        [(n, json.dumps(cv[0]), cv[1]) for n, cv in change.context.items() if cv],
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
            except BaseException:
                db.execute("ROLLBACK")
                raise
        except sqlite3.Error as e:
            raise JournalError(f"cannot write the journal: {e}", where=str(self.path)) from None

    def close(self) -> None:
        """Close the database; the journal keeps what was committed."""
        self._db.close()


def _dumps(record: Mapping[str, Any]) -> str:
    return json.dumps(record, default=str, separators=(",", ":"))
