"""The files a run's timeline is read from: a Manager's audit log or a Manager node's MCAP recording.

Both hold the runtime's records, ``{"kind": ..., "time": ..., **data}``. Nothing here reads
a record's fields (:mod:`cosleec.views.timeline` does); the readers are those that exist: an
audit log is checked line by line by :func:`cosleec.semantics.read_recording` (a bad line is
reported as ``file:line:col``, a torn last line is skipped) and read by
:func:`cosleec.runtime.read_audit`; a recording by :func:`cosleec.nodes.read_recording`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import read_recording as read_mcap
from cosleec.runtime import read_audit
from cosleec.semantics import read_recording

AUDIT_SUFFIXES = (".jsonl", ".ndjson")
"""The endings of an audit log (JSON Lines) that :func:`read_records` takes."""

MCAP_SUFFIXES = (".mcap",)
"""The ending of a Manager node's recording that :func:`read_records` takes."""


def read_records(path: str | Path) -> list[dict[str, Any]]:
    """The runtime records of an audit log (``.jsonl``, ``.ndjson``) or a recording (``.mcap``), in order.

    Raises :class:`UserError` for a file that is missing, empty, not what its name says or
    holds a line that is not JSON (``file:line:col``), and for a name that ends otherwise.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in AUDIT_SUFFIXES + MCAP_SUFFIXES:
        raise UserError(
            f"cannot tell what {p.name} is: {p.suffix or 'no extension'}",
            where=str(path),
            hint="give an audit log (.jsonl: cosleec demo --audit FILE.jsonl, Manager(audit=...)) "
            "or a Manager node's recording (.mcap: --record FILE.mcap)",
        )
    what = "the recording" if suffix in MCAP_SUFFIXES else "the audit log"
    if p.is_dir():
        raise UserError(f"cannot read {what}: it is a directory", where=str(path), hint="give the file")
    try:
        size = p.stat().st_size
        with p.open("rb"):
            pass
    except OSError as e:
        raise UserError(
            f"cannot read {what}: {e.strerror or e}",
            where=str(path),
            hint="check the path (relative paths are from the current directory)"
            if isinstance(e, FileNotFoundError)
            else "check the file's permissions",
        ) from None
    if size == 0:
        raise UserError(f"{what} is empty: there is no run to draw", where=str(path))
    return _mcap_records(p) if suffix in MCAP_SUFFIXES else _audit_records(p)


def _audit_records(p: Path) -> list[dict[str, Any]]:
    """The records of an audit log, after :func:`cosleec.semantics.read_recording` found every line sound."""
    if not p.read_bytes().strip():
        raise UserError("the audit log is empty: there is no run to draw", where=str(p))
    recording = read_recording(p)  # TraceError (a UserError) at file:line for a bad line
    if not recording.audit:
        raise UserError(
            "this is not an audit log: its first line is not a record the Manager wrote "
            "(a JSON object with seq, kind and time)",
            where=f"{p}:1",
            hint="give the file a Manager wrote with audit=... (cosleec demo --audit FILE.jsonl); "
            "a written trace is judged by cosleec conforms",
        )
    return read_audit(p)


def _mcap_records(p: Path) -> list[dict[str, Any]]:
    """The runtime records of a recording's ``/…/<kind>`` channels, in the order written: a
    rosbag2 recording (``--record-format ros2``, the default) or its JSON copy (``json``)."""
    try:
        messages = read_mcap(p)
    except ModuleNotFoundError as e:
        raise UserError(
            f"reading an MCAP recording needs the `mcap` package ({e.name} is missing)",
            where=str(p),
            hint="pip install 'cosleec[record]'",
        ) from None
    except UserError as e:  # not MCAP, or a channel of a type that holds no record: said where
        e.where = e.where or str(p)
        raise
    records = [m for _, m in messages if isinstance(m, dict) and isinstance(m.get("kind"), str)]
    if not records:
        raise UserError(
            "the recording holds no runtime record: it is not an MCAP file a Manager node wrote, "
            "or it was cut before its first record",
            where=str(p),
            hint="give the file of a Manager node's --record FILE.mcap",
        )
    return records
