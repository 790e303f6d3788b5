"""Where every name of a checked file is declared and used: what hover, go-to-definition,
find-references, rename and the outline read.

Built from a :class:`~cosleec.lang.CheckResult` -- the AST's spans, which name each token
exactly -- and, for the few names the AST keeps without a span of their own (the events of a
LEGOS relation, a constant's reference), the first occurrence of the name after the node's
start. A name is a symbol of one kind: an event, a measure, a constant, a rule, a concern or
purpose, or a scale value (scoped to its measure: ``low`` of ``light`` is not ``low`` of
``noise``). Each use says what it does there (triggers, obliged, forbidden, read, ...) and
where (``R1``, ``R1.2`` for the rule's second clause, ``concern c1``, ``relation``,
``priority``).
"""

from __future__ import annotations

import bisect
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import StrEnum

from cosleec.lang import CheckResult, SymbolTable
from cosleec.lang import ast as A
from cosleec.lsp.positions import LineIndex


class Kind(StrEnum):
    """What a name denotes."""

    EVENT = "event"
    MEASURE = "measure"
    CONSTANT = "constant"
    RULE = "rule"
    SCALE_VALUE = "scale value"
    CONCERN = "concern"
    PURPOSE = "purpose"


class Role(StrEnum):
    """What a use of a name does there."""

    DECLARED = "declared"
    TRIGGERS = "triggers"
    OBLIGED = "obliged"
    FORBIDDEN = "forbidden"
    READ = "read"
    NAMED = "named"  # a rule in the priority block, a name in a relation


Key = tuple[Kind, str]
"""A symbol: its kind and name (a scale value's name is ``measure.value``)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Use:
    """One occurrence of a name: ``start``/``end`` are offsets into the text."""

    key: Key
    role: Role
    start: int
    end: int
    where: str = ""  # R1, R1.2, concern c1, relation, priority; "" for a declaration

    @property
    def name(self) -> str:
        """The name as the user knows it (a scale value without its measure)."""
        return self.key[1].rpartition(".")[2] if self.key[0] is Kind.SCALE_VALUE else self.key[1]


@dataclass(frozen=True, slots=True, kw_only=True)
class Extent:
    """A declared thing for the outline: its name's place and the whole of it."""

    key: Key
    name_start: int
    name_end: int
    start: int
    end: int
    detail: str = ""


@dataclass
class Index:
    """Every use of every name of one text, sorted by place; the declarations; the rules'
    extents. Use :meth:`build`."""

    lines: LineIndex
    result: CheckResult
    uses: list[Use] = field(default_factory=list)
    declarations: dict[Key, Use] = field(default_factory=dict)
    outline: list[Extent] = field(default_factory=list)
    _starts: list[int] = field(default_factory=list, init=False, repr=False)
    _by_key: dict[Key, list[Use]] = field(default_factory=dict, init=False, repr=False)

    @classmethod
    def build(cls, result: CheckResult, lines: LineIndex) -> Index:
        """The index of a checked text (empty when it did not parse)."""
        index = cls(lines, result)
        if result.spec is not None:
            _Walk(index, result.spec, result.symbols or SymbolTable()).run()
        index.uses.sort(key=lambda u: u.start)
        index._starts = [u.start for u in index.uses]
        for u in index.uses:
            index._by_key.setdefault(u.key, []).append(u)
        return index

    def at(self, offset: int) -> Use | None:
        """The use whose name covers ``offset`` (the cursor just after a name counts)."""
        i = bisect.bisect_right(self._starts, offset) - 1
        for j in (i, i - 1):
            if 0 <= j < len(self.uses) and self.uses[j].start <= offset <= self.uses[j].end:
                return self.uses[j]
        return None

    def uses_of(self, key: Key) -> list[Use]:
        """Every use of a symbol, in file order (its declaration among them)."""
        return self._by_key.get(key, [])

    @property
    def spec(self) -> A.Specification | None:
        """The specification the index was built from."""
        return self.result.spec

    def measure(self, name: str) -> A.MeasureDecl | None:
        """The declaration of measure ``name``, if there is one."""
        spec = self.result.spec
        return next((m for m in spec.measures if m.name == name), None) if spec else None


_WORD = "(?<![A-Za-z0-9_^])\\^?{}(?![A-Za-z0-9_])"


