"""The reference semantics of SLEEC: what a rule set requires of a timed trace.

Small and simple rather than fast (though linear in a trace's length): written from the
language reference, sharing no code with :mod:`cosleec.runtime`, it is the oracle the
runtime is tested against and what ``cosleec conforms`` judges recorded runs with. Depends
on :mod:`cosleec.lang` only: :func:`judge` reads the rules as a :class:`cosleec.lang.Reading`
says, and which reading a recorded run is judged under is :mod:`~cosleec.semantics.conformance`.
"""

from __future__ import annotations

from cosleec.lang import CANCEL, CONFLICT_AWARE
from cosleec.semantics import conformance
from cosleec.semantics.reference import judge
from cosleec.semantics.trace import (
    Recording,
    RunOptions,
    Step,
    TraceError,
    Value,
    check_trace,
    fit_trace,
    read,
    read_audit_trace,
    read_recording,
    read_trace,
)
from cosleec.semantics.verdicts import BLOCKED, BREACHES, Conflict, Firing, Judgement, Verdict

__all__ = [
    "BLOCKED",
    "BREACHES",
    "CANCEL",
    "CONFLICT_AWARE",
    "Conflict",
    "Firing",
    "Judgement",
    "Recording",
    "RunOptions",
    "Step",
    "TraceError",
    "Value",
    "Verdict",
    "check_trace",
    "conformance",
    "fit_trace",
    "judge",
    "read",
    "read_audit_trace",
    "read_recording",
    "read_trace",
]
