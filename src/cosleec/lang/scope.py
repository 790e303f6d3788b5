"""What the checker's passes share while they check one specification (checker.py runs them).

:class:`Options` says what the checker is strict about; :class:`SymbolTable` is what the
names denote, the checker's result; :class:`Scope` is one run: the specification, the sink
its diagnostics go to, the table the declarations fill, the scale literals they make (with
the measures that own each), and the "did you mean" answers given so far.

May import: errors, and the lang modules ast, diagnostics and hedges.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cosleec.errors import closest
from cosleec.lang import ast as A
from cosleec.lang import hedges
from cosleec.lang.diagnostics import QUOTE_LIMIT, DiagnosticSink, clip


@dataclass(frozen=True)
class Options:
    """What the checker should be strict about."""

    strict_precedence: bool = False  # mixed and/or without parentheses is an error
    strict_extensions: bool = False  # cosleec extensions (response conjunction, priorities) are errors
    lint: bool = False  # naming conventions and style suggestions
    tk_names: bool = False  # warn about names SLEEC-TK rejects
    # for the hedge lint, when the file declares no semantics (its semantics block comes first)
    semantics: hedges.HedgeSemantics = hedges.HedgeSemantics.LAST_WINS
    # per rule (or concern, purpose), diagnostics of one code kept before the rest are
    # folded into one "... and N more" summary (DiagnosticSink.folding); 0 keeps them all
    repeat_limit: int = 20
    # read what LEGOS-SLEEC lets through as it does (cross-scale literals, scales compared
    # with numbers, duplicate rule, concern and purpose names): a warning each, and
    # check_and_read's specification carries LEGOS-SLEEC's reading (compat.py)
    legos_compat: bool = False


@dataclass
class SymbolTable:
    """What the names of a specification denote, after checking."""

    events: dict[str, A.EventDecl] = field(default_factory=dict)
    measures: dict[str, A.MeasureDecl] = field(default_factory=dict)
    constants: dict[str, A.ConstantDecl] = field(default_factory=dict)
    constant_values: dict[str, int] = field(default_factory=dict)

    def kind(self, name: str) -> str | None:
        """What ``name`` is declared as: ``"event"``, ``"measure"``, ``"constant"``, else None."""
        if name in self.events:
            return "event"
        if name in self.measures:
            return "measure"
        if name in self.constants:
            return "constant"
        return None


@dataclass
class Scope:
    """One run of the checker over ``spec``: what every pass reads, and what the
    declarations pass (declarations.py) fills in for the passes after it."""

    spec: A.Specification
    sink: DiagnosticSink
    opt: Options
    table: SymbolTable = field(default_factory=SymbolTable)
    scale_literals: set[str] = field(default_factory=set)
    owners_of: dict[str, list[str]] = field(
        default_factory=dict
    )  # scale literal -> the measures whose scale has it
    _suggestions: dict[tuple[str, str], str | None] = field(default_factory=dict, init=False, repr=False)

    def owners(self, lit: str) -> str:
        """The measures whose scale has ``lit``, for a message: `` `a`, `b` `` without the outer
        backticks, cut to a bounded length. Looked up in a table built with the declarations,
        not by a walk over every measure per comparison."""
        return clip("`, `".join(self.owners_of.get(lit, ())), 4 * QUOTE_LIMIT)

    def did_you_mean(self, name: str, among: str, code: str) -> str | None:
        """A "did you mean" hint for an undeclared ``name``: the closest declared name among
        the ``events``, the ``constants`` or the ``values`` (measures and constants).

        The search reads every declared name, so it is done only for a diagnostic with
        ``code`` that will be shown (not folded, :meth:`DiagnosticSink.shown`), and once per
        name: otherwise thousands of clauses misnaming a measure, in a file declaring
        thousands, would cost their product.
        """
        if not self.sink.shown(code):
            return None
        key = (name, among)
        if key not in self._suggestions:
            t = self.table
            pool: list[str] = (
                list(t.events)
                if among == "events"
                else list(t.constants)
                if among == "constants"
                else [*t.measures, *t.constants]
            )
            close = closest(name, pool, cutoff=0.75)
            self._suggestions[key] = f"did you mean `{clip(close)}`?" if close else None
        return self._suggestions[key]


__all__ = ["Options", "Scope", "SymbolTable"]