class _Walk:
    """One pass over a specification, adding its uses to an index."""

    def __init__(self, index: Index, spec: A.Specification, symbols: SymbolTable) -> None:
        self.index = index
        self.spec = spec
        self.symbols = symbols
        self.lines = index.lines
        self.text = index.lines.text
        self.scales: dict[str, list[str]] = {}  # scale value -> the measures whose scale has it
        for m in spec.measures:
            if isinstance(m.type, A.ScaleType):
                for v in m.type.literals:
                    self.scales.setdefault(v, []).append(m.name)
        self.end = 0  # the furthest offset reached in the current rule or situation

    def run(self) -> None:
        self.definitions()
        for r in self.spec.rules:
            self.rule(r)
        for kind, situations in ((Kind.CONCERN, self.spec.concerns), (Kind.PURPOSE, self.spec.purposes)):
            for s in situations:
                self.situation(kind, s)
        for rel in self.spec.relations:
            self.relation(rel)
        for p in self.spec.priorities:
            self.use((Kind.RULE, p.higher), Role.NAMED, p.higher_span, "priority")
            self.use((Kind.RULE, p.lower), Role.NAMED, p.lower_span, "priority")

    # ------------------------------------------------------------ recording
    def use(self, key: Key, role: Role, span: A.Span, where: str) -> Use | None:
        if not span.line:
            return None
        start, end = self.lines.span_offsets(span)
        if self.text[start:end].lstrip("^") != key[1].rpartition(".")[2]:
            return None  # a name the file does not spell here (a paper rule's R1, an inferred one)
        u = Use(key=key, role=role, start=start, end=end, where=where)
        self.index.uses.append(u)
        self.end = max(self.end, end)
        return u

    def declare(self, key: Key, span: A.Span) -> Use | None:
        u = self.use(key, Role.DECLARED, span, "")
        if u is not None:
            self.index.declarations.setdefault(key, u)
        return u

    def find(self, key: Key, role: Role, name: str, after: int, where: str) -> int:
        """A name the AST keeps without a span: its first occurrence after ``after``."""
        m = re.compile(_WORD.format(re.escape(name))).search(self.text, after)
        if m is None:
            return after
        line, col = self.lines.line_col(m.start())
        self.use(key, role, A.Span(line, col, line, col + len(m.group())), where)
        return m.end()

    # ------------------------------------------------------------ the file's parts
    def definitions(self) -> None:
        inferred = self.spec.dialect is A.Dialect.PAPER  # declared where first used
        for d in self.spec.definitions:
            kind = {A.EventDecl: Kind.EVENT, A.MeasureDecl: Kind.MEASURE, A.ConstantDecl: Kind.CONSTANT}.get(
                type(d)
            )
            if kind is None:
                continue
            if inferred:
                start, end = self.lines.span_offsets(d.span)
                first = Use(key=(kind, d.name), role=Role.DECLARED, start=start, end=end)
                self.index.declarations.setdefault((kind, d.name), first)
                continue
            u = self.declare((kind, d.name), d.span)
            detail = ""
            if isinstance(d, A.MeasureDecl):
                detail = str(d.type)
                if isinstance(d.type, A.ScaleType):
                    for v, s in zip(d.type.literals, d.type.literal_spans, strict=False):
                        self.declare((Kind.SCALE_VALUE, f"{d.name}.{v}"), s)
            elif isinstance(d, A.ConstantDecl):
                detail = f"= {'-> ' if d.arrow else ''}{d.value}"
                if isinstance(d.value, str) and u is not None:
                    self.find((Kind.CONSTANT, d.value), Role.READ, d.value, u.end, "")
            if u is not None:
                self.index.outline.append(
                    Extent(
                        key=(kind, d.name),
                        name_start=u.start,
                        name_end=u.end,
                        start=u.start,
                        end=u.end,
                        detail=detail,
                    )
                )

    def rule(self, r: A.Rule) -> None:
        name = self.use((Kind.RULE, r.name), Role.DECLARED, r.span, "")
        if name is not None:
            self.index.declarations.setdefault((Kind.RULE, r.name), name)
        start = self.lines.span_offsets(r.span)[0]
        self.end = start
        self.trigger(r.trigger, r.name)
        self.response(r.response, r.name, top=True)
        end = self.end
        while end < len(self.text) and self.text[end] in ")}] \t":  # what closes the rule's last part
            end += 1
        end = len(self.text[:end].rstrip())
        name_start, name_end = (name.start, name.end) if name else (start, start)
        self.index.outline.append(
            Extent(
                key=(Kind.RULE, r.name),
                name_start=name_start,
                name_end=name_end,
                start=start,
                end=max(end, name_end),
                detail=f"when {r.trigger.event}",
            )
        )

    def trigger(self, t: A.Trigger, where: str) -> None:
        self.use((Kind.EVENT, t.event), Role.TRIGGERS, t.span, where)
        self.expr(t.condition, where)

    def response(self, resp: A.Response | None, where: str, top: bool = False) -> None:
        if resp is None:
            return
        for item in resp.items:
            occ = item.occurrence
            role = Role.FORBIDDEN if occ.negated else Role.OBLIGED
            span = occ.span
            if occ.negated:  # the span starts at `not`: the name is at its end
                start = self.lines.offset(span.end_line, span.end_col) - len(occ.event)
                if start > 0 and self.text[start - 1] == "^":
                    start -= 1
                line, col = self.lines.line_col(start)
                span = A.Span(line, col, span.end_line, span.end_col)
            self.use((Kind.EVENT, occ.event), role, span, where)
            if occ.limit is not None:
                for d in (occ.limit.lo, occ.limit.hi):
                    if d is not None:
                        self.expr(d.value, where)
                        self.end = max(self.end, self.lines.span_offsets(d.span)[1])
            self.response(item.otherwise, where)
            self.response(item.alternative, where)
        for i, defeater in enumerate(resp.defeaters, start=1):
            clause = f"{where}.{i}" if top else where
            self.expr(defeater.condition, clause)
            self.response(defeater.response, clause)

    def expr(self, e: A.Expr | None, where: str, scale: str | None = None) -> None:
        if e is None:
            return
        self.end = max(self.end, self.lines.span_offsets(e.span)[1])
        if isinstance(e, A.Name):
            self.name(e, where, scale)
        elif isinstance(e, A.Not):
            self.expr(e.operand, where)
        elif isinstance(e, A.Compare):
            left, right = self.scale_of(e.left), self.scale_of(e.right)
            self.expr(e.left, where, right)
            self.expr(e.right, where, left)
        elif isinstance(e, A.BinOp):
            self.expr(e.left, where)
            self.expr(e.right, where)

    def scale_of(self, e: A.Expr) -> str | None:
        if isinstance(e, A.Name):
            m = self.symbols.measures.get(e.name)
            if m is not None and isinstance(m.type, A.ScaleType):
                return m.name
        return None

    def name(self, n: A.Name, where: str, scale: str | None) -> None:
        if n.name in self.symbols.constants:
            self.use((Kind.CONSTANT, n.name), Role.READ, n.span, where)
            return
        owners = self.scales.get(n.name, [])
        if n.name not in self.symbols.measures and owners:
            owner = scale if scale in owners else owners[0]
            self.use((Kind.SCALE_VALUE, f"{owner}.{n.name}"), Role.READ, n.span, where)
            return
        self.use((Kind.MEASURE, n.name), Role.READ, n.span, where)  # declared or not

    def situation(self, kind: Kind, s: A.Situation) -> None:
        u = self.declare((kind, s.name), s.span)
        self.end = u.end if u is not None else 0
        where = f"{kind} {s.name}"
        cur: A.Situation | None = s
        while cur is not None:
            self.trigger(cur.trigger, where)
            for resp in cur.responses:
                self.response(resp, where)
            cur = cur.meanwhile
        if u is not None:
            self.index.outline.append(
                Extent(
                    key=(kind, s.name),
                    name_start=u.start,
                    name_end=u.end,
                    start=u.start,
                    end=max(self.end, u.end),
                )
            )

    def relation(self, rel: A.Relation) -> None:
        where = "relation"
        after = self.lines.span_offsets(rel.span)[0]
        if isinstance(rel, A.EventRelation):
            after = self.find((Kind.EVENT, rel.first), Role.NAMED, rel.first, after + len(rel.kind), where)
            self.find((Kind.EVENT, rel.second), Role.NAMED, rel.second, after, where)
        elif isinstance(rel, A.MeasureRelation):
            self.expr(rel.first, where)
            self.expr(rel.second, where)
        elif isinstance(rel, A.EventMeasureRelation):
            self.find((Kind.EVENT, rel.event), Role.NAMED, rel.event, after + len(rel.kind), where)
            self.expr(rel.condition, where)
        elif isinstance(rel, A.UntilRelation):
            self.trigger(rel.trigger, where)
            self.expr(rel.condition, where)
            self.end = self.lines.span_offsets(rel.condition.span)[1]
            self.find((Kind.EVENT, rel.until_event), Role.NAMED, rel.until_event, self.end, where)
            self.expr(rel.until_condition, where)
        else:
            self.trigger(rel.trigger, where)
            self.expr(rel.condition, where)
            self.expr(rel.duration.value, where)


def names_of(spec: A.Specification | None) -> Iterator[tuple[Kind, str, str]]:
    """Every declared name of a specification with its kind and a detail (a measure's type,
    a constant's value): what completion offers."""
    if spec is None:
        return
    for d in spec.definitions:
        if isinstance(d, A.EventDecl):
            yield Kind.EVENT, d.name, "event"
        elif isinstance(d, A.MeasureDecl):
            yield Kind.MEASURE, d.name, f"measure : {d.type}"
        elif isinstance(d, A.ConstantDecl):
            yield Kind.CONSTANT, d.name, f"constant = {d.value}"
    for r in spec.rules:
        yield Kind.RULE, r.name, f"rule, when {r.trigger.event}"
