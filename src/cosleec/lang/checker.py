"""Static semantics of SLEEC (docs/reference/sleec-language.md §5): names, kinds, types, constants.

Every problem of a file is reported in one pass, as a diagnostic with a stable code. The
checker also resolves the information later stages need (constant values, each scale
literal's measure), exposed as a :class:`SymbolTable`.

:class:`Checker` runs the passes in file order, each over one concern, sharing one
:class:`~cosleec.lang.scope.Scope`: the def block (declarations.py), the rules (here: their
names; their triggers and responses, responses.py, whose expressions are typed by
expressions.py and whose ``unless`` clauses are asked about by unreachable.py), LEGOS-SLEEC's
concern, purpose and relation blocks (legos.py), the priorities (priorities.py) and the
declared clause semantics (declared.py). Under
``legos_compat`` what LEGOS-SLEEC lets through is read as it reads it (compat.py).
"""

from __future__ import annotations

from cosleec.lang import ast as A
from cosleec.lang.compat import LegosReader, LegosReading, apply
from cosleec.lang.declarations import Declarations, check_name
from cosleec.lang.declared import check_semantics
from cosleec.lang.diagnostics import DiagnosticSink, clip
from cosleec.lang.expressions import Expressions
from cosleec.lang.legos import check_relations, check_situations
from cosleec.lang.priorities import check_priorities
from cosleec.lang.responses import Responses
from cosleec.lang.scope import Options, Scope, SymbolTable


class Checker:
    """One run of the checks over ``spec``: :meth:`run` reports to ``sink`` and returns the
    symbol table; :attr:`reading` is then what ``legos_compat`` reads differently."""

    def __init__(self, spec: A.Specification, sink: DiagnosticSink, options: Options) -> None:
        self.scope = Scope(spec, sink, options)
        self.legos = LegosReader(self.scope)
        self.responses = Responses(self.scope, Expressions(self.scope, self.legos))

    @property
    def reading(self) -> LegosReading:
        """LEGOS-SLEEC's reading of the defects ``legos_compat`` lets through (compat.py)."""
        return self.legos.reading

    def run(self) -> SymbolTable:
        """Every check, in the order the diagnostics come out; the resolved symbol table."""
        scope = self.scope
        spec, sink = scope.spec, scope.sink
        if not spec.has_def_block:
            sink.error(
                "no-def-block",
                "no def block: events and measures are not declared",
                spec.rules[0].span if spec.rules else A.NO_SPAN,
                hint="add `def_start ... def_end`, or run with --infer-defs to infer the declarations",
            )
            return scope.table
        Declarations(scope).check()
        if not spec.rules and any(b.kind == "rule" for b in spec.blocks):
            mark = next(b for b in spec.blocks if b.kind == "rule")
            sink.error("empty-rule-block", "empty rule block: a rule set needs at least one rule", mark.span)
        self._rules()
        check_situations(scope, self.responses, self.legos)
        check_relations(scope, self.responses)
        check_priorities(
            spec,
            sink,
            kind=scope.table.kind,
            strict=scope.opt.strict_extensions,
            repeat_limit=scope.opt.repeat_limit,
        )
        check_semantics(spec, sink, strict=scope.opt.strict_extensions)
        return scope.table

    def _rules(self) -> None:
        """Every rule: a name of its own (a second one of a name is kept under a new name
        under ``legos_compat``), its trigger and its response."""
        scope = self.scope
        rules, sink, opt = scope.spec.rules, scope.sink, scope.opt
        names: dict[str, A.Rule] = {}
        nth: dict[str, int] = {}
        for i, r in enumerate(rules):
            if r.name in names:
                related = ((f"`{clip(r.name)}` first defined here", names[r.name].span),)
                if opt.legos_compat:
                    new = self.legos.rename(self.legos.reading.rules, i, r.name, nth, rules)
                    sink.warning(
                        "duplicate-rule",
                        f"rule `{clip(r.name)}` is defined twice; LEGOS-SLEEC keeps both rules (it "
                        f"never compares rule names), and so does cosleec, calling this one `{clip(new)}`",
                        r.span,
                        related=related,
                        hint="give each rule a name of its own",
                    )
                else:
                    sink.error(
                        "duplicate-rule", f"rule `{clip(r.name)}` is defined twice", r.span, related=related
                    )
            else:
                names[r.name] = r
            check_name(scope, r.name, r.span)
            # a rule's clauses can repeat one mistake thousands of times: report some, count the rest
            with sink.folding(f"rule `{clip(r.name)}`", opt.repeat_limit):
                self.responses.trigger(r.trigger)
                self.responses.response(r.response)


def check(spec: A.Specification, sink: DiagnosticSink, options: Options | None = None) -> SymbolTable:
    """Check ``spec``; diagnostics go to ``sink``. Returns the resolved symbol table."""
    return Checker(spec, sink, options or Options()).run()


def check_and_read(
    spec: A.Specification, sink: DiagnosticSink, options: Options | None = None
) -> tuple[A.Specification, SymbolTable]:
    """:func:`check`, and the specification as the checks read it: ``spec`` itself, except
    under ``legos_compat``, where it is rebuilt with LEGOS-SLEEC's reading of the defects
    that option lets through (:mod:`cosleec.lang.compat`)."""
    checker = Checker(spec, sink, options or Options())
    table = checker.run()
    return apply(spec, checker.reading), table


__all__ = ["Options", "SymbolTable", "check", "check_and_read"]
