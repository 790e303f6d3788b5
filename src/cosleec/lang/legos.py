"""The checks of LEGOS-SLEEC's blocks (docs/reference/sleec-language.md §9): concerns, purposes, relations.

A concern or purpose is a situation -- a trigger, responses, and a ``meanwhile`` situation
-- checked as a rule's trigger and response are (responses.py), with a name of its own in
its block; a second one of a name is kept under a new name under ``legos_compat``
(compat.py). A relation names declared events and conditions; a relation word that no
published SLEEC grammar has (sleecvalDef's ``conflict``, ``effect``) is an error.

May import: the lang modules ast, compat, diagnostics, responses and scope.
"""

from __future__ import annotations

from cosleec.lang import ast as A
from cosleec.lang.compat import LegosReader
from cosleec.lang.diagnostics import clip
from cosleec.lang.responses import Responses
from cosleec.lang.scope import Scope


def check_situations(scope: Scope, responses: Responses, legos: LegosReader) -> None:
    """Every concern, then every purpose: one name per situation of a block, and what each says."""
    for block, items, renames in (
        ("concern", scope.spec.concerns, legos.reading.concerns),
        ("purpose", scope.spec.purposes, legos.reading.purposes),
    ):
        seen: dict[str, A.Situation] = {}
        nth: dict[str, int] = {}
        for i, s in enumerate(items):
            if s.name in seen:
                related = (("first defined here", seen[s.name].span),)
                if scope.opt.legos_compat:
                    new = legos.rename(renames, i, s.name, nth, items)
                    scope.sink.warning(
                        "duplicate-name",
                        f"{block} `{clip(s.name)}` is defined twice; LEGOS-SLEEC keeps both (it "
                        f"never compares {block} names), and so does cosleec, calling this one "
                        f"`{clip(new)}`",
                        s.span,
                        related=related,
                        hint=f"give each {block} a name of its own",
                    )
                else:
                    scope.sink.error(
                        "duplicate-name",
                        f"{block} `{clip(s.name)}` is defined twice",
                        s.span,
                        related=related,
                    )
            seen.setdefault(s.name, s)
            with scope.sink.folding(f"{block} `{clip(s.name)}`", scope.opt.repeat_limit):
                _situation(responses, s)


def _situation(responses: Responses, s: A.Situation) -> None:
    """``s`` and the chain of ``meanwhile`` situations under it."""
    cur: A.Situation | None = s
    while cur is not None:
        responses.trigger(cur.trigger)
        for r in cur.responses:
            responses.response(r)
        cur = cur.meanwhile


def check_relations(scope: Scope, responses: Responses) -> None:
    """Every relation: its events declared, its conditions truth values, its words SLEEC's."""
    condition = responses.expressions.condition
    for rel in scope.spec.relations:
        if isinstance(rel, A.EventRelation):
            if rel.kind == "conflict":
                _nonstandard(scope, rel.span, "conflict", "mutualExclusive")
                continue
            responses.event(rel.first, rel.span, "relation")
            responses.event(rel.second, rel.span, "relation")
        elif isinstance(rel, A.MeasureRelation):
            if rel.kind == "conflict":
                _nonstandard(scope, rel.span, "measure conflict", "measure mutualExclusive")
                continue
            condition(rel.first)
            if rel.second is not None:
                condition(rel.second)
        elif isinstance(rel, A.EventMeasureRelation):
            if rel.kind == "effect":
                _nonstandard(scope, rel.span, "effect", "includes")
                continue
            responses.event(rel.event, rel.span, "relation")
            condition(rel.condition)
        elif isinstance(rel, A.UntilRelation):
            responses.trigger(rel.trigger)
            condition(rel.condition)
            responses.event(rel.until_event, rel.span, "relation")
            if rel.until_condition is not None:
                condition(rel.until_condition)
        else:
            responses.trigger(rel.trigger)
            condition(rel.condition)
            responses.duration(rel.duration)


def _nonstandard(scope: Scope, span: A.Span, word: str, instead: str) -> None:
    scope.sink.error(
        "nonstandard-relation",
        f"`{word}` is not a relation in any published SLEEC grammar (it appears only in "
        "sleecvalDef's LLM-sanitised files)",
        span,
        hint=f"did you mean `{instead}`?",
    )


__all__ = ["check_relations", "check_situations"]
