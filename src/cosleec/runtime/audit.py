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
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any, BinaryIO

from cosleec.errors import UserError


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
            self.torn, self.last_seq = _repair(self.path)
            self._fh: BinaryIO = self.path.open("ab")
            self.size = self._fh.seek(0, os.SEEK_END)
        except OSError as e:
            raise UserError(
                f"cannot open the audit log: {e.strerror or e}", where=str(path), hint="give a writable path"
            ) from None
        self._fsync = fsync
        self._lock = threading.Lock()
        self.count = 0

    def write(self, record: dict[str, Any]) -> None:
        """Append one record and flush it to the operating system before returning."""
        self.write_many((record,))

    def write_many(self, records: Iterable[dict[str, Any]]) -> None:
        """Append records in order with one flush (and one fsync) for all of them."""
        self.write_lines(json.dumps(r, default=str, separators=(",", ":")) for r in records)

    def write_lines(self, lines: Iterable[str]) -> int:
        """Append records already encoded as one-line JSON texts, in order, with one flush.

        Returns the length of the log after them, in bytes (what a journal commits).
        """
        data = "".join(f"{line}\n" for line in lines).encode()
        with self._lock:
            if data:
                try:
                    self._fh.write(data)
                    self._fh.flush()
                    if self._fsync:
                        os.fsync(self._fh.fileno())
                except BaseException:
                    with contextlib.suppress(OSError, ValueError):  # what really reached the file
                        self.size = os.stat(self.path).st_size
                    raise
                self.count += data.count(b"\n")
                self.size += len(data)
            return self.size

    def cut(self, at: int) -> list[dict[str, Any]]:
        """Set aside everything after byte ``at`` (appended to ``<log>.uncommitted``); return those records.

        The Manager calls it on a restart with a journal: records written for a step whose
        commit never happened are not part of the history. ``last_seq`` becomes that of the
        last record kept.
        """
        with self._lock:
            self._fh.flush()
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

    def close(self) -> None:
        """Close the file; later writes fail."""
        with self._lock:
            self._fh.close()


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
    """Every complete record of an audit log (a torn last line is skipped)."""
    out = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out
