"""Text -> :class:`~cosleec.lang.ast.Specification`, with syntax diagnostics.

Both grammars live in ``grammar/*.lark``; Lark builds their LALR tables once, at import.
Each :class:`Grammar` then holds two readings of the same grammar: plain Lark (its own
lexer and parser, ``Grammar.lark``) and the fast path cosleec parses with (the scanner of
lexer.py feeding the driver of lalr.py). tests/unit/lang/test_parser_crosscheck.py holds
them equal; benchmarks/parse_corpus.py measures the second against the first.

The DSL (TK and LEGOS dialects) and the paper notation are told apart per file: a file
with ``def_start`` or ``rule_start`` is DSL, any other file that contains ``when`` is the
paper notation.

May import: lark (public API), the other lang modules below the front end.
"""

from __future__ import annotations

import bisect
import difflib
import itertools
import re
from dataclasses import dataclass
from importlib import resources
from typing import Any

from lark import Lark

from cosleec.bulk import paused_gc
from cosleec.lang import ast as A
from cosleec.lang.diagnostics import DiagnosticSink
from cosleec.lang.lalr import END, CompiledLALR, SyntaxProblem, read_lark_tables
from cosleec.lang.lexer import BAD_CHAR, ContextualKeywords, Lexicon, Token
from cosleec.lang.mistakes import natural_mistake
from cosleec.lang.paper import PaperToAst
from cosleec.lang.transformer import Block, ToAst


@dataclass(frozen=True)
class Grammar:
    """One grammar of ``grammar/``, built once: use :data:`SLEEC` and :data:`PAPER`.

    ``lark`` is plain Lark -- ``Lark(..., parser="lalr", lexer="basic", transformer=...)``
    with the lexicon's post-lexer for relation keywords -- whose ``parse`` is the reference
    reading of the grammar; :meth:`parse` is the fast path the front end uses.
    """

    name: str
    lark: Lark
    lexicon: Lexicon
    driver: CompiledLALR
    display: dict[str, str]  # terminal -> how messages name it
    rel_ops: frozenset[str]  # the relational operators (the `rel_op` rule)

    @classmethod
    def load(cls, name: str, transformer: ToAst, contextual_block: str | None = None) -> Grammar:
        """Build ``grammar/<name>.lark``; the keywords used only inside ``contextual_block``
        are reserved only there (docs/reference/sleec-language.md §3)."""
        text = resources.files("cosleec.lang").joinpath(f"grammar/{name}.lark").read_text("utf-8")
        postlex = ContextualKeywords()
        lark = Lark(
            text,
            parser="lalr",
            lexer="basic",
            postlex=postlex,
            maybe_placeholders=True,
            transformer=transformer,
        )
        tables = read_lark_tables(lark)
        lexicon = Lexicon(lark.terminals, lark.lexer_conf.ignore, tables.productions(), contextual_block)
        postlex.lexicon = lexicon
        display = {END: "end of file", "NAME": "a name", "INT": "a number", "DECIMAL": "a number"}
        for term in lark.terminals:
            if term.pattern.type == "str":
                display[term.name] = f"`{term.pattern.value}`"
        rel_ops = frozenset(
            display[sym].strip("`") for r in tables.rules if r.origin == "rel_op" for sym in r.symbols
        )
        return cls(name, lark, lexicon, CompiledLALR(tables, transformer=transformer), display, rel_ops)

    def parse(self, text: str, problems: list[SyntaxProblem]) -> Any:
        """The transformer's value for ``text``, or None with the syntax errors in ``problems``."""
        return self.driver.parse_text(self.lexicon, text, problems)


SLEEC = Grammar.load("sleec", ToAst(), contextual_block="relation_block")
PAPER = Grammar.load("paper", PaperToAst())

KEYWORDS = frozenset(SLEEC.lexicon.keywords)
"""The DSL's reserved words (docs/reference/sleec-language.md §3), read from ``grammar/sleec.lark``."""
CONTEXTUAL_KEYWORDS = frozenset(SLEEC.lexicon.contextual)
"""The DSL's words reserved only inside a relation block, read from ``grammar/sleec.lark``."""
PAPER_KEYWORDS = frozenset(PAPER.lexicon.keywords)
"""The paper notation's keywords, lower case (they are case-insensitive), read from ``grammar/paper.lark``."""

_DSL_MARK = re.compile(r"\b(?:def_start|rule_start)\b")
_PAPER_MARK = re.compile(r"(?i)\bwhen\b")
_COMMENT_OR_MARK = re.compile(f"(?:{SLEEC.lexicon.comment_pattern})|({_DSL_MARK.pattern})")
"""A comment (skipped whole), or a DSL mark outside one (group 1): read left to right, the
comments it finds are the scanner's, since no SLEEC token holds a `/` (a comment's first
character: every `/` outside a comment is where a token or layout starts)."""


