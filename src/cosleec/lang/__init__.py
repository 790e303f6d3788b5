"""The SLEEC language: parsing (both dialects and the paper notation), checking, printing.

Typical use::

    from cosleec.lang import load
    spec = load("rules.sleec")          # raises SleecError with every diagnostic

    result = analyse_file("rules.sleec")  # never raises for bad input
    print(result.render())

Rule priorities (cosleec's extension, a file's ``priority_start`` block) are
``spec.priorities``; priorities from elsewhere go through ``parse_priority("Rule21 > Rule3")``,
and ``closure`` and ``cycle`` answer questions about any set of pairs (priorities.py).
The clause semantics a file declares (its ``semantics_start`` block) is
``spec.clause_semantics``; ``clause_semantics_for(spec, given)`` is the one rule for which
semantics to read it with (declared.py).
How rules are read -- clause semantics, unknowns, untimed responses, priorities -- is one
value, :class:`Reading` (reading.py): the runtime, the reference semantics, ``conforms`` and
``analyse`` take it, and it is the audit log's ``options`` record.

Other packages import from here only; the pipeline itself is in frontend.py.
"""

from __future__ import annotations

from cosleec.lang import ast, priorities, visit
from cosleec.lang.ast import Dialect, Specification
from cosleec.lang.checker import Options, SymbolTable, check
from cosleec.lang.declared import clause_semantics_for
from cosleec.lang.deep import deeply
from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink, Severity, SleecError
from cosleec.lang.dialect import legos_features, legos_misreads
from cosleec.lang.extents import rule_extents
from cosleec.lang.formatter import format_source
from cosleec.lang.frontend import DIALECTS, CheckResult, analyse, analyse_file, load, parse, read_source
from cosleec.lang.hedges import HedgeSemantics, Unknowns, candidates, choose, decisive
from cosleec.lang.incremental import IncrementalAnalyser, Reuse
from cosleec.lang.infer import infer_definitions
from cosleec.lang.parser import CONTEXTUAL_KEYWORDS, KEYWORDS, PAPER_KEYWORDS
from cosleec.lang.printer import WIDTH, PaperPrinter, Printer, format_spec
from cosleec.lang.priorities import (
    CANCEL,
    CONFLICT_AWARE,
    PRIORITY_SEMANTICS,
    PrioritySemantics,
    closure,
    cycle,
    pairs,
    parse_priority,
)
from cosleec.lang.reading import IMMEDIATE_S, Reading, Untimed, one_of, parse_untimed

__all__ = [
    "CANCEL",
    "CONFLICT_AWARE",
    "CONTEXTUAL_KEYWORDS",
    "DIALECTS",
    "IMMEDIATE_S",
    "KEYWORDS",
    "PAPER_KEYWORDS",
    "PRIORITY_SEMANTICS",
    "WIDTH",
    "CheckResult",
    "Diagnostic",
    "DiagnosticSink",
    "Dialect",
    "HedgeSemantics",
    "IncrementalAnalyser",
    "Options",
    "PaperPrinter",
    "Printer",
    "PrioritySemantics",
    "Reading",
    "Reuse",
    "Severity",
    "SleecError",
    "Specification",
    "SymbolTable",
    "Unknowns",
    "Untimed",
    "analyse",
    "analyse_file",
    "ast",
    "candidates",
    "check",
    "choose",
    "clause_semantics_for",
    "closure",
    "cycle",
    "decisive",
    "deeply",
    "format_source",
    "format_spec",
    "infer_definitions",
    "legos_features",
    "legos_misreads",
    "load",
    "one_of",
    "pairs",
    "parse",
    "parse_priority",
    "parse_untimed",
    "priorities",
    "read_source",
    "rule_extents",
    "visit",
]
