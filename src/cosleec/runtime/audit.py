"""An append-only JSON Lines audit trail that loses nothing when the process crashes.

Each record is written and flushed to the operating system before ``write`` returns; a
crash of the Python process cannot lose a record already written. ``fsync=True`` also
survives a crash of the machine, at a cost per record.

A crash in the middle of a write leaves a torn last line. Opening the log sets it aside --
appended to ``<log>.torn`` and cut from the log -- so it is never glued to the first
record of the next run. With a journal, the Manager writes a step's records here first and
then commits the step with the log's new length; records past the committed length on the
next start belong to a step that never happened, and :meth:`AuditLog.cut` sets them aside
to ``<log>.uncommitted`` (each record carries its sequence number, ``seq``).

One writer per log: opening it takes an exclusive lock on the file (``flock``), held until
:meth:`AuditLog.close`, so two Managers can never interleave their ``seq`` in one log.
Readers (``read_audit``, ``cosleec conforms``, ``cosleec timeline``) take no lock. The
format of a line is :mod:`cosleec.records`' (written by :meth:`AuditLog.write_events`).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import io
import json
import os
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from cosleec.errors import UserError
from cosleec.records import RuntimeEvent, audit_lines, read_records


class AuditLog:
    """An append-only JSON Lines file of runtime events; pass one (or a path) as ``Manager(audit=...)``.

    Opening it creates missing parent directories and appends to an existing file, after
    setting aside a torn last line (``torn`` is its text, ``None`` when there was none).
    ``last_seq`` is the ``seq`` of the last complete record found (0 if none); ``size`` the
    length of the log in bytes. Thread-safe: records are written whole, one per line, in the
    order of the calls. ``count`` is the number of records this object wrote.
    """

    def __init__(self, path: str | Path, *, fsync: bool = False) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # unbuffered: a write that fails leaves nothing behind to fail again at close
            self._fh: io.FileIO = io.FileIO(self.path, "a")
        except OSError as e:
            raise UserError(
                f"cannot open the audit log: {e.strerror or e}", where=str(path), hint="give a writable path"
            ) from None
        try:
            _lock(self._fh, self.path)  # before the repair: a torn line may be another writer's last
            self.torn, self.last_seq = _repair(self.path)
            self.size = self._fh.seek(0, os.SEEK_END)
        except BaseException as e:
            self._fh.close()
            if isinstance(e, OSError):
                raise UserError(
                    f"cannot open the audit log: {e.strerror or e}",
                    where=str(path),
                    hint="give a writable path",
                ) from None
            raise
        self._fsync = fsync
        self._lock = threading.Lock()
        self.count = 0

    def write(self, record: dict[str, Any]) -> None:
        """Append one record and flush it to the operating system before returning."""
        self.write_many((record,))

    def write_many(self, records: Iterable[dict[str, Any]]) -> None:
        """Append records in order with one flush (and one fsync) for all of them."""
        self.write_lines(json.dumps(r, default=str, separators=(",", ":")) for r in records)

    def write_events(self, events: Iterable[RuntimeEvent], *, run: str, rules: str) -> int:
        """Append one step's records as audit lines (:func:`cosleec.records.audit_lines`: one
        header -- wall and monotonic time, ``run``, the first 16 characters of the ``rules``
        digest -- for all of them) with one flush; returns what :meth:`write_lines` returns."""
        return self.write_lines(audit_lines(events, run=run, rules=rules))

    def write_lines(self, lines: Iterable[str]) -> int:
        """Append records already encoded as one-line JSON texts, in order, with one flush.

        Returns the length of the log after them, in bytes (what a journal commits). All or
        nothing: when the write fails (a full disk: OSError ``ENOSPC``), what reached the file
        of it is cut off again before the error is raised, so the log still ends with a whole
        record and a later :meth:`close` has nothing left to write.
        """
        data = "".join(f"{line}\n" for line in lines).encode()
        with self._lock:
            if data:
                try:
                    view, done = memoryview(data), 0
                    while done < len(data):
                        done += self._fh.write(view[done:]) or 0
                    if self._fsync:
                        os.fsync(self._fh.fileno())
                except OSError:
                    self._undo()
                    raise
                self.count += data.count(b"\n")
                self.size += len(data)
            return self.size

    def _undo(self) -> None:
        """Cut what a failed write left after the last whole record (truncating needs no space)."""
        try:
            os.ftruncate(self._fh.fileno(), self.size)
        except (OSError, ValueError):  # cannot: the next start sets a torn line aside
            with contextlib.suppress(OSError):
                self.size = os.stat(self.path).st_size

    def cut(self, at: int) -> list[dict[str, Any]]:
        """Set aside everything after byte ``at`` (appended to ``<log>.uncommitted``); return those records.

        The Manager calls it on a restart with a journal: records written for a step whose
        commit never happened are not part of the history. ``last_seq`` becomes that of the
        last record kept.
        """
        with self._lock:
            with self.path.open("rb+") as fh:
                if at > 0:  # only at a line boundary: a log edited by hand is not cut mid-record
                    fh.seek(at - 1)
                    if fh.read(1) != b"\n":
                        raise ValueError(f"byte {at} of the audit log is not the start of a record")
                fh.seek(at)
                tail = fh.read()
                if tail:
                    with self.path.with_name(self.path.name + ".uncommitted").open("ab") as aside:
                        aside.write(tail)
                    fh.truncate(at)
            self.size = at
            records = []
            for line in tail.splitlines():
                try:
                    rec = json.loads(line)
                except ValueError:
                    continue  # a torn or foreign line: set aside all the same
                if isinstance(rec, dict):
                    records.append(rec)
            if records and isinstance(records[0].get("seq"), int):
                self.last_seq = max(0, records[0]["seq"] - 1)
            return records

    def record_before(self, at: int) -> dict[str, Any] | None:
        """The record whose line ends at byte ``at`` (None: ``at`` is not the end of a whole record)."""
        if at <= 0 or at > self.size:
            return None
        with self._lock, self.path.open("rb") as fh:
            back = 65536
            while True:
                start = max(0, at - back)
                fh.seek(start)
                chunk = fh.read(at - start)
                if not chunk.endswith(b"\n"):
                    return None
                begin = chunk.rfind(b"\n", 0, len(chunk) - 1)
                if begin >= 0 or start == 0:
                    return _record(chunk[begin + 1 :])
                back *= 16  # a line longer than the chunk: read further back

    def steps_after(self, at: int, steps: int = 2) -> list[dict[str, Any]]:
        """The whole records after byte ``at``, up to the first ``steps`` steps of the Manager.

        All the records one Manager step writes share ``run``, ``mono`` and ``wall``
        (``Manager._commit`` writes them in one :meth:`write_lines`), so the records of
        ``steps + 1`` steps are never read: an old journal facing a long log costs no more
        than a fresh one. A partial first line (``at`` inside a record) and lines that are
        not JSON objects are skipped.
        """
        out: list[dict[str, Any]] = []
        seen: set[tuple[object, object, object]] = set()
        for rec in self._records(at):
            key = (rec.get("run"), rec.get("mono"), rec.get("wall"))
            if key not in seen:
                if len(seen) == steps:
                    break
                seen.add(key)
            out.append(rec)
        return out

    def _records(self, at: int) -> Iterator[dict[str, Any]]:
        with self.path.open("rb") as fh:
            fh.seek(max(0, at - 1))
            if at > 0 and fh.read(1) != b"\n":
                fh.readline()  # the rest of a record cut at ``at``
            for line in fh:
                rec = _record(line)
                if rec is not None:
                    yield rec

    def last_step(self) -> int:
        """Where the records of the log's last step begin (its length when it is empty): what
        a kill between writing a step's records and committing it may have left uncommitted."""
        with self._lock, self.path.open("rb") as fh:
            back = 65536
            while True:
                start = max(0, self.size - back)
                fh.seek(start)
                lines = fh.read(self.size - start).split(b"\n")[:-1]
                at, key = self.size, None
                for line in reversed(lines[1:] if start > 0 else lines):
                    rec = _record(line)
                    mine = None if rec is None else (rec.get("run"), rec.get("mono"), rec.get("wall"))
                    if rec is None or (key is not None and mine != key):
                        return at
                    key, at = mine, at - len(line) - 1
                if start == 0:
                    return at
                back *= 16  # a long step: read further back

    def last_of(self, kind: str, before: int | None = None) -> dict[str, Any] | None:
        """The last record of ``kind`` in the log (before byte ``before``; None: there is none),
        read backwards from the end.

        Used when a Manager opens an empty journal: it reads back only as far as the last
        such record (the whole log when there is none, once).
        """
        needle = f'"kind":{json.dumps(kind)}'.encode()
        with self._lock, self.path.open("rb") as fh:
            end = self.size if before is None else min(before, self.size)
            while end > 0:
                start = max(0, end - (1 << 20))
                fh.seek(start)
                chunk = fh.read(end - start)
                first = chunk.find(b"\n") + 1 if start > 0 else 0  # a line cut at ``start`` is read next time
                hit = chunk.rfind(needle, first)
                while hit >= 0:
                    line_start = chunk.rfind(b"\n", 0, hit) + 1
                    line_end = chunk.find(b"\n", hit)
                    rec = _record(chunk[line_start : line_end if line_end >= 0 else len(chunk)])
                    if rec is not None and rec.get("kind") == kind:
                        return rec
                    hit = chunk.rfind(needle, first, line_start)
                end = start + first if start > 0 else 0
            return None

    def close(self) -> None:
        """Close the file and release the lock; later writes fail. Never raises: a write that
        failed was reported by that write, and left nothing behind to write now."""
        with self._lock, contextlib.suppress(OSError):
            self._fh.close()


