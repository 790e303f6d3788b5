"""The SLEEC language: parsing (both dialects and the paper notation), checking, printing.

Typical use::

    from cosleec.lang import load
    spec = load("rules.sleec")          # raises SleecError with every diagnostic

    result = analyse_file("rules.sleec")  # never raises for bad input
    print(result.render())

Other packages import from here only; the pipeline itself is in frontend.py.
"""

from __future__ import annotations

from cosleec.lang import ast
from cosleec.lang.ast import Dialect, Specification
from cosleec.lang.checker import Options, SymbolTable, check
from cosleec.lang.diagnostics import Diagnostic, DiagnosticSink, Severity, SleecError
from cosleec.lang.frontend import DIALECTS, CheckResult, analyse, analyse_file, load, parse, read_source
from cosleec.lang.hedges import HedgeSemantics, Unknowns, candidates, choose, decisive
from cosleec.lang.infer import infer_definitions
from cosleec.lang.printer import Printer, format_spec

__all__ = [
    "DIALECTS",
    "CheckResult",
    "Diagnostic",
    "DiagnosticSink",
    "Dialect",
    "HedgeSemantics",
    "Options",
    "Printer",
    "Severity",
    "SleecError",
    "Specification",
    "SymbolTable",
    "Unknowns",
    "analyse",
    "analyse_file",
    "ast",
    "candidates",
    "check",
    "choose",
    "decisive",
    "format_spec",
    "infer_definitions",
    "load",
    "parse",
    "read_source",
]
