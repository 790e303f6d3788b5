"""The CO-SLEEC paper's rule notation -> AST rules (see ``grammar/paper.lark``).

``WHEN E THEN A UNLESS C IN WHICH CASE (B AND D)`` becomes a rule whose response is the
conjunction extension of the DSL (``then A unless C then B and D``); unnamed rules get
``R1``, ``R2``, ... by position in the file.
"""

from __future__ import annotations

from typing import Any

from cosleec.lang import ast as A
from cosleec.lang.transformer import ToAst, ident, tok_span


class PaperToAst(ToAst):
    """Builds rules from the paper notation, sharing the DSL's expression callbacks."""

    def start(self, c: list[Any]) -> Any:
        rules: list[A.Rule] = []
        for i, (name_tok, rule) in enumerate(c, start=1):
            name = ident(name_tok) if name_tok is not None else f"R{i}"
            rules.append(A.Rule(name, rule.trigger, rule.response, span=rule.span))
        return rules

    def prule(self, c: list[Any]) -> tuple[Any, A.Rule]:
        name_tok, event, cond, items, *clauses = c
        trigger = A.Trigger(ident(event), cond, span=tok_span(event))
        response = A.Response(items.items, tuple(clauses), span=items.span)
        span = tok_span(name_tok) if name_tok is not None else trigger.span
        return name_tok, A.Rule("", trigger, response, span=span)

    def pclause(self, c: list[Any]) -> A.Defeater:
        return A.Defeater(c[1], c[2], span=tok_span(c[0]))

    def pitems(self, c: list[Any]) -> A.Response:
        return A.Response(tuple(c), (), span=c[0].span)

    def pitem(self, c: list[Any]) -> A.ResponseItem:
        not_tok, name, duration, otherwise = c
        limit = A.TimeLimit(duration, None, span=duration.span) if duration is not None else None
        occ = A.Occurrence(ident(name), not_tok is not None, limit, False, span=tok_span(name))
        return A.ResponseItem(occ, otherwise, span=occ.span)

    def potherwise(self, c: list[Any]) -> A.Response:
        r: A.Response = c[0]
        return r

    def duration(self, c: list[Any]) -> A.Duration:
        """Units are keywords, and the paper's keywords are case-insensitive: ``MINUTES`` is
        ``minutes``. A unit the grammar does not know (a NAME) stays as written, for the
        checker's message."""
        d = super().duration(c)
        if c[1].type != "NAME":
            return A.Duration(d.value, d.unit.lower(), span=d.span)
        return d