def _record(line: bytes) -> dict[str, Any] | None:
    """One JSON Lines line as a record (None: not a JSON object)."""
    try:
        rec = json.loads(line)
    except ValueError:
        return None
    return rec if isinstance(rec, dict) else None


def _lock(fh: io.FileIO, path: Path) -> None:
    """Take the one-writer lock of an audit log; UserError naming who holds it when it is taken."""
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        if e.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            raise
        holder = _holder(fh.fileno())
        raise UserError(
            f"the audit log is in use by another writer{holder}: two writers would interleave its records",
            where=str(path),
            hint="stop the Manager (or AuditLog) that writes it first, or give each Manager its own audit log",
        ) from None


def _holder(fd: int) -> str:
    """`` (process N)`` for the process holding the flock of ``fd``'s file, when /proc/locks says."""
    try:
        st = os.fstat(fd)
        ident = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
        with open("/proc/locks", encoding="ascii") as fh:
            for line in fh:
                parts = line.split()
                if "FLOCK" in parts and ident in parts and "->" not in parts:
                    pid = parts[parts.index(ident) - 1]
                    return f" (process {pid}{', this one' if pid == str(os.getpid()) else ''})"
    except (OSError, ValueError, IndexError):
        pass
    return ""


def _repair(path: Path) -> tuple[str | None, int]:
    """Set aside a torn last line (to ``<path>.torn``); return it and the last complete ``seq``."""
    if not path.exists():
        return None, 0
    with path.open("rb+") as fh:
        size = fh.seek(0, os.SEEK_END)
        start, chunk = size, b""
        # read back until the chunk holds the whole last line and the whole line before it
        while start > 0 and chunk.count(b"\n") < 3:
            start = max(0, start - 65536)
            fh.seek(start)
            chunk = fh.read(size - start)
        torn = None
        if chunk and not chunk.endswith(b"\n"):
            end = chunk.rfind(b"\n")  # -1: the whole file is one torn line
            torn = chunk[end + 1 :].decode("utf-8", "replace")
            with path.with_name(path.name + ".torn").open("ab") as aside:
                aside.write(chunk[end + 1 :] + b"\n")
            fh.truncate(start + end + 1)
            chunk = chunk[: end + 1]
    lines = chunk.rstrip(b"\n").split(b"\n")
    if start > 0:
        lines = lines[1:]  # the first may be cut
    seq = 0
    if lines and lines[-1]:
        try:
            rec = json.loads(lines[-1])
            if isinstance(rec, dict) and isinstance(rec.get("seq"), int):
                seq = rec["seq"]
        except ValueError:
            pass
    return torn, seq


def read_audit(path: str | Path) -> list[dict[str, Any]]:
    """Every record of an audit log, each as the JSON object of its line, in order.

    Read by the one reader (:func:`cosleec.records.read_records`), leniently: a line that is
    not a record (a torn last line, or what a crash or a hand left between records) is
    skipped. :func:`cosleec.records.read_records` gives typed records and refuses such lines.
    """
    return [record.to_json() for record in read_records(path, lenient=True)]