def looks_like_paper(text: str) -> bool:
    """Is ``text`` in the paper notation (no ``def_start``/``rule_start``, but a ``when``)?

    Words in comments do not count: a paper-notation file may keep an old rule block
    commented out.
    """
    mark = _DSL_MARK.search(text)
    if mark is not None and ("//" in text[: mark.start()] or "/*" in text[: mark.start()]):
        # one pass in C over the text, comments skipped (tests/unit/lang/test_fast_parse.py
        # holds it to the scanner's comments)
        mark = next((m for m in _COMMENT_OR_MARK.finditer(text) if m.group(1)), None)
    return mark is None and _PAPER_MARK.search(text) is not None


def parse_blocks(text: str, sink: DiagnosticSink) -> list[Block] | None:
    """Parse DSL text into its blocks; syntax errors go to ``sink``."""
    if text.lstrip().startswith("{\\rtf"):  # one clear error, not one per RTF control word
        sink.error(
            "rtf",
            "this file is RTF, not plain text",
            A.Span(1, 1, 1, 6),
            hint="save it as plain text (UTF-8)",
        )
        return None
    with paused_gc():  # bulk construction (see cosleec.bulk)
        blocks: list[Block] | None = _parse(SLEEC, text, sink)
    return blocks


def parse_paper_rules(text: str, sink: DiagnosticSink) -> list[A.Rule] | None:
    """Parse the paper notation into rules; syntax errors go to ``sink``."""
    with paused_gc():  # bulk construction (see cosleec.bulk)
        rules: list[A.Rule] | None = _parse(PAPER, text, sink)
    return rules


def _parse(g: Grammar, text: str, sink: DiagnosticSink) -> Any:
    problems: list[SyntaxProblem] = []
    result = g.parse(text, problems)
    parens = _Parens(g, text) if problems else None
    for p in problems:
        _report(p, g, text, sink, parens)
    return None if problems else result


_ORDER: tuple[A.BlockKind, ...] = ("def", "rule", "concern", "purpose", "relation")
"""The blocks of standard SLEEC, in the order a file has them."""


def assemble(blocks: list[Block], path: str, sink: DiagnosticSink) -> A.Specification:
    """Blocks -> Specification, checking that each block appears once and in order.

    The priority block (cosleec's extension, docs/reference/sleec-language.md §13.4) stands
    outside the standard order: anywhere after the rule block, whose rules it names. The
    semantics block (§7.4) names nothing, and may stand anywhere.
    """
    seen: dict[str, A.Span] = {}
    parts: dict[str, list[Any]] = {k: [] for k in (*_ORDER, "priority", "semantics")}
    last_rank = -1
    marks = []
    first_rule = next((i for i, b in enumerate(blocks) if b.kind == "rule"), len(blocks))
    for i, b in enumerate(blocks):
        marks.append(A.BlockMark(b.kind, empty=not b.items, span=b.span))
        if b.kind in seen:
            sink.error(
                "duplicate-block",
                f"a second `{b.kind}_start` block; a file has at most one of each",
                b.span,
                related=(("the first one is here", seen[b.kind]),),
            )
        else:
            seen[b.kind] = b.span
        if b.kind == "semantics":
            parts["semantics"].extend(b.items)
            continue
        if b.kind == "priority":
            if i < first_rule:
                sink.error(
                    "block-order",
                    "the `priority_start` block is out of order; it names rules, so it comes after "
                    "the rule block",
                    b.span,
                )
            parts["priority"].extend(b.items)
            continue
        rank = _ORDER.index(b.kind)
        if rank < last_rank:
            sink.error(
                "block-order",
                f"the `{b.kind}_start` block is out of order; blocks come in the order "
                "def, rule, concern, purpose, relation",
                b.span,
            )
        last_rank = max(last_rank, rank)
        parts[b.kind].extend(b.items)
    if "rule" not in seen:
        sink.error("no-rule-block", "no rule block: a SLEEC file needs `rule_start ... rule_end`")
    return A.Specification(
        definitions=tuple(parts["def"]),
        rules=tuple(parts["rule"]),
        concerns=tuple(parts["concern"]),
        purposes=tuple(parts["purpose"]),
        relations=tuple(parts["relation"]),
        priorities=tuple(parts["priority"]),
        semantics=tuple(parts["semantics"]),
        path=path,
        blocks=tuple(marks),
    )


# ------------------------------------------------------------------ syntax messages


