"""Canonical SLEEC text in either dialect (``cosleec fmt``).

The printer's contract is round-tripping: for every AST, ``parse(print(ast)) == ast``
(spans and syntactic hints aside). It therefore adds exactly the parentheses and braces
needed to keep the tree's shape under TK precedence and the greedy attachment rules of
docs/reference/sleec-language.md §4.5, and in the LEGOS dialect it writes LEGOS' mandatory forms
(``{m}``, every operator in its own parentheses, ``(not X)``, ``-> C``).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

from cosleec.bulk import paused_gc
from cosleec.lang import ast as A
from cosleec.lang.deep import deeply
from cosleec.lang.layout import Comment, Key, Layout
from cosleec.lang.parser import CONTEXTUAL_KEYWORDS, KEYWORDS, PAPER

WIDTH = 100
"""The line width past which ``fmt`` prints a rule one clause per line."""

# precedence levels of the unified grammar (higher binds tighter)
_LEVEL = {"and": 1, "or": 1, "not": 2, "cmp": 3, "+": 4, "-": 4, "*": 5}
_ATOM = 6


class Printer:
    """Prints one specification in one dialect; use :func:`format_spec` for a whole file,
    the methods for one part of it (a rule, a response, an expression).

    With a :class:`~cosleec.lang.layout.Layout` (see :func:`cosleec.lang.formatter.format_source`), the whole file
    keeps the source's comments and blank lines, and a rule longer than ``width`` (or with
    comments between its clauses) is printed one clause per line.
    """

    def __init__(
        self,
        spec: A.Specification,
        dialect: A.Dialect,
        layout: Layout | None = None,
        width: int = WIDTH,
    ) -> None:
        self.legos = dialect is A.Dialect.LEGOS
        self.measures = {m.name for m in spec.measures}
        self.spec = spec
        self.reserved = KEYWORDS  # the words that need SLEEC-TK's `^` escape to be names
        self.layout = layout if layout is not None else Layout()
        self.width = width

    def name(self, n: str) -> str:
        """A name as the DSL reads it back: a keyword gets SLEEC-TK's ``^`` escape."""
        return "^" + n if n in self.reserved else n

    def kw(self, word: str) -> str:
        """A keyword of an expression (``and``, ``not``, ``true``...) as this notation writes it."""
        return word

    # ------------------------------------------------------------------ whole file
    def specification(self) -> str:
        """The whole file: a non-empty semantics block, def and rule blocks (always), then
        non-empty concern, purpose, relation and priority blocks (the last one pair a line,
        chains written as pairs)."""
        spec = self.spec
        out = _Lines(self)
        # how the rules are read comes before them (wherever the file had it)
        self.block(out, "semantics", [[f"{d.aspect} {d.value}"] for d in spec.semantics])
        if not any(b.kind == "def" for b in spec.blocks):  # declarations inferred: printed first,
            first = ("start", "rule") if ("start", "rule") in self.layout.leading else ("rule", 0)
            out.comments(self.layout.leading.pop(first, []))  # under the file's header comments
        self.block(out, "def", [[self.definition(d)] for d in spec.definitions], always=True)
        self.block(out, "rule", [self.rule_clauses(r) for r in spec.rules], always=True)
        for kind, situations in (("concern", spec.concerns), ("purpose", spec.purposes)):
            bodies = [[f"{self.name(s.name)} {self.situation_body(s)}"] for s in situations]
            self.block(out, kind, bodies)
        self.reserved = KEYWORDS | CONTEXTUAL_KEYWORDS
        self.block(out, "relation", [[self.relation(r)] for r in spec.relations])
        self.reserved = KEYWORDS
        pairs = [[f"{self.name(p.higher)} > {self.name(p.lower)}"] for p in spec.priorities]
        self.block(out, "priority", pairs)
        out.closing()
        return out.text()

    def block(self, out: _Lines, kind: str, bodies: list[list[str]], always: bool = False) -> None:
        """One block, ``kind_start`` to ``kind_end``, each item's text given as its clauses."""
        keep = self.layout.has_comments(("start", kind)) or self.layout.has_comments(("end", kind))
        if not bodies and not always and not keep:  # an empty block goes, unless commented
            return
        out.blank()
        out.item(("start", kind), "", [f"{kind}_start"], opens=True)
        if out.plain():
            out.plain_items("    ", bodies)  # no comments or blank lines to put back
        else:
            for i, clauses in enumerate(bodies):
                out.item((kind, i), "    ", clauses)
        out.item(("end", kind), "", [f"{kind}_end"], closes=True)

    def comment_lines(self, text: str) -> list[str]:
        """An own-line comment as lines: as written, except that LEGOS-SLEEC, which has no
        ``/* */`` comments, gets a block comment as ``//`` lines."""
        if not (self.legos and text.startswith("/*")):
            return [text]
        lines = [line.strip() for line in text[2:-2].split("\n")]
        while lines and not lines[0]:
            lines.pop(0)
        while lines and not lines[-1]:
            lines.pop()
        return [f"// {line}" if line else "//" for line in lines] or ["//"]

    def trailing_comment(self, text: str) -> str:
        """A comment at the end of a line: a block comment for LEGOS-SLEEC becomes one ``//``."""
        if not (self.legos and text.startswith("/*")):
            return text
        words = " ".join(line.strip() for line in text[2:-2].split("\n") if line.strip())
        return f"// {words}" if words else "//"

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
        return " ".join(self.rule_clauses(r))

    def rule_clauses(self, r: A.Rule) -> list[str]:
        """A rule as its clauses: ``R when trigger then response``, then each ``unless``.
        Joined by spaces they are the rule on one line; one a line, the wrapped form."""
        head, clauses = self.response_parts(r.response)
        return [f"{self.name(r.name)} when {self.trigger(r.trigger)} then {head}", *clauses]

    def trigger(self, t: A.Trigger) -> str:
        """A trigger: ``E`` or ``E and condition``."""
        if t.condition is None:
            return self.name(t.event)
        return f"{self.name(t.event)} and {self.expr(t.condition)}"

    # ------------------------------------------------------------------ responses
    def response(self, r: A.Response, braced: bool) -> str:
        """A response: its items joined by ``and``, then its ``unless`` clauses; in braces if ``braced``."""
        text, clauses = self.response_parts(r)
        text = " ".join([text, *clauses])
        return f"{{{text}}}" if braced else text

    def response_parts(self, r: A.Response) -> tuple[str, list[str]]:
        """A response's items joined by ``and``, and its ``unless`` clauses, one text each."""
        items = r.items
        n = len(items)
        if n == 1:  # the common case: nothing follows the one item
            text = self.item(items[0], False)
        else:
            # inside an item, what follows an inner response would be swallowed by it
            text = " and ".join([self.item(item, i < n - 1) for i, item in enumerate(items)])
        defeaters = r.defeaters
        return text, [self.defeater(d) for d in defeaters] if defeaters else []

    def defeater(self, d: A.Defeater) -> str:
        """One hedge clause: ``unless condition [then response]``."""
        text = f"unless {self.expr(d.condition)}"
        if d.response is not None:
            text += f" then {self.inner(d.response, followed=False)}"
        return text

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
            return self.kw("true" if e.value else "false")
        if isinstance(e, A.IntLit):
            return str(e.value)
        if isinstance(e, A.DecimalLit):
            return e.text
        if isinstance(e, A.Not):
            if self.legos:
                return f"(not {self.expr(e.operand, _ATOM)})"
            text = f"{self.kw('not')} {self.expr(e.operand, _LEVEL['not'])}"
            return f"({text})" if need > _LEVEL["not"] else text
        if isinstance(e, A.Compare):
            level = _LEVEL["cmp"]
            text = f"{self.expr(e.left, level + 1)} {e.op} {self.expr(e.right, level + 1)}"
        else:
            level = _LEVEL[e.op]
            # left-associative: the right operand needs a tighter binding than the operator
            text = f"{self.expr(e.left, level)} {self.kw(e.op)} {self.expr(e.right, level + 1)}"
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


