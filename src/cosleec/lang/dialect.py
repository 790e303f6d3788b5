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
from cosleec.lang.mistakes import untimed_otherwise

Feature = tuple[str, A.Span]
"""A construct (as a message names it) and where it is."""

_BLOCK_COMMENT = re.compile(r"//[^\n]*|(/\*)")
_ESCAPE = re.compile(r"//[^\n]*|/\*[\s\S]*?\*/|(\^)[A-Za-z_]")


@dataclass(frozen=True, slots=True)
class DialectFacts:
    """What one file uses that only one dialect has; use :func:`collect` to get them.

    ``legos`` lists the constructs only LEGOS-SLEEC has, in the order detection cites them
    (blocks, then conditions, deadlines, constants, responses); ``tk`` the constructs
    LEGOS-SLEEC's grammar rejects that SLEEC-TK's accepts (TK syntax); ``tk_rejects`` what
    else SLEEC-TK's grammar rejects, and ``legos_rejects`` what else LEGOS-SLEEC's rejects
    (textX, ``sleec-gramar.tx``), as complete messages; ``legos_misreads`` the names that
    LEGOS-SLEEC's parser would cut in two (:data:`LEGOS_PREFIXES`), as complete messages;
    ``extensions`` cosleec's own constructs, which neither tool accepts and which therefore
    say nothing about the dialect (the priority and semantics blocks); ``untimed_otherwise``
    each ``otherwise`` after a response without ``within`` (LEGOS-only, and in a SLEEC-TK file
    a forgotten deadline), as a message naming it and the fix.
    """

    legos: tuple[Feature, ...]
    tk: tuple[Feature, ...]
    tk_rejects: tuple[Feature, ...]
    extensions: tuple[Feature, ...] = ()
    legos_rejects: tuple[Feature, ...] = ()
    legos_misreads: tuple[Feature, ...] = ()
    untimed_otherwise: tuple[tuple[str, str, A.Span], ...] = ()  # (message, fix, where): see check_mixed


def collect(spec: A.Specification, text: str) -> DialectFacts:
    """Walk ``spec`` (and scan ``text`` for comments and escapes) once for its dialect facts."""
    w = _Walk({m.name: m.type for m in spec.measures})
    w.names(spec)
    blocks = [
        (f"a {kind} block", b.span)
        for kind in ("concern", "purpose", "relation")
        for b in spec.blocks
        if b.kind == kind
    ]
    for b in spec.blocks:
        if b.empty and b.kind in _LEGOS_ITEM:  # an empty rule block is an error in every mode
            w.legos_rejects.append(
                (
                    f"LEGOS-SLEEC rejects an empty {b.kind} block (its grammar needs at least one "
                    f"{_LEGOS_ITEM[b.kind]})",
                    b.span,
                )
            )
    for i, r in enumerate(spec.rules):
        if i:
            w.misread(r.name, r.span, _AFTER_RESPONSE, "rule name")
        w.event(r.trigger.event, r.trigger.span)
        w.condition(r.trigger.condition, w.trigger)
        w.response(r.response)
        if r.response.braced:
            w.tk_other.append(("braces around the rule's response", r.response.span))
    for block in (spec.concerns, spec.purposes):
        for i, s in enumerate(block):
            if i:
                w.misread(s.name, s.span, _AFTER_SITUATION, "concern or purpose name")
            cur: A.Situation | None = s
            while cur is not None:
                w.event(cur.trigger.event, cur.trigger.span)
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
        if c.sign or (isinstance(c.value, int) and c.value < 0):
            constants.append(("a signed number", c.span))
            if c.sign.endswith(" "):
                w.legos_rejects.append((_APART.format(c.sign.strip()), c.span))
        elif isinstance(c.value, str) and not c.arrow:
            w.tk_other.append((f"constant reference without `->` (LEGOS writes `-> {c.value}`)", c.span))
    for d in spec.definitions:
        if isinstance(d, A.FluentDecl):
            w.legos_rejects.append(
                (
                    "`fluent` is an extension of the CPeluti/LEGOS-SLEEC fork; LEGOS-SLEEC's grammar "
                    "rejects it",
                    d.span,
                )
            )
    legos = (*blocks, *w.trigger[0], *w.unless[0], *w.relations[0], *w.deadline[0], *constants, *w.items)
    tk = (
        *_text_features(text),
        *w.trigger[1],
        *w.unless[1],
        *w.relations[1],
        *w.deadline[1],
        *w.tk_other,
    )
    named = {
        "priority": "a priority block (`priority_start`)",
        "semantics": "a semantics block (`semantics_start`)",
    }
    extensions = tuple((named[b.kind], b.span) for b in spec.blocks if b.kind in named)
    return DialectFacts(
        legos,
        tk,
        tuple(w.tk_rejects),
        extensions,
        tuple(w.legos_rejects),
        tuple(w.misreads),
        tuple(w.untimed_otherwise),
    )


