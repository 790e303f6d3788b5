"""Canonical SLEEC text in either dialect (``cosleec fmt``).

The printer's contract is round-tripping: for every AST, ``parse(print(ast)) == ast``
(spans and syntactic hints aside). It therefore adds exactly the parentheses and braces
needed to keep the tree's shape under TK precedence and the greedy attachment rules of
docs/reference/sleec-language.md §4.5, and in the LEGOS dialect it writes LEGOS' mandatory forms
(``{m}``, every operator in its own parentheses, ``(not X)``, ``-> C``).
"""

from __future__ import annotations

from cosleec.lang import ast as A
from cosleec.lang.deep import deeply
from cosleec.lang.parser import CONTEXTUAL_KEYWORDS, KEYWORDS

# precedence levels of the unified grammar (higher binds tighter)
_LEVEL = {"and": 1, "or": 1, "not": 2, "cmp": 3, "+": 4, "-": 4, "*": 5}
_ATOM = 6


class Printer:
    """Prints one specification in one dialect; use :func:`format_spec` for a whole file,
    the methods for one part of it (a rule, a response, an expression)."""

    def __init__(self, spec: A.Specification, dialect: A.Dialect) -> None:
        self.legos = dialect is A.Dialect.LEGOS
        self.measures = {m.name for m in spec.measures}
        self.spec = spec
        self.reserved = KEYWORDS  # the words that need SLEEC-TK's `^` escape to be names

    def name(self, n: str) -> str:
        """A name as the DSL reads it back: a keyword gets SLEEC-TK's ``^`` escape."""
        return "^" + n if n in self.reserved else n

    # ------------------------------------------------------------------ whole file
    def specification(self) -> str:
        """The whole file: def and rule blocks (always), then non-empty concern, purpose,
        relation and priority blocks (the last one pair a line, chains written as pairs)."""
        spec = self.spec
        out = ["def_start"]
        for d in spec.definitions:
            out.append("    " + self.definition(d))
        out.append("def_end")
        out.append("")
        out.append("rule_start")
        for r in spec.rules:
            out.append("    " + self.rule(r))
        out.append("rule_end")
        for kind, items in (("concern", spec.concerns), ("purpose", spec.purposes)):
            if items:
                out += ["", f"{kind}_start"]
                out += ["    " + f"{self.name(s.name)} {self.situation_body(s)}" for s in items]
                out.append(f"{kind}_end")
        if spec.relations:
            out += ["", "relation_start"]
            self.reserved = KEYWORDS | CONTEXTUAL_KEYWORDS
            out += ["    " + self.relation(r) for r in spec.relations]
            self.reserved = KEYWORDS
            out.append("relation_end")
        if spec.priorities:
            out += ["", "priority_start"]
            out += [f"    {self.name(p.higher)} > {self.name(p.lower)}" for p in spec.priorities]
            out.append("priority_end")
        return "\n".join(out) + "\n"

    def definition(self, d: A.Definition) -> str:
        """One def-block line: ``event E``, ``measure m : type``, ``constant N = v`` or ``fluent F``."""
        name = self.name(d.name)
        if isinstance(d, A.EventDecl):
            return f"event {name}"
        if isinstance(d, A.MeasureDecl):
            if isinstance(d.type, A.ScaleType):
                return f"measure {name} : scale({', '.join(map(self.name, d.type.literals))})"
            return f"measure {name} : {d.type}"
        if isinstance(d, A.ConstantDecl):
            if isinstance(d.value, int):
                return f"constant {name} = {d.value}"
            value = self.name(d.value)
            return f"constant {name} = -> {value}" if self.legos else f"constant {name} = {value}"
        starts, ends = ", ".join(map(self.name, d.initiating)), ", ".join(map(self.name, d.terminating))
        return f"fluent {name} <{{{starts}}}, {{{ends}}}>"

    def rule(self, r: A.Rule) -> str:
        """One rule line, ``R when trigger then response``, the top-level response unbraced."""
        response = self.response(r.response, braced=False)
        return f"{self.name(r.name)} when {self.trigger(r.trigger)} then {response}"

    def trigger(self, t: A.Trigger) -> str:
        """A trigger: ``E`` or ``E and condition``."""
        if t.condition is None:
            return self.name(t.event)
        return f"{self.name(t.event)} and {self.expr(t.condition)}"

    # ------------------------------------------------------------------ responses
    def response(self, r: A.Response, braced: bool) -> str:
        """A response: its items joined by ``and``, then its ``unless`` clauses; in braces if ``braced``."""
        parts = []
        n = len(r.items)
        for i, item in enumerate(r.items):
            # inside an item, what follows an inner response would be swallowed by it
            followed = i < n - 1
            parts.append(self.item(item, followed))
        text = " and ".join(parts)
        for d in r.defeaters:
            text += f" unless {self.expr(d.condition)}"
            if d.response is not None:
                text += f" then {self.inner(d.response, followed=False)}"
        return f"{{{text}}}" if braced else text

    def item(self, item: A.ResponseItem, followed: bool) -> str:
        """One response item with its ``otherwise``/``else``; ``followed``: more text comes after it."""
        text = self.occurrence(item.occurrence)
        if item.otherwise is not None:
            text += " otherwise " + self.inner(item.otherwise, followed or item.alternative is not None)
        if item.alternative is not None:
            text += " else " + self.inner(item.alternative, followed)
        return text

    def inner(self, r: A.Response, followed: bool) -> str:
        """An inner response: braced when it has defeaters or would swallow what follows."""
        return self.response(r, braced=bool(r.defeaters) or followed)

    def occurrence(self, o: A.Occurrence) -> str:
        """An occurrence: ``[not] E [within d | within [lo, hi]] [eventually]``."""
        text = ("not " if o.negated else "") + self.name(o.event)
        if o.limit is not None:
            if o.limit.lo is None:
                text += f" within {self.duration(o.limit.hi)}"
            else:
                text += f" within [{self.duration(o.limit.lo)}, {self.duration(o.limit.hi)}]"
        if o.eventually:
            text += " eventually"
        return text

    def duration(self, d: A.Duration) -> str:
        """A duration ``value unit``; a unit that is no time unit is printed as a name."""
        unit = d.unit if d.unit in A.TIME_UNITS else self.name(d.unit)
        return f"{self.expr(d.value)} {unit}"

    # ------------------------------------------------------------------ expressions
    def expr(self, e: A.Expr, need: int = 0) -> str:
        """``e`` as text, parenthesised if it binds looser than ``need``."""
        if isinstance(e, A.Name):
            if self.legos and e.name in self.measures:
                return f"{{{self.name(e.name)}}}"
            return self.name(e.name)
        if isinstance(e, A.BoolLit):
            return "true" if e.value else "false"
        if isinstance(e, A.IntLit):
            return str(e.value)
        if isinstance(e, A.DecimalLit):
            return e.text
        if isinstance(e, A.Not):
            if self.legos:
                return f"(not {self.expr(e.operand, _ATOM)})"
            text = f"not {self.expr(e.operand, _LEVEL['not'])}"
            return f"({text})" if need > _LEVEL["not"] else text
        if isinstance(e, A.Compare):
            level = _LEVEL["cmp"]
            text = f"{self.expr(e.left, level + 1)} {e.op} {self.expr(e.right, level + 1)}"
        else:
            level = _LEVEL[e.op]
            # left-associative: the right operand needs a tighter binding than the operator
            text = f"{self.expr(e.left, level)} {e.op} {self.expr(e.right, level + 1)}"
        if self.legos or need > level:
            return f"({text})"
        return text

    # ------------------------------------------------------------------ LEGOS blocks
    def situation_body(self, s: A.Situation) -> str:
        """A concern or purpose after its name: ``when|exists trigger [then|while R ...] [meanwhile (...)]``."""
        text = f"{s.kind} {self.trigger(s.trigger)}"
        if s.responses:
            joiner = " then " if s.kind == "when" else " while "
            text += joiner + " while ".join(self.response(r, braced=False) for r in s.responses)
        if s.meanwhile is not None:
            text += f" meanwhile ({self.situation_body(s.meanwhile)})"
        return text

    def relation(self, r: A.Relation) -> str:
        """One relation-block line, e.g. ``mutualExclusive A B`` or ``when A then p until B``."""
        if isinstance(r, A.EventRelation):
            return f"{r.kind} {self.name(r.first)} {self.name(r.second)}"
        if isinstance(r, A.MeasureRelation):
            if r.second is None:
                return f"measure invariant {self.expr(r.first, _ATOM)}"
            return f"measure {r.kind} {self.expr(r.first, _ATOM)} {self.expr(r.second, _ATOM)}"
        if isinstance(r, A.EventMeasureRelation):
            return f"{r.kind} {self.name(r.event)} {self.expr(r.condition, _ATOM)}"
        if isinstance(r, A.UntilRelation):
            until = self.name(r.until_event)
            text = f"when {self.trigger(r.trigger)} then {self.expr(r.condition)} until {until}"
            if r.until_condition is not None:
                text += f" and {self.expr(r.until_condition)}"
            return text
        return f"when {self.trigger(r.trigger)} then {self.expr(r.condition)} for {self.duration(r.duration)}"


def format_spec(spec: A.Specification, dialect: A.Dialect | str | None = None) -> str:
    """Canonical text of ``spec``; by default in the dialect it was written in (paper -> TK)."""
    d = A.Dialect(dialect) if dialect is not None else spec.dialect
    if d is A.Dialect.PAPER:
        d = A.Dialect.TK
    printer = Printer(spec, d)
    return deeply(printer.specification)  # recursive: a deep expression runs in a deep thread
