"""The records of a run: what observers hear and the audit log keeps, one per state change.

Defined here, below both :mod:`cosleec.runtime` (which writes them) and
:mod:`cosleec.semantics` (which reads an audit log back to judge it), so that both name the
same thing -- the format, never what a record means for the rules:

- :class:`Kind`: every kind of record (:mod:`cosleec.records.kinds`);
- :data:`FIELDS`: the fields each kind carries, their types, which a reader may rely on
  (:mod:`cosleec.records.fields`);
- :class:`RuntimeEvent`: a record as observers hear it (:mod:`cosleec.records.event`);
- :func:`audit_lines`: the one writer of audit lines (:mod:`cosleec.records.encode`);
- :func:`read_records` and :func:`records_in`: the one reader, giving :class:`AuditRecord`
  values and refusing a line that is not a record with ``file:line``
  (:mod:`cosleec.records.read`).
"""

from cosleec.records.encode import as_object, audit_lines, encode
from cosleec.records.event import RuntimeEvent
from cosleec.records.fields import FIELDS, HEADER, Field, Json, problem
from cosleec.records.kinds import Kind
from cosleec.records.read import (
    AuditRecord,
    RecordError,
    check_fields,
    load_json,
    read_records,
    records_in,
    seconds,
    starts_audit_log,
)

__all__ = [
    "FIELDS",
    "HEADER",
    "AuditRecord",
    "Field",
    "Json",
    "Kind",
    "RecordError",
    "RuntimeEvent",
    "as_object",
    "audit_lines",
    "check_fields",
    "encode",
    "load_json",
    "problem",
    "read_records",
    "records_in",
    "seconds",
    "starts_audit_log",
]