def _report(
    p: SyntaxProblem, g: Grammar, text: str, sink: DiagnosticSink, parens: _Parens | None = None
) -> None:
    tok = p.token
    ttype, value = tok.type, tok.value
    span = A.Span(tok.line, tok.column, tok.line, tok.column + max(len(value), 1))
    opened = parens.unclosed(p) if parens is not None else None
    if opened is not None:
        where = "end of file" if ttype == END else f"`{value}`"
        sink.error(
            "unclosed-paren",
            "`(` is never closed",
            A.Span(opened.line, opened.column, opened.line, opened.column + 1),
            related=((f"the parser reached {where} with it still open", span),),
            hint="add the `)` where the parenthesised expression ends",
        )
        return
    expected = sorted({g.display.get(t, t) for t in p.expected if t != BAD_CHAR})
    expected_values = {g.display.get(t, t).strip("`") for t in p.expected}
    if expected_values >= _UNITS and ttype not in ("NAME", BAD_CHAR):
        unit_message, unit_hint, limit = _missing_unit(tok, text)
        sink.error("missing-unit", unit_message, limit or span, hint=unit_hint)
        return
    if parens is not None:
        before, after = parens.around(tok)
        mistake = natural_mistake(tok, before, after, expected_values, paper=g.name == "paper")
        if mistake is not None:
            sink.error(mistake.code, mistake.message, mistake.span, hint=mistake.hint)
            return
    special = _special_message(g, tok, p.expected, expected_values, text)
    if special is not None:
        code, message, hint = special
        sink.error(code, message, span, hint=hint)
        return
    shown = "end of file" if ttype == END else f"`{value}`"
    if len(expected) > 8:
        expected = [*[e for e in expected if e.startswith("`")][:7], "..."]
    exp = ", ".join(expected) if expected else "nothing more"
    hint = None
    if ttype == "NAME":
        kws = [g.display[t].strip("`") for t in p.expected if g.display.get(t, "").startswith("`")]
        close = difflib.get_close_matches(value, [k for k in kws if k.isidentifier()], n=1, cutoff=0.6)
        if close:
            hint = f"did you mean `{close[0]}`?"
    elif ttype != END and g.lexicon.reserved(value) and "NAME" in p.expected:
        hint = f"`{value}` is a reserved keyword and cannot be used as a name"
    sink.error("syntax", f"unexpected {shown}; expected {exp}", span, hint=hint)


_CONDITION_WORDS = frozenset({"and", "or", "not", "true", "false"})
"""The keywords that may stand inside parentheses (of a condition)."""


class _Parens:
    """Which `(` is left open where the parser met a problem, and the tokens around a problem
    (:meth:`around`): asked about a file's problems in order, it reads the file's tokens once
    in all, and only for a file with a syntax error."""

    def __init__(self, g: Grammar, text: str) -> None:
        self.g = g
        self.text = text
        self.tokens: list[Token] | None = None  # scanned when first needed
        self.at = 0  # the tokens before this one have been read into `open`
        self.open: list[Token] = []

    def scanned(self) -> list[Token]:
        """The file's tokens, scanned when first asked for."""
        if self.tokens is None:
            self.tokens = self.g.lexicon.tokens(self.text)
        return self.tokens

    def around(self, tok: Token) -> tuple[list[Token], Token | None]:
        """Up to four tokens before ``tok`` (nearest last) and the one after it."""
        tokens = self.scanned()
        k = (
            bisect.bisect_left(tokens, tok.start_pos, key=lambda t: t.start_pos)
            if tok.type != END
            else len(tokens)
        )
        return tokens[max(0, k - 4) : k], tokens[k + 1] if k + 1 < len(tokens) else None

    def unclosed(self, p: SyntaxProblem) -> Token | None:
        """The `(` left open where the parser met ``p``'s token, if one is and nothing closes
        it before the text goes on with what cannot be inside parentheses (`then`, `unless`,
        the next rule's `when`, the end): the mistake is that `(`, not where it showed."""
        g = self.g
        if not any(g.display.get(t) == "`)`" for t in p.expected):
            return None
        tokens = self.scanned()
        end = p.token.type == END
        while self.at < len(tokens) and (end or tokens[self.at].start_pos < p.token.start_pos):
            t = tokens[self.at]
            if t.value == "(":
                self.open.append(t)
            elif t.value == ")" and self.open:
                self.open.pop()
            self.at += 1
        if not self.open:
            return None
        depth = 0
        for t in itertools.islice(tokens, self.at, None):
            if t.value == "(":
                depth += 1
            elif t.value == ")":
                if depth == 0:
                    return None  # closed after all: some other mistake inside
                depth -= 1
            elif g.lexicon.reserved(t.value) and t.value.lower() not in _CONDITION_WORDS:
                break
        return self.open[-1]


