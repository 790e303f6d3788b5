"""Rule-set analysis: conflicting, redundant and dead rules, found before the robot runs them.

``cosleec analyse`` is built here, on z3 and on the reference semantics
(:mod:`cosleec.semantics`): every question is a satisfiability question over the finite
timed traces of the rules (:mod:`~cosleec.analysis.encoding`), every unsat core is
minimised the same way every run (:mod:`~cosleec.analysis.cores`), and every witness trace
is judged by the reference semantics before it is shown (:mod:`~cosleec.analysis.witness`).
Depends on :mod:`cosleec.lang` and :mod:`cosleec.semantics` only.

Typical use::

    from cosleec.analysis import Settings, analyse_file
    report = analyse_file("rules.sleec", Settings())
    for f in report.findings:
        print(f.diagnostic().render(report.source))

A :class:`Deadline` (``analyse_file(..., deadline=Deadline.after(60))``) bounds a whole run,
where ``Settings.timeout`` bounds one solver question: the report is then partial, and
``FileReport.undecided`` says what was not decided.

The encoding itself (:class:`Encoding`, its :class:`Slot`, and the witness helpers) is public
for the tools built on the analysis: :mod:`cosleec.repair` asks its own questions with it
(what else a patch changes).
"""

from __future__ import annotations

from cosleec.analysis.checks import DEFAULT_BOUND, Settings
from cosleec.analysis.deadline import Deadline, OutOfTime
from cosleec.analysis.encoding import Encoding, Slot, as_float
from cosleec.analysis.findings import BOUNDED, CHECKS, MORE, PROVED, FileReport, Finding, Witness
from cosleec.analysis.run import Coverage, analyse_file, analyse_spec
from cosleec.analysis.sarif import sarif
from cosleec.analysis.witness import final_breaches, smallest, snapshot, steps

__all__ = [
    "BOUNDED",
    "CHECKS",
    "DEFAULT_BOUND",
    "MORE",
    "PROVED",
    "Coverage",
    "Deadline",
    "Encoding",
    "FileReport",
    "Finding",
    "OutOfTime",
    "Settings",
    "Slot",
    "Witness",
    "analyse_file",
    "analyse_spec",
    "as_float",
    "final_breaches",
    "sarif",
    "smallest",
    "snapshot",
    "steps",
]
