"""LEGOS-SLEEC's reading of the defects it lets through (``legos_compat``, docs/reference/sleec-language.md §11 item 18).

N-Check's case studies, written for LEGOS-SLEEC, hold defects cosleec rejects: scale literals
compared with a measure of another scale, scales compared with numbers, two rules (or two
concerns, two purposes) of one name. LEGOS-SLEEC reads them without a word: it maps every
scale literal to its position in its own scale and compares positions as integers, and it
never compares rule, concern or purpose names. With ``Options(legos_compat=True)`` the checker
reports each such defect as a warning instead of an error and records here how LEGOS-SLEEC
reads it; :func:`apply` then rebuilds the specification with that reading, so that whatever
comes after the front end gets LEGOS-SLEEC's meaning in ordinary cosleec terms:

- a literal of another scale becomes the literal at the same position of the compared
  measure's own scale (``{battery} = low``, ``low`` the first of its scale, is read as
  ``{battery} = low2``, the first of ``battery``'s);
- a number compared with a scale measure becomes the literal at that position; a literal
  compared with a number becomes its position, an integer;
- a comparison whose position lies outside the measure's scale has the same value for every
  value of the measure (LEGOS-SLEEC bounds a scale measure to its positions): it becomes that
  value, ``true`` or ``false``;
- a second rule (concern, purpose) of a name is kept under a new name, :func:`fresh_name`.

May import: the lang modules ast and diagnostics.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field, replace

from cosleec.lang import ast as A


def fresh_name(name: str, nth: int, taken: Collection[str]) -> str:
    """The name a later definition of ``name`` gets: ``name__2`` for the second definition,
    ``name__3`` for the third, ..., the number counted up past any name in ``taken``.

    A SLEEC identifier (so ``cosleec fmt`` writes a file that reads back, and a JSON or
    SARIF consumer shows it as is), and never one the file already uses.
    """
    k = nth
    while f"{name}__{k}" in taken:
        k += 1
    return f"{name}__{k}"


def ordinal(i: int) -> str:
    """``0`` -> ``"1st"``: a position (counted from 0) as a message says it."""
    n = i + 1
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


_MIRROR = {"<": ">", ">": "<", "<=": ">=", ">=": "<=", "=": "=", "<>": "<>"}


def mirrored(op: str) -> str:
    """The operator with its sides swapped: ``a < b`` is ``b > a``."""
    return _MIRROR[op]


def holds(op: str, a: int, b: int) -> bool:
    """``a op b`` on integers, for a SLEEC relational operator."""
    if op == "<":
        return a < b
    if op == "<=":
        return a <= b
    if op == ">":
        return a > b
    if op == ">=":
        return a >= b
    if op == "=":
        return a == b
    return a != b


@dataclass
class LegosReading:
    """How LEGOS-SLEEC reads one file's defects: what :func:`apply` changes."""

    # id(original) -> (original, replacement); the original is kept so that its id stays its own
    exprs: dict[int, tuple[A.Expr, A.Expr]] = field(default_factory=dict)
    rules: dict[int, str] = field(default_factory=dict)  # index in spec.rules -> new name
    concerns: dict[int, str] = field(default_factory=dict)
    purposes: dict[int, str] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.exprs or self.rules or self.concerns or self.purposes)

    def replace(self, old: A.Expr, new: A.Expr) -> None:
        """Read the expression node ``old`` (the very node, not an equal one) as ``new``."""
        self.exprs[id(old)] = (old, new)


def apply(spec: A.Specification, reading: LegosReading) -> A.Specification:
    """``spec`` as LEGOS-SLEEC reads it; ``spec`` itself when there is nothing to change."""
    if not reading:
        return spec
    return _Rebuild(reading).spec(spec)


class _Rebuild:
    """One walk that rebuilds only what a replacement or a rename touches."""

    def __init__(self, reading: LegosReading) -> None:
        self.r = reading

    def spec(self, s: A.Specification) -> A.Specification:
        rules = tuple(
            replace(
                rule,
                name=self.r.rules.get(i, rule.name),
                trigger=self.trigger(rule.trigger),
                response=self.response(rule.response),
            )
            for i, rule in enumerate(s.rules)
        )
        concerns = tuple(self.situation(x, self.r.concerns.get(i)) for i, x in enumerate(s.concerns))
        purposes = tuple(self.situation(x, self.r.purposes.get(i)) for i, x in enumerate(s.purposes))
        relations = tuple(self.relation(x) for x in s.relations)
        return replace(s, rules=rules, concerns=concerns, purposes=purposes, relations=relations)

    def expr(self, e: A.Expr) -> A.Expr:
        hit = self.r.exprs.get(id(e))
        if hit is not None and hit[0] is e:
            return hit[1]
        if isinstance(e, A.BinOp | A.Compare):
            left, right = self.expr(e.left), self.expr(e.right)
            if left is e.left and right is e.right:
                return e
            return replace(e, left=left, right=right)
        if isinstance(e, A.Not):
            operand = self.expr(e.operand)
            return e if operand is e.operand else replace(e, operand=operand)
        return e

    def condition(self, e: A.Expr | None) -> A.Expr | None:
        return None if e is None else self.expr(e)

    def trigger(self, t: A.Trigger) -> A.Trigger:
        c = self.condition(t.condition)
        return t if c is t.condition else replace(t, condition=c)

    def duration(self, d: A.Duration) -> A.Duration:
        v = self.expr(d.value)
        return d if v is d.value else replace(d, value=v)

    def response(self, r: A.Response) -> A.Response:
        items = tuple(self.item(i) for i in r.items)
        defeaters = tuple(
            replace(
                d,
                condition=self.expr(d.condition),
                response=None if d.response is None else self.response(d.response),
            )
            for d in r.defeaters
        )
        return replace(r, items=items, defeaters=defeaters)

    def item(self, i: A.ResponseItem) -> A.ResponseItem:
        occ = i.occurrence
        if occ.limit is not None:
            lim = occ.limit
            lim = replace(lim, hi=self.duration(lim.hi), lo=None if lim.lo is None else self.duration(lim.lo))
            occ = replace(occ, limit=lim)
        return replace(
            i,
            occurrence=occ,
            otherwise=None if i.otherwise is None else self.response(i.otherwise),
            alternative=None if i.alternative is None else self.response(i.alternative),
        )

    def situation(self, s: A.Situation, name: str | None) -> A.Situation:
        return replace(
            s,
            name=s.name if name is None else name,
            trigger=self.trigger(s.trigger),
            responses=tuple(self.response(r) for r in s.responses),
            meanwhile=None if s.meanwhile is None else self.situation(s.meanwhile, None),
        )

    def relation(self, rel: A.Relation) -> A.Relation:
        if isinstance(rel, A.MeasureRelation):
            return replace(rel, first=self.expr(rel.first), second=self.condition(rel.second))
        if isinstance(rel, A.EventMeasureRelation):
            return replace(rel, condition=self.expr(rel.condition))
        if isinstance(rel, A.UntilRelation):
            return replace(
                rel,
                trigger=self.trigger(rel.trigger),
                condition=self.expr(rel.condition),
                until_condition=self.condition(rel.until_condition),
            )
        if isinstance(rel, A.ForRelation):
            return replace(
                rel,
                trigger=self.trigger(rel.trigger),
                condition=self.expr(rel.condition),
                duration=self.duration(rel.duration),
            )
        return rel