def _special_message(
    g: Grammar, tok: Token, expected: frozenset[str], values: set[str], text: str
) -> tuple[str, str, str | None] | None:
    """Messages for the mistakes real files make (docs/reference/sleec-language.md §11 item 17)."""
    ttype, value = tok.type, tok.value
    if tok.start_pos == 0 and text.lstrip().startswith("{\\rtf"):
        return ("rtf", "this file is RTF, not plain text", "save it as plain text (UTF-8)")
    if ttype == BAD_CHAR:
        if value == "/*":
            return ("unterminated-comment", "unterminated comment: `/*` has no matching `*/`", None)
        if value == "/":
            return ("division", "`/` is not a SLEEC operator: there is no division (only + - *)", None)
        if value.isalpha():
            return (
                "non-ascii",
                f"`{value}` is not allowed in a name: identifiers use ASCII letters, digits and `_`",
                None,
            )
        if value == "," and g.name == "paper":
            return (
                "paper-comma",
                "`,` has no place in the paper notation",
                "join responses with `AND`, and write an exception as `UNLESS c IN WHICH CASE B`, "
                "without a comma",
            )
        return ("bad-char", f"unexpected character `{value}`", None)
    if value == "or" and "then" in values and "and" in values and "or" not in values:
        return (
            "trigger-or",
            "a rule is triggered by exactly one event; `or` between trigger events is not SLEEC",
            "write one rule per trigger event, or move the alternative into the condition",
        )
    if value == "not" and values == {"a name"}:
        return ("negated-trigger", "a trigger is a single event and cannot be negated", None)
    # where only a name may come (a priority block's `A > > B`), a `>` is no comparison
    if value in g.rel_ops and not (values & g.rel_ops) and not values <= {"a name", "priority_end"}:
        return (
            "comparison-chain",
            f"a comparison cannot be chained (`a < b {value} c`)",
            "combine two comparisons with `and`",
        )
    if "until" in values and "for" in values:
        return (
            "relation-end",
            f"unexpected {'end of file' if ttype == END else f'`{value}`'}: a relation `when E then p` "
            "needs `until F` (or `for T`) after its condition",
            "LEGOS-SLEEC's grammar makes `until` optional, but its analyser stops ('unsupported "
            "yet') on a relation without it, so the form has no meaning to follow",
        )
    if value == "{" and values == {"("}:
        return ("scale-braces", "scale literals are listed in parentheses: `scale(low, medium, high)`", None)
    if g.name == "paper":
        return _paper_message(tok, values, text)
    return None


_UNITS = frozenset({"seconds", "minutes", "hours", "days"})
_WITHIN = re.compile(r"(?i)\b(within)[ \t]+([0-9][0-9. \t+*-]*?)\s*\Z")


def _missing_unit(tok: Token, text: str) -> tuple[str, str, A.Span | None]:
    """`within 5` and no unit (where the parser expects a unit, and meets no name): the
    message quotes the limit as written and points at it, when it is a plain number."""
    m = _WITHIN.search(text, 0, len(text) if tok.type == END else tok.start_pos)
    if m is None or len(m.group(2)) > 20:
        return (
            "a time limit needs a unit after its number",
            "write the unit after the number: `within 5 seconds` (or minutes, hours, days)",
            None,
        )
    written = f"{m.group(1)} {m.group(2)}"
    unit = "SECONDS" if m.group(1).isupper() else "seconds"
    line = text.count("\n", 0, m.start()) + 1
    col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
    return (
        f"`{written}` has no time unit",
        f"write the unit: `{written} {unit}` (or minutes, hours, days)",
        A.Span(line, col, line, col + m.end(2) - m.start()),
    )


def _paper_message(tok: Token, values: set[str], text: str) -> tuple[str, str, str | None] | None:
    """The DSL's forms written in the paper notation, which says them otherwise."""
    value = tok.value
    if value.lower() == "then" and "in" in values:
        upper = value.isupper()
        in_which_case = "IN WHICH CASE" if upper else "in which case"
        line = text.splitlines()[tok.line - 1] if tok.line <= len(text.splitlines()) else ""
        col = tok.column - 1
        fixed = (line[:col] + in_which_case + line[col + len(value) :]).strip()
        example = f": `{fixed}`" if line[col : col + len(value)] == value and len(fixed) <= 100 else ""
        return (
            "paper-unless-then",
            f"in the paper notation an exception's response follows `{in_which_case}`, not "
            f"`{value}` (`unless c then B` is the DSL's form)",
            f"write `{in_which_case}` for `{value}`{example}",
        )
    return None
