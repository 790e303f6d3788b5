"""An append-only JSON Lines audit trail that loses nothing when the process crashes.

Each record is written and flushed to the operating system before ``write`` returns; a
crash of the Python process cannot lose a record already written. ``fsync=True`` also
survives a crash of the machine, at a cost per record.
"""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path
from typing import Any, TextIO

from cosleec.errors import UserError


class AuditLog:
    """An append-only JSON Lines file of runtime events; pass one (or a path) as ``Manager(audit=...)``.

    Opening it creates missing parent directories and appends to an existing file.
    Thread-safe: records are written whole, one per line, in the order of the calls.
    ``count`` is the number of records this object wrote.
    """

    def __init__(self, path: str | Path, *, fsync: bool = False) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fh: TextIO = self.path.open("a", encoding="utf-8")
        except OSError as e:
            raise UserError(
                f"cannot open the audit log: {e.strerror or e}", where=str(path), hint="give a writable path"
            ) from None
        self._fsync = fsync
        self._lock = threading.Lock()
        self.count = 0

    def write(self, record: dict[str, Any]) -> None:
        """Append one record and flush it to the operating system before returning."""
        line = json.dumps(record, default=str, separators=(",", ":")) + "\n"
        with self._lock:
            self._fh.write(line)
            self._fh.flush()
            if self._fsync:
                os.fsync(self._fh.fileno())
            self.count += 1

    def close(self) -> None:
        """Close the file; later writes fail."""
        with self._lock:
            self._fh.close()


def read_audit(path: str | Path) -> list[dict[str, Any]]:
    """Every complete record of an audit log (a torn last line is skipped)."""
    out = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out
