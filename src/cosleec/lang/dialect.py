"""Which dialect a file is written in, and strict checking against one tool's grammar.

cosleec reads the union of both dialects (docs/reference/sleec-language.md §2). One walk over the AST
(:func:`collect`) gathers the *dialect facts*: every construct that only one dialect has,
with where it is. Detection (:func:`detect`), the mixed-dialect check (:func:`check_mixed`)
and the strict modes (:func:`check_strict`, ``--dialect tk|legos``: what that tool's grammar
would reject, §4.3 and §4.4) only read those facts.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from cosleec.lang import ast as A
from cosleec.lang.diagnostics import DiagnosticSink

Feature = tuple[str, A.Span]
"""A construct (as a message names it) and where it is."""

_BLOCK_COMMENT = re.compile(r"//[^\n]*|(/\*)")
_ESCAPE = re.compile(r"//[^\n]*|/\*[\s\S]*?\*/|(\^)[A-Za-z_]")


@dataclass(frozen=True, slots=True)
class DialectFacts:
    """What one file uses that only one dialect has; use :func:`collect` to get them.

    ``legos`` lists the constructs only LEGOS-SLEEC has, in the order detection cites them
    (blocks, then conditions, deadlines, constants, responses); ``tk`` the constructs
    LEGOS-SLEEC's grammar rejects; ``tk_rejects`` what else SLEEC-TK's grammar rejects,
    as complete messages; ``extensions`` cosleec's own constructs, which neither tool
    accepts and which therefore say nothing about the dialect (the priority block).
    """

    legos: tuple[Feature, ...]
    tk: tuple[Feature, ...]
    tk_rejects: tuple[Feature, ...]
    extensions: tuple[Feature, ...] = ()


def collect(spec: A.Specification, text: str) -> DialectFacts:
    """Walk ``spec`` (and scan ``text`` for comments and escapes) once for its dialect facts."""
    w = _Walk({m.name for m in spec.measures})
    blocks = [
        (f"a {kind} block", b.span)
        for kind in ("concern", "purpose", "relation")
        for b in spec.blocks
        if b.kind == kind
    ]
    for r in spec.rules:
        w.condition(r.trigger.condition, w.trigger)
        w.response(r.response)
        if r.response.braced:
            w.tk_other.append(("braces around the rule's response", r.response.span))
    for s in (*spec.concerns, *spec.purposes):
        cur: A.Situation | None = s
        while cur is not None:
            w.condition(cur.trigger.condition, w.trigger)
            for resp in cur.responses:
                w.response(resp)
            cur = cur.meanwhile
    for rel in spec.relations:
        w.relation(rel)
    constants: list[Feature] = []
    for c in spec.constants:
        if c.arrow:
            constants.append(("`-> C` in a constant", c.span))
        if isinstance(c.value, int) and c.value < 0:
            constants.append(("a signed number", c.span))
        elif isinstance(c.value, str) and not c.arrow:
            w.tk_other.append((f"constant reference without `->` (LEGOS writes `-> {c.value}`)", c.span))
    legos = (*blocks, *w.trigger[0], *w.unless[0], *w.relations[0], *w.deadline[0], *constants, *w.items)
    tk = (
        *_text_features(text),
        *w.trigger[1],
        *w.unless[1],
        *w.relations[1],
        *w.deadline[1],
        *w.tk_other,
    )
    extensions = tuple(
        ("a priority block (`priority_start`)", b.span) for b in spec.blocks if b.kind == "priority"
    )
    return DialectFacts(legos, tk, tuple(w.tk_rejects), extensions)


def detect(facts: DialectFacts) -> tuple[A.Dialect, Feature | None]:
    """LEGOS if the file uses anything only LEGOS has (returned as the evidence); else TK.

    Files that both tools accept (no measure in any condition, say) count as TK.
    """
    if facts.legos:
        return A.Dialect.LEGOS, facts.legos[0]
    return A.Dialect.TK, None


def check_mixed(facts: DialectFacts, evidence: Feature, sink: DiagnosticSink) -> None:
    """A file with LEGOS-only syntax must not also use what LEGOS rejects: no tool reads a mix."""
    what_legos, where = evidence
    for what, span in facts.tk:
        sink.error(
            "mixed-dialect",
            f"{what} is TK syntax, but this file also uses LEGOS syntax ({what_legos} at line "
            f"{where.line}); no SLEEC tool accepts a mix of the two",
            span,
            hint="write the file in one dialect; `cosleec fmt --dialect legos` converts it",
        )


def check_strict(
    facts: DialectFacts, dialect: A.Dialect, sink: DiagnosticSink, *, extensions: bool = True
) -> None:
    """Report what ``dialect``'s own tool would reject.

    ``extensions=False`` leaves out cosleec's extensions: for a caller whose checker already
    rejects them (``--strict``), so that one construct does not draw two errors.
    """
    if dialect is A.Dialect.TK:
        for what, span in facts.legos:
            sink.error("dialect", f"{what} is not TK syntax (SLEEC-TK rejects it)", span)
        for message, span in facts.tk_rejects:
            sink.error("dialect", message, span)
    elif dialect is A.Dialect.LEGOS:
        for what, span in facts.tk:
            sink.error("dialect", f"{what} is not LEGOS syntax (LEGOS-SLEEC rejects it)", span)
    if extensions and dialect in (A.Dialect.TK, A.Dialect.LEGOS):
        tool = "SLEEC-TK" if dialect is A.Dialect.TK else "LEGOS-SLEEC"
        for what, span in facts.extensions:
            sink.error(
                "dialect",
                f"{what} is a cosleec extension, not {dialect.name} syntax ({tool} rejects it)",
                span,
                hint=f"leave out --dialect {dialect} to use cosleec's extensions",
            )


def _text_features(text: str) -> list[Feature]:
    """TK syntax that leaves no trace in the AST: ``/* */`` comments and ``^`` escapes."""
    found: list[Feature] = []
    if "/*" in text:
        for m in _BLOCK_COMMENT.finditer(text):
            if m.group(1):
                found.append(("a `/* */` comment", _span_at(text, m.start(), 2)))
    if "^" in text:
        for m in _ESCAPE.finditer(text):
            if m.group(1):
                found.append(("a `^` keyword escape", _span_at(text, m.start(), 1)))
    return found


def _span_at(text: str, pos: int, width: int) -> A.Span:
    line = text.count("\n", 0, pos) + 1
    col = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return A.Span(line, col, line, col + width)


class _Walk:
    """The one walk of :func:`collect`. Each kind of place (trigger conditions, ``unless``
    conditions, relations, deadlines) keeps its own (LEGOS, TK) lists, so that the facts
    come out grouped in a fixed order, whatever order the walk visits them in."""

    def __init__(self, measures: set[str]) -> None:
        self.measures = measures
        self.trigger: tuple[list[Feature], list[Feature]] = ([], [])
        self.unless: tuple[list[Feature], list[Feature]] = ([], [])
        self.relations: tuple[list[Feature], list[Feature]] = ([], [])
        self.deadline: tuple[list[Feature], list[Feature]] = ([], [])
        self.items: list[Feature] = []  # LEGOS-only response forms
        self.tk_other: list[Feature] = []
        self.tk_rejects: list[Feature] = []

    def response(self, r: A.Response) -> None:
        """``r``, then the responses nested in it (pre-order, as the checker reads them)."""
        for item in r.items:
            occ = item.occurrence
            if occ.eventually:
                self.items.append(("`eventually`", occ.span))
            if occ.limit is not None and occ.limit.lo is not None:
                self.items.append(("a `within [a, b]` interval", occ.limit.span))
            if item.alternative is not None:
                self.items.append(("`else`", item.alternative.span))
            if occ.negated and occ.limit is None:
                self.items.append(("an untimed `not E`", occ.span))
            if item.otherwise is not None:
                if occ.negated or occ.limit is None:
                    self.items.append(
                        ("`otherwise` after a prohibition or an untimed response", item.otherwise.span)
                    )
                if occ.negated and occ.limit is not None:
                    self.tk_rejects.append(
                        ("SLEEC-TK allows no `otherwise` after `not E within T`", item.otherwise.span)
                    )
            if occ.limit is not None:
                for deadline in (occ.limit.lo, occ.limit.hi):
                    if deadline is not None:
                        self.duration(deadline)
                        if not isinstance(deadline.value, A.IntLit | A.Name):
                            self.tk_rejects.append(
                                ("SLEEC-TK deadlines are a number or a constant", deadline.span)
                            )
        for clause in r.defeaters:
            self.condition(clause.condition, self.unless)
        for item in r.items:
            if item.otherwise is not None:
                self.response(item.otherwise)
            if item.alternative is not None:
                self.response(item.alternative)
        for clause in r.defeaters:
            if clause.response is not None:
                self.response(clause.response)

    def duration(self, d: A.Duration) -> None:
        self.condition(d.value, self.deadline)

    def relation(self, rel: A.Relation) -> None:
        if isinstance(rel, A.MeasureRelation):
            self.condition(rel.first, self.relations)
            self.condition(rel.second, self.relations)
        elif isinstance(rel, A.EventMeasureRelation):
            self.condition(rel.condition, self.relations)
        elif isinstance(rel, A.UntilRelation):
            self.condition(rel.trigger.condition, self.trigger)
            self.condition(rel.condition, self.relations)
            self.condition(rel.until_condition, self.relations)
        elif isinstance(rel, A.ForRelation):
            self.condition(rel.trigger.condition, self.trigger)
            self.condition(rel.condition, self.relations)
            self.duration(rel.duration)

    def condition(self, e: A.Expr | None, into: tuple[list[Feature], list[Feature]]) -> None:
        """The features of expression ``e``, node by node in pre-order, left first."""
        if e is None:
            return
        legos, tk = into
        t = type(e)
        if t is A.Name:
            n: A.Name = e  # type: ignore[assignment]
            if n.braced or n.arrow:
                legos.append(("`{m}` measure braces" if n.braced else "`->C` constant reference", n.span))
            if n.name in self.measures and not n.braced:
                tk.append((f"bare measure `{n.name}` (LEGOS writes `{{{n.name}}}`)", n.span))
            if n.parenthesized:
                tk.append((f"`({n.name})`, a lone name in parentheses (LEGOS writes it without)", n.span))
        elif t is A.BinOp or t is A.Compare:
            b: A.BinOp | A.Compare = e  # type: ignore[assignment]
            if t is A.BinOp and b.op in A.ARITH_OPS:
                legos.append(("arithmetic", b.span))
            if not b.parenthesized:
                tk.append((f"`{b.op}` outside its own parentheses", b.span))
            self.condition(b.left, into)
            self.condition(b.right, into)
        elif t is A.Not:
            neg: A.Not = e  # type: ignore[assignment]
            if not neg.parenthesized:
                tk.append(("`not` outside parentheses (LEGOS writes `(not X)`)", neg.span))
            self.condition(neg.operand, into)
        elif t is A.IntLit and e.value < 0:  # type: ignore[union-attr]
            legos.append(("a signed number", e.span))
