"""The audit log writes a step's records through the one writer and reads them back through the
one reader (issue 29, part 3): built alone, without a Manager."""

from __future__ import annotations

import json
import math
from pathlib import Path

from cosleec.records import Kind, RuntimeEvent, audit_lines
from cosleec.runtime import AuditLog, read_audit

DIGEST = "0123456789abcdef0123456789abcdef"


def step() -> list[RuntimeEvent]:
    return [
        RuntimeEvent.made(Kind.DECISION, 9.0, {"id": 3, "time": 4.5, "rule": "R1"}, 1),
        RuntimeEvent.made(Kind.RESTORED, 9.0, {}, 2),
        RuntimeEvent.made(Kind.OCCURRENCE, math.inf, {"event": "E"}, 3),
    ]


def test_write_events_writes_the_writers_lines_and_returns_the_length(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    log = AuditLog(path)
    end = log.write_events(step(), run="run-1", rules=DIGEST)
    text = path.read_text()
    assert end == len(text.encode()) == log.size and log.count == 3
    first = json.loads(text.splitlines()[0])
    assert first["rules"] == DIGEST[:16] and first["run"] == "run-1"
    # byte for byte what the writer makes of the step with the header the log used
    assert text == "".join(
        f"{line}\n"
        for line in audit_lines(step(), run="run-1", rules=DIGEST, wall=first["wall"], mono=first["mono"])
    )
    assert log.write_events([], run="run-1", rules=DIGEST) == end  # nothing to write: the length as it is
    log.close()


def test_read_audit_gives_each_records_object_and_skips_what_is_no_record(tmp_path: Path) -> None:
    path = tmp_path / "audit.jsonl"
    log = AuditLog(path)
    log.write_events(step(), run="run-1", rules=DIGEST)
    log.close()
    written = path.read_text().splitlines()
    with path.open("a") as fh:
        fh.write('garbage\n{"a": 1}\n{"seq":4,"kind":"event","ti')
    records = read_audit(path)
    assert records == [json.loads(line) for line in written]
    assert [r["kind"] for r in records] == ["decision", "restored", "event"]
    assert records[0]["time"] == 4.5 and written[0].count('"time"') == 1  # the decision's own time
    assert records[2]["time"] is None  # a time that was not finite, kept as the log has it
    assert all(type(r) is dict for r in records) and len(json.dumps(records[0])) > 0


def test_one_name_means_one_thing() -> None:
    """``read_audit`` is the records of an audit log; the trace a log records is ``read_audit_trace``."""
    import cosleec.semantics

    assert not hasattr(cosleec.semantics, "read_audit") and callable(cosleec.semantics.read_audit_trace)