class _Lines:
    """The lines of a printed file, with the layout's comments and blank lines put back.

    Blank lines are asked for, not written: one is written before the next line unless it
    would open a block's body, close a block, or follow another blank (so a file never has
    two blank lines in a row, nor one just inside a block).
    """

    def __init__(self, printer: Printer) -> None:
        self.printer = printer
        self.layout = printer.layout
        self.lines: list[str] = []
        self.pending = False
        self.opened = True  # at the start of the file or of a block's body

    def blank(self) -> None:
        self.pending = True

    def plain(self) -> bool:
        """Whether the layout has nothing to put back (no comment, no blank line): the
        canonical form, where :meth:`plain_items` prints a block's items the same way."""
        layout = self.layout
        return not (layout.leading or layout.trailing or layout.inner or layout.blank)

    def plain_items(self, indent: str, bodies: list[list[str]]) -> None:
        """What :meth:`item` prints for each of ``bodies`` when the layout is :meth:`plain`."""
        if not bodies:
            return
        lines = self.lines
        if self.pending and not self.opened:
            lines.append("")
        self.pending = False
        self.opened = False
        width = self.printer.width - len(indent)
        more = indent + "    "
        for clauses in bodies:
            if len(clauses) == 1:
                lines.append(indent + clauses[0])
                continue
            one_line = " ".join(clauses)
            if len(one_line) > width:
                lines.append(indent + clauses[0])
                lines.extend([more + clause for clause in clauses[1:]])
            else:
                lines.append(indent + one_line)

    def add(self, line: str, *, opens: bool = False, closes: bool = False) -> None:
        if self.pending and not self.opened and not closes:
            self.lines.append("")
        self.pending = False
        self.lines.append(line)
        self.opened = opens

    def comment(self, c: Comment, indent: str) -> None:
        """An own-line comment (a blank line first if the source had one)."""
        if c.blank_before:
            self.blank()
        for text in self.printer.comment_lines(c.text):
            self.add(indent + text)

    def trail(self, comments: list[Comment]) -> str:
        """Trailing comments as the end of a line: ``""`` or ``" // ..."``."""
        return "".join(" " + self.printer.trailing_comment(c.text) for c in comments)

    def item(
        self, key: Key, indent: str, clauses: list[str], opens: bool = False, closes: bool = False
    ) -> None:
        """One anchor: its leading comments, a blank line if it had one, then its text with
        its trailing comments; a rule one clause per line when it is long or commented inside."""
        layout = self.layout
        inside = indent + "    " if closes else indent
        for c in layout.leading.get(key, ()):
            self.comment(c, inside)
        if key in layout.blank:
            self.blank()
        one_line = " ".join(clauses)
        wrap = len(clauses) > 1 and (
            len(indent) + len(one_line) > self.printer.width
            or layout.has_inner(key)
            or len(layout.trailing_clauses(key)) > 1
        )
        # after the item, what follows it is printed at this indentation
        after = indent + "    " if opens else "" if closes else indent
        if not wrap:
            trailing = sorted(
                (c for k in range(len(clauses)) for c in layout.trailing.get((key, k), ())),
                key=lambda c: c.offset,
            )
            self.line(indent + one_line, trailing, after, opens=opens, closes=closes)
            return
        for k, clause in enumerate(clauses):
            at = indent if k == 0 else indent + "    "
            for c in layout.inner.get((key, k), ()):
                self.comment(c, at)
            last = k == len(clauses) - 1
            self.line(at + clause, layout.trailing.get((key, k), []), after if last else indent + "    ")

    def line(
        self, text: str, trailing: list[Comment], after: str, opens: bool = False, closes: bool = False
    ) -> None:
        """A line of code with its trailing comments. A comment may follow another on the line
        only after a one-line block comment (after a ``//`` it would be part of it, after a
        multi-line one it would share its last line with code); the others go on lines of
        their own, after it, at the indentation of what follows (``after``)."""
        on_line: list[Comment] = []
        for c in trailing:
            if on_line:
                printed = self.printer.trailing_comment(on_line[-1].text)  # LEGOS: `/* */` is `//`
                if not printed.startswith("/*") or "\n" in printed:
                    break
            on_line.append(c)
        self.add(text + self.trail(on_line), opens=opens, closes=closes)
        spilled = trailing[len(on_line) :]
        if spilled and closes:
            self.blank()  # they lead what comes next: the next block, or the file's end
        for c in spilled:
            self.comment(replace(c, blank_before=False), after)

    def comments(self, comments: Iterable[Comment], indent: str = "") -> None:
        for c in comments:
            self.comment(c, indent)

    def closing(self) -> None:
        """The comments after the last token of the file."""
        self.comments(self.layout.closing)

    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def format_spec(spec: A.Specification, dialect: A.Dialect | str | None = None) -> str:
    """Canonical text of ``spec`` without comments; by default in the dialect it was written
    in, the paper notation as TK (what a rule set's digest is computed from). For what
    ``cosleec fmt`` prints, see :func:`cosleec.lang.formatter.format_source`."""
    d = A.Dialect(dialect) if dialect is not None else spec.dialect
    if d is A.Dialect.PAPER:
        d = A.Dialect.TK
    printer = Printer(spec, d)
    with paused_gc():  # many small strings, no garbage cycles (see cosleec.bulk)
        return deeply(printer.specification)  # recursive: a deep expression runs in a deep thread


