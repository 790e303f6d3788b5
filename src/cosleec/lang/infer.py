"""Infer declarations for rule sets written without a def block.

Two kinds of input need it: the CO-SLEEC paper's notation (which never has one) and
rule-block fragments such as the SLEEC@run.time rulesets (``--infer-defs``). Inference is
from use: a trigger or response is an event; a name used as a truth value is a boolean
measure; a name compared with a number or used in arithmetic is numeric; a name compared
with a bare identifier is a scale measure whose literals are those identifiers.

Scale order cannot be seen in use, so it comes from a vocabulary of common graded words
when every literal is in it, and otherwise from order of first appearance -- with a
warning, because comparisons like ``>`` depend on it.
"""

from __future__ import annotations

from dataclasses import replace

from cosleec.lang import ast as A
from cosleec.lang import visit
from cosleec.lang.diagnostics import DiagnosticSink

# Graded words, lowest first, as they appear in the corpus' scales.
_GRADES = (
    "none",
    "null",
    "verylow",
    "very_low",
    "vlow",
    "low",
    "light",
    "minor",
    "mild",
    "slow",
    "moderate",
    "medium",
    "mid",
    "smedium",
    "average",
    "normal",
    "high",
    "shigh",
    "strong",
    "severe",
    "major",
    "veryhigh",
    "very_high",
    "vhigh",
    "critical",
    "extreme",
)
_RANK = {w: i for i, w in enumerate(_GRADES)}


def _order(literals: list[str]) -> tuple[tuple[str, ...], bool]:
    """(ordered literals, whether the order is known rather than guessed)."""
    if all(lit.lower() in _RANK for lit in literals):
        return tuple(sorted(literals, key=lambda w: _RANK[w.lower()])), True
    return tuple(literals), len(literals) <= 1


def infer_definitions(spec: A.Specification, sink: DiagnosticSink) -> A.Specification:
    """Return ``spec`` with declarations for every undeclared name it uses."""
    declared = {d.name for d in spec.definitions}
    events: dict[str, A.Span] = {}
    for name, span in visit.event_references(spec):
        if name not in declared:
            events.setdefault(name, span)

    kinds: dict[str, str] = {}  # measure -> "boolean" | "numeric" | "scale"
    spans: dict[str, A.Span] = {}
    literals: dict[str, list[str]] = {}
    declared_measures = {m.name for m in spec.measures}
    constants = {c.name for c in spec.constants}

    def note(name: A.Name, kind: str) -> None:
        if name.name in declared or name.name in events:
            return
        spans.setdefault(name.name, name.span)
        old = kinds.get(name.name)
        # numeric and scale beat boolean: a name compared with something is not a flag
        if old is None or old == "boolean":
            kinds[name.name] = kind

    def walk(e: A.Expr, ctx: str) -> None:
        if isinstance(e, A.Name):
            note(e, ctx)
        elif isinstance(e, A.Not):
            walk(e.operand, "boolean")
        elif isinstance(e, A.BinOp):
            sub = "boolean" if e.op in A.BOOL_OPS else "numeric"
            walk(e.left, sub)
            walk(e.right, sub)
        elif isinstance(e, A.Compare):
            left, right = e.left, e.right
            if isinstance(left, A.Name) and isinstance(right, A.Name):
                measure, lit = _measure_and_literal(left, right, kinds, declared_measures, constants)
                if measure is not None and lit is not None:
                    note(measure, "scale")
                    if measure.name not in declared:
                        bucket = literals.setdefault(measure.name, [])
                        if lit.name not in bucket:
                            bucket.append(lit.name)
                    return
            other_bool = isinstance(left, A.BoolLit) or isinstance(right, A.BoolLit)
            for side in (left, right):
                walk(side, "boolean" if other_bool else "numeric")

    for cond in visit.conditions(spec):
        walk(cond, "boolean")
    for dur in visit.all_durations(spec):
        walk(dur.value, "numeric")

    new_defs: list[A.Definition] = [A.EventDecl(n, span=s) for n, s in events.items()]
    for name, kind in kinds.items():
        if kind == "scale":
            lits = literals.get(name, [])
            ordered, known = _order(lits)
            if not known:
                sink.warning(
                    "infer-scale-order",
                    f"scale order of `{name}` guessed from first use: {', '.join(ordered)}",
                    spans[name],
                    hint="declare the measure with its literals listed lowest first",
                )
            mtype: A.MeasureType = A.ScaleType(ordered)
        elif kind == "numeric":
            mtype = A.NumericType()
        else:
            mtype = A.BooleanType()
        new_defs.append(A.MeasureDecl(name, mtype, span=spans[name]))
    # a literal is no measure: drop names that were only ever literals
    all_literals = {lit for lits in literals.values() for lit in lits}
    new_defs = [d for d in new_defs if not (isinstance(d, A.MeasureDecl) and d.name in all_literals)]
    if new_defs:
        n_ev = sum(isinstance(d, A.EventDecl) for d in new_defs)
        sink.note("infer-defs", f"inferred {n_ev} events and {len(new_defs) - n_ev} measures (no def block)")
    return replace(spec, definitions=(*spec.definitions, *new_defs))


def _measure_and_literal(
    left: A.Name, right: A.Name, kinds: dict[str, str], measures: set[str], constants: set[str]
) -> tuple[A.Name | None, A.Name | None]:
    if left.name in constants or right.name in constants:
        return None, None
    if left.braced and not right.braced:
        return left, right
    if right.braced and not left.braced:
        return right, left
    for m, lit in ((left, right), (right, left)):
        if m.name in measures or m.name in kinds:
            return m, lit
    return left, right