def legos_features(spec: A.Specification) -> tuple[Feature, ...]:
    """The constructs of ``spec`` that only LEGOS-SLEEC has, each with where it is."""
    return collect(spec, "").legos


def legos_misreads(spec: A.Specification) -> tuple[Feature, ...]:
    """The names of ``spec`` that LEGOS-SLEEC's parser would cut in two (:data:`LEGOS_PREFIXES`),
    each as a complete message and where the name is: what ``cosleec fmt --dialect legos``
    refuses to write, since LEGOS-SLEEC would not read the result as cosleec does."""
    return collect(spec, "").legos_misreads


def detect(facts: DialectFacts) -> tuple[A.Dialect, Feature | None]:
    """LEGOS if the file uses anything only LEGOS has (returned as the evidence); else TK.

    Files that both tools accept (no measure in any condition, say) count as TK.
    """
    if facts.legos:
        return A.Dialect.LEGOS, facts.legos[0]
    return A.Dialect.TK, None


def check_mixed(facts: DialectFacts, evidence: Feature, sink: DiagnosticSink) -> None:
    """A file with LEGOS-only syntax must not also use what LEGOS rejects: no tool reads a mix.

    The error goes where the mix is likeliest a mistake: when the file's only LEGOS syntax is
    an ``otherwise`` after a response without ``within`` -- a SLEEC-TK file with a forgotten
    deadline -- it goes to each such ``otherwise``, with the fix; otherwise to each TK construct.
    """
    what_legos, where = evidence
    accidental = {span for _, _, span in facts.untimed_otherwise}
    if facts.tk and accidental and all(span in accidental for _, span in facts.legos):
        what_tk, where_tk = facts.tk[0]
        for message, fix, span in facts.untimed_otherwise:
            sink.error(
                "mixed-dialect",
                f"{message}; so written it is LEGOS syntax, but the rest of this file is TK "
                f"syntax ({what_tk} at line {where_tk.line}), and no SLEEC tool accepts a mix",
                span,
                hint=fix,
            )
        return
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
        for message, span in facts.legos_rejects:
            sink.error("dialect", message, span)
        for message, span in facts.legos_misreads:
            sink.error("dialect", message, span, hint="rename it")
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


_LEGOS_ITEM = {"def": "definition", "concern": "concern", "purpose": "purpose", "relation": "relation"}
_APART = "LEGOS-SLEEC rejects a sign apart from its number (`{0} 3`): its numbers are one token, `{0}3`"

LEGOS_PREFIXES: dict[str, tuple[str, ...]] = {
    "response event": ("not",),
    "rule name": ("eventually", "otherwise", "else", "then"),
    "concern or purpose name": ("eventually", "otherwise", "else", "then", "while"),
}
"""The keywords LEGOS-SLEEC's parser tries where a name of each kind starts, and that would
cut a longer name in two. textX reserves no keyword and matches one as a prefix of a word:
after ``then``, ``notStop`` is read as ``not Stop``; after a rule's response, a next rule
named ``eventuallyServe`` is read as ``eventually`` and a rule ``Serve``. Only where the
rest of the parse then goes on (or fails) differently is a prefix listed: a keyword that
must be followed by what a name cannot start (``unless (``) backtracks harmlessly. The
first rule of a block and the first concern or purpose are read as names, and so is a
negated event (``not notify``)."""
_AFTER_RESPONSE = LEGOS_PREFIXES["rule name"]
_AFTER_SITUATION = LEGOS_PREFIXES["concern or purpose name"]
_AMONG = {
    "any": "everything with a name (events, measures, constants, scale literals, rules, concerns, purposes)",
    "event": "the events",
    "boolean": "the boolean measures",
    "constant": "the constants",
}