class PaperPrinter(Printer):
    """Prints rules in the CO-SLEEC paper's notation::

        WHEN CurtainOpenRequest THEN OpenCurtains
            UNLESS userUndressed IN WHICH CASE (Refuse AND ExplainWhy)

    The notation has no def block (a reader infers the declarations from use), no constants,
    no ``else``, ``eventually`` or intervals, no ``unless`` inside a response, and no
    concern, purpose, relation or priority blocks. What it cannot say is collected in
    :attr:`problems` (a message and where) instead of being printed wrong.
    """

    def __init__(self, spec: A.Specification, layout: Layout | None = None, width: int = WIDTH) -> None:
        super().__init__(spec, A.Dialect.TK, layout, width)
        self.lexicon = PAPER.lexicon  # the paper grammar's own reserved words
        self.position = 0  # of the rule being printed (1-based): unnamed rules are R1, R2, ...
        self.problems: list[tuple[str, A.Span]] = []

    def name(self, n: str) -> str:
        """A name the paper grammar reads back: a keyword (case-insensitive here) escaped."""
        return "^" + n if self.lexicon.reserved(n) else n

    def kw(self, word: str) -> str:
        """Keywords in capitals, as the paper writes them (the notation is case-insensitive)."""
        return word.upper()

    def cannot(self, what: str, span: A.Span) -> None:
        """Record one thing the notation cannot say, and where it is."""
        self.problems.append((f"the paper notation has no {what}", span))

    def specification(self) -> str:
        """The rules, one after another; what has no place in the notation is refused
        (see :attr:`problems`), except comments, which are kept at the top."""
        spec = self.spec
        out = _Lines(self)
        for d in spec.definitions:
            if isinstance(d, A.ConstantDecl):
                self.cannot(f"constants: `{d.name}` would be read as a measure", d.span)
            elif isinstance(d, A.FluentDecl):
                self.cannot(f"fluents: `{d.name}`", d.span)
        for kind, group in (
            ("concern", spec.concerns),
            ("purpose", spec.purposes),
            ("relation", spec.relations),
            ("priority", spec.priorities),
            ("semantics", spec.semantics),
        ):
            for node in group[:1]:
                self.cannot(f"{kind} block", node.span)
        # what has no place in the notation keeps its comments, at the top
        homeless = self.layout.comments_outside({("rule", i) for i in range(len(spec.rules))})
        out.comments(replace(c, blank_before=False) for c in homeless)
        if homeless:
            out.blank()
        for i, r in enumerate(spec.rules):
            self.position = i + 1
            out.item(("rule", i), "", self.rule_clauses(r))
        out.closing()
        return out.text()

    def rule_clauses(self, r: A.Rule) -> list[str]:
        """``R1: WHEN trigger THEN response``, then each ``UNLESS`` clause."""
        head, clauses = self.response_parts(r.response)
        # as the paper writes rules: unnamed, when the name is the one position gives
        name = "" if r.name == f"R{self.position}" else f"{self.name(r.name)}: "
        return [f"{name}WHEN {self.trigger(r.trigger)} THEN {head}", *clauses]

    def trigger(self, t: A.Trigger) -> str:
        """``E`` or ``E AND condition``."""
        if t.condition is None:
            return self.name(t.event)
        return f"{self.name(t.event)} AND {self.expr(t.condition)}"

    def response_parts(self, r: A.Response) -> tuple[str, list[str]]:
        """The items and the ``UNLESS`` clauses of a rule's response."""
        return self.items(r, followed=False), [self.defeater(d) for d in r.defeaters]

    def items(self, r: A.Response, followed: bool) -> str:
        """A response's items: ``A``, or ``(A AND B)``; parenthesised too when text follows."""
        n = len(r.items)
        text = " AND ".join(self.item(item, i < n - 1) for i, item in enumerate(r.items))
        return f"({text})" if n > 1 or followed else text

    def defeater(self, d: A.Defeater) -> str:
        """``UNLESS condition [IN WHICH CASE response]``."""
        text = f"UNLESS {self.expr(d.condition)}"
        if d.response is not None:
            text += f" IN WHICH CASE {self.inner(d.response, followed=False)}"
        return text

    def inner(self, r: A.Response, followed: bool) -> str:
        """An inner response: its items only (the notation has no ``unless`` inside one)."""
        for d in r.defeaters:
            self.cannot("`unless` inside a response", d.span)
        return self.items(r, followed)

    def item(self, item: A.ResponseItem, followed: bool) -> str:
        """``E [WITHIN d] [OTHERWISE response]``."""
        text = self.occurrence(item.occurrence)
        if item.otherwise is not None:
            text += " OTHERWISE " + self.inner(item.otherwise, followed)
        if item.alternative is not None:
            self.cannot("`else`", item.alternative.span)
        return text

    def occurrence(self, o: A.Occurrence) -> str:
        """``[NOT] E [WITHIN d]``."""
        text = ("NOT " if o.negated else "") + self.name(o.event)
        if o.limit is not None:
            if o.limit.lo is not None:
                self.cannot("interval deadlines (`within [lo, hi]`)", o.limit.span)
            text += f" WITHIN {self.duration(o.limit.hi)}"
        if o.eventually:
            self.cannot("`eventually`", o.span)
        return text

    def duration(self, d: A.Duration) -> str:
        """``30 SECONDS``: units are keywords of the notation, in capitals as the others."""
        unit = d.unit.upper() if d.unit in A.TIME_UNITS else self.name(d.unit)
        return f"{self.expr(d.value)} {unit}"

    def comment_lines(self, text: str) -> list[str]:
        """Comments as written: the paper notation has both kinds."""
        return [text]

    def trailing_comment(self, text: str) -> str:
        """Comments as written: the paper notation has both kinds."""
        return text
