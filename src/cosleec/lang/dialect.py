"""Which dialect a file is written in, and strict checking against one tool's grammar.

cosleec reads the union of both dialects (sleec-language.md §2). Detection records the
dialect a file uses; a *forced* dialect (``--dialect tk|legos``) reports every construct
that tool's grammar would reject (§4.3, §4.4), for users who need a file the other tools
accept too.
"""

from __future__ import annotations

import re
from collections.abc import Iterator

from cosleec.lang import ast as A
from cosleec.lang import visit
from cosleec.lang.diagnostics import DiagnosticSink

_BLOCK_COMMENT = re.compile(r"//[^\n]*|(/\*)")


def legos_features(spec: A.Specification) -> Iterator[tuple[str, A.Span]]:
    """Constructs only the LEGOS dialect has, with where they are."""
    for kind in ("concern", "purpose", "relation"):
        for b in spec.blocks:
            if b.kind == kind:
                yield f"a {kind} block", b.span
    for e in _all_exprs(spec):
        for s in visit.subexpressions(e):
            if isinstance(s, A.Name) and (s.braced or s.arrow):
                yield ("`{m}` measure braces" if s.braced else "`->C` constant reference"), s.span
            elif isinstance(s, A.BinOp) and s.op in A.ARITH_OPS:
                yield "arithmetic", s.span
            elif isinstance(s, A.IntLit) and s.value < 0:
                yield "a signed number", s.span
    for c in spec.constants:
        if c.arrow:
            yield "`-> C` in a constant", c.span
        if isinstance(c.value, int) and c.value < 0:
            yield "a signed number", c.span
    for resp in visit.all_responses(spec):
        for r in visit.responses(resp):
            for item in r.items:
                occ = item.occurrence
                if occ.eventually:
                    yield "`eventually`", occ.span
                if occ.limit is not None and occ.limit.lo is not None:
                    yield "a `within [a, b]` interval", occ.limit.span
                if item.alternative is not None:
                    yield "`else`", item.alternative.span
                if occ.negated and occ.limit is None:
                    yield "an untimed `not E`", occ.span
                if item.otherwise is not None and (occ.negated or occ.limit is None):
                    yield "`otherwise` after a prohibition or an untimed response", item.otherwise.span


def tk_features(spec: A.Specification, text: str) -> Iterator[tuple[str, A.Span]]:
    """Constructs the LEGOS grammar rejects (bare measures, loose operators, /* */...)."""
    for m in _BLOCK_COMMENT.finditer(text) if "/*" in text else ():
        if m.group(1):
            line = text.count("\n", 0, m.start()) + 1
            col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
            yield "a `/* */` comment", A.Span(line, col, line, col + 2)
    measures = {m.name for m in spec.measures}
    for e in _all_exprs(spec):
        for s in visit.subexpressions(e):
            if isinstance(s, A.Name) and s.name in measures and not s.braced:
                yield f"bare measure `{s.name}` (LEGOS writes `{{{s.name}}}`)", s.span
            if isinstance(s, A.BinOp | A.Compare) and not s.parenthesized:
                yield f"`{s.op}` outside its own parentheses", s.span
            elif isinstance(s, A.Name) and s.parenthesized:
                yield f"`({s.name})`, a lone name in parentheses (LEGOS writes it without)", s.span
            elif isinstance(s, A.Not) and not s.parenthesized:
                yield "`not` outside parentheses (LEGOS writes `(not X)`)", s.span
    for c in spec.constants:
        if isinstance(c.value, str) and not c.arrow:
            yield f"constant reference without `->` (LEGOS writes `-> {c.value}`)", c.span
    for r in spec.rules:
        if r.response.braced:
            yield "braces around the rule's response", r.response.span


def _all_exprs(spec: A.Specification) -> Iterator[A.Expr]:
    yield from visit.conditions(spec)
    for d in visit.all_durations(spec):
        yield d.value


def detect(spec: A.Specification) -> tuple[A.Dialect, tuple[str, A.Span] | None]:
    """LEGOS if the file uses anything only LEGOS has (returned as the evidence); else TK.

    Files that both tools accept (no measure in any condition, say) count as TK.
    """
    for evidence in legos_features(spec):
        return A.Dialect.LEGOS, evidence
    return A.Dialect.TK, None


def _tk_free(e: A.Expr, measures: set[str]) -> bool:
    """Is this expression written the LEGOS way throughout? (A plain recursion: the common
    answer, yes, is found without building anything.)"""
    t = type(e)
    if t is A.Name:
        return not e.parenthesized and (e.braced or e.name not in measures)  # type: ignore[union-attr]
    if t is A.BinOp or t is A.Compare:
        return (
            e.parenthesized  # type: ignore[union-attr]
            and _tk_free(e.left, measures)  # type: ignore[union-attr]
            and _tk_free(e.right, measures)  # type: ignore[union-attr]
        )
    if t is A.Not:
        return e.parenthesized and _tk_free(e.operand, measures)  # type: ignore[union-attr]
    return True


def _looks_legos(spec: A.Specification, text: str) -> bool:
    if "/*" in text:
        return False  # maybe a block comment: let the detailed pass decide
    measures = {m.name for m in spec.measures}
    if any(isinstance(c.value, str) and not c.arrow for c in spec.constants):
        return False
    if any(r.response.braced for r in spec.rules):
        return False
    return all(_tk_free(e, measures) for e in _all_exprs(spec))


def check_mixed(spec: A.Specification, evidence: tuple[str, A.Span], text: str, sink: DiagnosticSink) -> None:
    """A file with LEGOS-only syntax must not also use what LEGOS rejects: no tool reads a mix."""
    if _looks_legos(spec, text):
        return  # the usual case, settled by the fast check
    what_legos, where = evidence
    for what, span in tk_features(spec, text):
        sink.error(
            "mixed-dialect",
            f"{what} is TK syntax, but this file also uses LEGOS syntax ({what_legos} at line "
            f"{where.line}); no SLEEC tool accepts a mix of the two",
            span,
            hint="write the file in one dialect; `cosleec fmt --dialect legos` converts it",
        )


def check_strict(spec: A.Specification, dialect: A.Dialect, text: str, sink: DiagnosticSink) -> None:
    """Report what ``dialect``'s own tool would reject."""
    if dialect is A.Dialect.TK:
        for what, span in legos_features(spec):
            sink.error("dialect", f"{what} is not TK syntax (SLEEC-TK rejects it)", span)
        for resp in visit.all_responses(spec):
            for r in visit.responses(resp):
                for item in r.items:
                    occ = item.occurrence
                    if occ.negated and occ.limit is not None and item.otherwise is not None:
                        sink.error(
                            "dialect",
                            "SLEEC-TK allows no `otherwise` after `not E within T`",
                            item.otherwise.span,
                        )
            for d in visit.durations(resp):
                if not isinstance(d.value, A.IntLit | A.Name):
                    sink.error("dialect", "SLEEC-TK deadlines are a number or a constant", d.span)
    elif dialect is A.Dialect.LEGOS:
        for what, span in tk_features(spec, text):
            sink.error("dialect", f"{what} is not LEGOS syntax (LEGOS-SLEEC rejects it)", span)
