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

:class:`LegosReader` is the checker's side: handed each such defect, it works out that reading,
warns, and records it in a :class:`LegosReading`.

May import: the lang modules ast, diagnostics and scope.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field, replace

from cosleec.lang import ast as A
from cosleec.lang.diagnostics import QUOTE_LIMIT, clip
from cosleec.lang.scope import Scope


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


class LegosReader:
    """How the checker reads, under ``legos_compat``, what LEGOS-SLEEC lets through.

    LEGOS-SLEEC reads a scale literal as its position in its own scale and a scale measure
    as its position in its scale, and compares positions as integers. Each method is handed
    one such comparison (or a second definition of a name), reads it that way, warns,
    records the reading in :attr:`reading` and returns True; it returns False (the caller
    reports the error) where LEGOS-SLEEC has no reading.
    """

    def __init__(self, scope: Scope) -> None:
        self.scope = scope
        self.sink = scope.sink
        self.reading = LegosReading()
        self._taken: dict[int, set[str]] = {}  # id(a renames map of reading) -> names in use there

    def position(self, lit: str) -> int | None:
        """``lit``'s position in LEGOS-SLEEC's one table of literals: its index in its scale,
        the same in every scale that has it (or None: LEGOS-SLEEC's table asserts that)."""
        found = set()
        for owner in self.scope.owners_of.get(lit, ()):
            t = self.scope.table.measures[owner].type
            assert isinstance(t, A.ScaleType)
            found.add(t.literals.index(lit))
        return found.pop() if len(found) == 1 else None

    def literal(self, e: A.Compare, node: A.Expr, lit: str, measure: str, scale: A.ScaleType) -> bool:
        """``{measure} op lit`` with ``lit`` (the expression ``node`` of ``e``) a literal of
        another scale."""
        p = self.position(lit)
        if p is None:
            return False
        owners = self.scope.owners(lit)
        head = (
            f"`{clip(lit)}` is not in the scale of `{clip(measure)}` "
            f"({clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}); LEGOS-SLEEC reads a scale "
            f"literal as its position in its own scale, and `{clip(lit)}` is the {ordinal(p)} of "
            f"`{owners}`'s"
        )
        if p < len(scale.literals):
            new = scale.literals[p]
            self.reading.replace(node, _renamed(node, new))
            self.sink.warning(
                "scale-literal",
                f"{head}, so cosleec reads it as `{clip(new)}`, the {ordinal(p)} of `{clip(measure)}`'s",
                node.span,
                hint=f"write `{clip(new)}` if that is what is meant",
            )
            return True
        op = e.op if node is e.right else mirrored(e.op)  # with the measure on the left
        value = holds(op, 0, p)  # every position of the scale is below p
        self._constant(e, value)
        self.sink.warning(
            "scale-literal",
            f"{head}, beyond the {len(scale.literals)} of `{clip(measure)}`'s: LEGOS-SLEEC compares "
            f"the positions, so the comparison is always {str(value).lower()}, and cosleec reads it "
            f"as `{str(value).lower()}`",
            node.span,
            hint=f"compare with a literal of `{clip(measure)}`: "
            f"{clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}",
        )
        return True

    def number(self, node: A.Expr, lit: str) -> bool:
        """A scale literal (the expression ``node``) compared with a number (a numeric measure, say)."""
        p = self.position(lit)
        if p is None:
            return False
        parens = node.parenthesized
        self.reading.replace(node, A.IntLit(p, parenthesized=parens, span=node.span))
        self.sink.warning(
            "type",
            f"scale literal `{clip(lit)}` (of `{self.scope.owners(lit)}`) is compared with a number; "
            f"LEGOS-SLEEC reads a scale literal as its position in its scale, so cosleec reads it "
            f"as {p}",
            node.span,
            hint="compare a number with a number, a scale measure with its own literals",
        )
        return True

    def scale_number(self, e: A.Compare, measure: str, number: A.Expr, op: str, c: int) -> bool:
        """Scale measure ``measure`` compared by ``e`` with ``number``, whose constant value is
        ``c`` (``op``: the comparison with the measure on the left)."""
        scale = self.scope.table.measures[measure].type
        assert isinstance(scale, A.ScaleType)
        shown = f"`{clip(number.name)}` = {c}" if isinstance(number, A.Name) else f"{c}"
        head = (
            f"`{e.op}` compares the scale of `{clip(measure)}` with a number ({shown}); LEGOS-SLEEC "
            f"compares the measure's position in its scale (0 to {len(scale.literals) - 1}) with it"
        )
        hint = (
            f"compare with a literal of `{clip(measure)}`: {clip(', '.join(scale.literals), 4 * QUOTE_LIMIT)}"
        )
        if 0 <= c < len(scale.literals):
            new = scale.literals[c]
            self.reading.replace(number, A.Name(new, parenthesized=number.parenthesized, span=number.span))
            self.sink.warning(
                "type",
                f"{head}, so cosleec reads {c} as `{clip(new)}`, the {ordinal(c)} of `{clip(measure)}`'s",
                e.span,
                hint=hint,
            )
            return True
        value = holds(op, 0, c)  # every position is on the same side of c
        self._constant(e, value)
        self.sink.warning(
            "type",
            f"{head}: always {str(value).lower()}, and cosleec reads it as `{str(value).lower()}`",
            e.span,
            hint=hint,
        )
        return True

    def _constant(self, e: A.Compare, value: bool) -> None:
        self.reading.replace(e, A.BoolLit(value, parenthesized=e.parenthesized, span=e.span))

    def rename(
        self,
        renames: dict[int, str],
        i: int,
        name: str,
        nth: dict[str, int],
        items: Sequence[A.Rule] | Sequence[A.Situation],
    ) -> str:
        """The new name of item ``i`` of ``items``, a later definition of ``name``: recorded
        in ``renames`` (one of :attr:`reading`'s maps), :func:`fresh_name`, clear of every
        name of ``items`` and of the new names given so far; ``nth`` counts the definitions
        of each name."""
        taken = self._taken.get(id(renames))
        if taken is None:
            taken = self._taken[id(renames)] = {x.name for x in items}
        nth[name] = nth.get(name, 1) + 1
        new = fresh_name(name, nth[name], taken)
        taken.add(new)
        renames[i] = new
        return new


def _renamed(node: A.Expr, name: str) -> A.Name:
    """A scale literal ``node`` (a Name) read as the literal ``name``, written as it was."""
    assert isinstance(node, A.Name)
    return A.Name(name, parenthesized=node.parenthesized, span=node.span)


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