class _Walk:
    """The one walk of :func:`collect`. Each kind of place (trigger conditions, ``unless``
    conditions, relations, deadlines) keeps its own (LEGOS, TK) lists, so that the facts
    come out grouped in a fixed order, whatever order the walk visits them in."""

    def __init__(self, measures: dict[str, A.MeasureType]) -> None:
        self.measures = measures
        self.trigger: tuple[list[Feature], list[Feature]] = ([], [])
        self.unless: tuple[list[Feature], list[Feature]] = ([], [])
        self.relations: tuple[list[Feature], list[Feature]] = ([], [])
        self.deadline: tuple[list[Feature], list[Feature]] = ([], [])
        self.items: list[Feature] = []  # LEGOS-only response forms
        self.tk_other: list[Feature] = []
        self.tk_rejects: list[Feature] = []
        self.legos_rejects: list[Feature] = []
        self.misreads: list[Feature] = []
        self.untimed_otherwise: list[tuple[str, str, A.Span]] = []
        # names that LEGOS-SLEEC cannot resolve (textX: "name X is not unique"): carried by
        # two named things of any kind (``any``: measures, constants and scale literals are
        # looked up among everything with a name, rules and concerns included), or declared
        # twice as an event, a boolean measure or a constant (looked up by that kind)
        self.ambiguous: dict[str, frozenset[str]] = {}
        self._reported: set[tuple[str, str]] = set()

    def names(self, spec: A.Specification) -> None:
        """Find the names that more than one named thing carries (usually none)."""
        count: dict[str, int] = {}
        for d in spec.definitions:
            count[d.name] = count.get(d.name, 0) + 1
            if isinstance(d, A.MeasureDecl) and isinstance(d.type, A.ScaleType):
                for lit in d.type.literals:
                    count[lit] = count.get(lit, 0) + 1
        for named in (spec.rules, spec.concerns, spec.purposes):
            for x in named:
                count[x.name] = count.get(x.name, 0) + 1
        shared = {name for name, n in count.items() if n > 1}
        if not shared:
            return
        by_kind: dict[str, dict[str, int]] = {"event": {}, "boolean": {}, "constant": {}}
        for d in spec.definitions:
            kind = (
                "event"
                if isinstance(d, A.EventDecl)
                else "constant"
                if isinstance(d, A.ConstantDecl)
                else "boolean"
                if isinstance(d, A.MeasureDecl) and isinstance(d.type, A.BooleanType)
                else None
            )
            if kind is not None and d.name in shared:
                by_kind[kind][d.name] = by_kind[kind].get(d.name, 0) + 1
        for name in shared:
            kinds = {"any"} | {k for k, seen in by_kind.items() if seen.get(name, 0) > 1}
            self.ambiguous[name] = frozenset(kinds)

    def reference(self, name: str, span: A.Span, kind: str) -> None:
        """A reference that LEGOS-SLEEC resolves among the named things of ``kind``."""
        if kind in self.ambiguous.get(name, ()) and (name, kind) not in self._reported:
            self._reported.add((name, kind))
            among = _AMONG[kind]
            self.legos_rejects.append(
                (
                    f"LEGOS-SLEEC rejects this reference to `{name}`: it looks the name up among "
                    f'{among}, and more than one is called `{name}` (textX: "name {name} is not '
                    'unique")',
                    span,
                )
            )

    def event(self, name: str, span: A.Span) -> None:
        if self.ambiguous:
            self.reference(name, span, "event")

    def misread(self, name: str, span: A.Span, keywords: tuple[str, ...], what: str) -> None:
        """``name`` where LEGOS-SLEEC's parser first tries ``keywords``: a name that begins with
        one of them (and goes on) is cut in two."""
        if name.startswith(keywords):
            kw = next(k for k in keywords if name.startswith(k))
            if len(name) > len(kw):
                self.misreads.append(
                    (
                        f"the {what} `{name}` begins with the keyword `{kw}`: LEGOS-SLEEC's parser "
                        f"(textX, which reserves no keyword and matches one as the start of a word) "
                        f"reads it as `{kw} {name[len(kw) :]}`",
                        span,
                    )
                )

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
            elif not occ.negated:
                self.misread(occ.event, occ.span, LEGOS_PREFIXES["response event"], "response event")
            if self.ambiguous:
                self.reference(occ.event, occ.span, "event")
            if item.otherwise is not None:
                if occ.negated or occ.limit is None:
                    self.items.append(
                        ("`otherwise` after a prohibition or an untimed response", item.otherwise.span)
                    )
                if occ.limit is None and not occ.eventually:
                    self.untimed_otherwise.append((*untimed_otherwise(item), item.otherwise.span))
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
        self.condition(d.value, self.deadline, num=True)

    def relation(self, rel: A.Relation) -> None:
        if isinstance(rel, A.EventRelation):
            if rel.kind == "isContradictoryWith":
                self.legos_rejects.append(
                    (
                        "`isContradictoryWith` is an extension of the NickF0211/sleecvalDef fork; "
                        "LEGOS-SLEEC's grammar rejects it (write `mutualExclusive`)",
                        rel.span,
                    )
                )
            if self.ambiguous:
                self.reference(rel.first, rel.span, "event")
                self.reference(rel.second, rel.span, "event")
        elif isinstance(rel, A.MeasureRelation):
            self.condition(rel.first, self.relations)
            self.condition(rel.second, self.relations)
        elif isinstance(rel, A.EventMeasureRelation):
            if self.ambiguous:
                self.reference(rel.event, rel.span, "event")
            self.condition(rel.condition, self.relations)
        elif isinstance(rel, A.UntilRelation):
            self.event(rel.trigger.event, rel.trigger.span)
            self.condition(rel.trigger.condition, self.trigger)
            self.condition(rel.condition, self.relations)
            self.event(rel.until_event, rel.span)
            self.condition(rel.until_condition, self.relations)
        elif isinstance(rel, A.ForRelation):
            self.legos_rejects.append(
                (
                    "LEGOS-SLEEC never reads a `for` relation: its grammar tries the `until` form "
                    "first, whose `until` is optional, and then stops at `for`",
                    rel.span,
                )
            )
            self.event(rel.trigger.event, rel.trigger.span)
            self.condition(rel.trigger.condition, self.trigger)
            self.condition(rel.condition, self.relations)
            self.duration(rel.duration)

    def condition(
        self, e: A.Expr | None, into: tuple[list[Feature], list[Feature]], num: bool = False
    ) -> None:
        """The features of expression ``e``, node by node in pre-order, left first. ``num``:
        ``e`` is where LEGOS-SLEEC's grammar expects a number (an operand of a comparison or
        of arithmetic, a deadline), where it takes a name without braces."""
        if e is None:
            return
        legos, tk = into
        t = type(e)
        if t is A.Name:
            n: A.Name = e  # type: ignore[assignment]
            if n.braced or n.arrow:
                legos.append(("`{m}` measure braces" if n.braced else "`->C` constant reference", n.span))
            if not num and not n.braced and n.name in self.measures:
                tk.append((f"bare measure `{n.name}` as a condition (LEGOS writes `{{{n.name}}}`)", n.span))
            if n.parenthesized:
                tk.append((f"`({n.name})`, a lone name in parentheses (LEGOS writes it without)", n.span))
            if self.ambiguous:
                # `{m}` as a condition is LEGOS's BoolTerminal (boolean measures only), `-> C`
                # its Value (constants only); elsewhere a name is looked up among all names
                kind = "constant" if n.arrow else "any" if num else "boolean"
                self.reference(n.name, n.span, kind)
        elif t is A.BinOp or t is A.Compare:
            b: A.BinOp | A.Compare = e  # type: ignore[assignment]
            arith = t is A.BinOp and b.op in A.ARITH_OPS
            if arith:
                legos.append(("arithmetic", b.span))
            if not b.parenthesized:
                tk.append((f"`{b.op}` outside its own parentheses", b.span))
            elif b.parenthesized > 1:
                self.legos_rejects.append(_redundant(f"`{b.op}`", b.parenthesized, b.span, operator=True))
            if t is A.Compare:
                for side in (b.left, b.right):
                    if type(side) is A.BoolLit:
                        word = "true" if side.value else "false"
                        self.legos_rejects.append(
                            (
                                f"LEGOS-SLEEC rejects `{word}` as an operand of `{b.op}`: its "
                                f"comparisons are between numbers and scales (write `{{p}}` or "
                                "`(not {p})` for a boolean measure p)",
                                side.span,
                            )
                        )
            inner = t is A.Compare or arith
            self.condition(b.left, into, inner)
            self.condition(b.right, into, inner)
        elif t is A.Not:
            neg: A.Not = e  # type: ignore[assignment]
            if not neg.parenthesized:
                tk.append(("`not` outside parentheses (LEGOS writes `(not X)`)", neg.span))
            elif neg.parenthesized > 1:
                self.legos_rejects.append(_redundant("`not`", neg.parenthesized, neg.span, operator=True))
            self.condition(neg.operand, into)
        elif t is A.IntLit:
            i: A.IntLit = e  # type: ignore[assignment]
            if i.value < 0 or i.sign:
                legos.append(("a signed number", i.span))
                if i.sign.endswith(" "):
                    self.legos_rejects.append((_APART.format(i.sign.strip()), i.span))
            if i.parenthesized:
                self.legos_rejects.append(_redundant(f"`{i.value}`", i.parenthesized, i.span, operator=False))
        elif e.parenthesized:  # a BoolLit or a DecimalLit
            text = e.text if t is A.DecimalLit else ("true" if e.value else "false")  # type: ignore[union-attr]
            self.legos_rejects.append(_redundant(f"`{text}`", e.parenthesized, e.span, operator=False))


def _redundant(what: str, pairs: int, span: A.Span, *, operator: bool) -> Feature:
    """LEGOS-SLEEC's grammar has one pair of parentheses around each operator and none around
    a literal: more is a syntax error there."""
    if operator:
        return (
            f"LEGOS-SLEEC rejects {what} in {pairs} pairs of parentheses: its grammar puts exactly "
            "one pair around each operator",
            span,
        )
    return (
        f"LEGOS-SLEEC rejects {what} in parentheses: its grammar puts none around a literal",
        span,
    )
