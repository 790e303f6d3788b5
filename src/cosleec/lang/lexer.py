"""The words and marks of SLEEC, read from a grammar's terminals, and the fast scanner built on them.

Why a scanner of our own: Lark's lexer spends about 3.6 µs per token (a Python ``Token``
object, line bookkeeping, a keyword callback), which alone caps parsing well below the
project's 20,000 rules/s target. This one runs a single compiled regular expression over
the whole text. Nothing in it is written by hand: the keywords, the punctuation, the token
patterns, the layout (whitespace and comments) and the relation-only keywords all come
from the ``.lark`` grammar, so the grammar stays the single source of truth.

What a lexicon decides, the way Lark's own lexer decides it (the cross-check test,
tests/unit/lang/test_parser_crosscheck.py, holds the two equal):

- terminals are tried in Lark's order (priority, then longest possible match, ...);
- a string terminal that the name pattern matches entirely (``"when"``) is a *keyword*:
  a word scanned as a name becomes that keyword -- case-insensitively for ``"when"i``;
- keyword reservation (docs/reference/sleec-language.md §3): keywords are reserved everywhere, except
  the *contextual* ones, which only the rules inside a relation block use (``witness``,
  ``until``, ...): those are reserved only between ``relation_start`` and ``relation_end``.

May import: lark (public API: ``Lark.terminals``, ``lexer_conf.ignore``, ``PostLex``).
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable, Iterator, Mapping
from typing import Any, NamedTuple

from lark import Token as LarkToken
from lark.lark import PostLex

BAD_CHAR = "$BADCHAR"
"""The type of a character no terminal matches (the parser reports it)."""


class Token(NamedTuple):
    """One token: the attributes the transformer reads, named as on Lark's own ``Token``.

    A named tuple because it is built at C speed, and lexing is on the hot path of parsing;
    the transformer reads ``type``, ``value``, ``line`` and ``column`` and so works on the
    tokens of either lexer.
    """

    type: str
    value: str
    start_pos: int
    line: int
    column: int


class Production(NamedTuple):
    """A grammar rule as the lexicon needs it: its name and the names of its symbols."""

    origin: str
    symbols: tuple[str, ...]


_new = tuple.__new__
_MEMO_LIMIT = 100_000


class Lexicon:
    """The lexical rules of one grammar, and a scanner applying them (see module docstring).

    Build one per grammar from ``Lark.terminals``, the names of the ignored terminals
    (``Lark.lexer_conf.ignore``) and the grammar's rules; ``contextual_block`` names the rule
    whose inner keywords are reserved only inside it. Use :meth:`tokens` to scan text for
    the fast driver, and a :class:`ContextualKeywords` post-lexer to have Lark's own lexer
    apply the same reservation.
    """

    def __init__(
        self,
        terminals: Iterable[Any],
        ignore: Collection[str],
        productions: Iterable[Production],
        contextual_block: str | None = None,
    ) -> None:
        terminals, productions = list(terminals), list(productions)
        terms = [t for t in terminals if t.name not in ignore]
        regexps = [t for t in terms if t.pattern.type == "re"]
        strings = [t for t in terms if t.pattern.type == "str"]
        exact: dict[str, str] = {}  # word -> keyword terminal
        folded: dict[str, str] = {}  # lower-cased word -> case-insensitive keyword terminal
        owner: dict[str, str] = {}  # keyword terminal -> the regexp terminal that scans it
        punct: dict[str, str] = {}
        for s in strings:
            value = s.pattern.value
            for r in regexps:  # as Lark does: the pattern's first match is the whole string
                m = re.match(r.pattern.to_regexp(), value)
                if s.priority == r.priority and m is not None and m.group() == value:
                    if "i" in s.pattern.flags:
                        folded[value.lower()] = s.name
                    else:
                        exact[value] = s.name
                    owner[s.name] = r.name
                    break
            else:
                punct[value] = s.name
        words = {**exact, **folded}
        contextual = _contextual(set(words.values()), productions, contextual_block)
        #: Reserved everywhere (word -> terminal).
        self.keywords: dict[str, str] = {w: t for w, t in words.items() if t not in contextual}
        #: Reserved only inside the contextual block (word -> terminal).
        self.contextual: dict[str, str] = {w: t for w, t in words.items() if t in contextual}
        #: Punctuation (mark -> terminal).
        self.punct = punct
        #: The terminals that open and close the contextual block.
        self.block_marks = _block_marks(contextual_block, productions)
        #: A contextual keyword's terminal -> the terminal it is outside the block (a name).
        self.relaxed = {t: owner[t] for t in self.contextual.values()}
        self._exact, self._folded = exact, folded
        self._owner = owner
        # Lark's own order of trial: priority, then the longest possible match, ...
        order = sorted(
            (t for t in terms if t.name not in owner),
            key=lambda t: (-t.priority, -t.pattern.max_width, -len(t.pattern.value), t.name),
        )
        self._classes: list[tuple[str, re.Pattern[str]]] = [
            (t.name, re.compile(t.pattern.to_regexp())) for t in order
        ]
        layout = layout_pattern([t.pattern.to_regexp() for t in terminals if t.name in ignore])
        tokens = "|".join(t.pattern.to_regexp() for t in order)
        # One findall over the whole text (it runs in C): each match is the layout before a
        # token, then the token; at the end the token is empty; any other character is a
        # token of its own (a BAD_CHAR), so nothing is skipped silently. Layout is tried
        # before tokens, where Lark tries all in its one order: the same, as long as no
        # ignored terminal starts like a token (`//` and `/*` comments, and no `/` mark).
        self._scan = re.compile(f"({layout})({tokens}|\\Z|[\\s\\S])")
        #: ``findall`` of the scanning pattern: ``(layout, token)`` pairs, the last token
        #: empty (what :meth:`tokens` reads; the fast driver reads it directly, lalr.py).
        self.pairs = self._scan.findall
        comments = "|".join(
            t.pattern.to_regexp() for t in terminals if t.name in ignore and "COMMENT" in t.name
        )
        self._comment = re.compile(comments) if comments else None
        #: The ignored terminals named ``*COMMENT``, as one regular expression (``(?!)``, which
        #: matches nothing, when there are none).
        self.comment_pattern = comments or "(?!)"
        self._memo: tuple[dict[str, str], dict[str, str]] = ({}, {})

    def reserved(self, word: str) -> bool:
        """Is ``word`` a keyword everywhere (so that it can never be a name unescaped)?"""
        return (word in self._exact or word.lower() in self._folded) and word not in self.contextual

    def comments(self, text: str) -> list[tuple[int, str]]:
        """The comments of ``text`` as ``(offset, text)``, in order: what the scanner skips as
        layout and a formatter must keep (the ignored terminals named ``*COMMENT``).

        Scans as :meth:`tokens` does, so a ``//`` inside a block comment is no comment of
        its own and an unterminated ``/*`` is none at all.
        """
        found: list[tuple[int, str]] = []
        if self._comment is None:
            return found
        pos = 0
        for layout, tok in self._scan.findall(text):
            if layout:
                if "/" in layout:  # every comment starts with one; most layout is spaces
                    for m in self._comment.finditer(layout):
                        found.append((pos + m.start(), m.group()))
                pos += len(layout)
            if not tok:
                break
            pos += len(tok)
        return found

    # ------------------------------------------------------------------ the fast scanner
    def memos(self) -> tuple[dict[str, str], dict[str, str]]:
        """Token text -> type, learnt as scans go, outside the contextual block and inside
        it: most tokens are one dictionary look-up (a miss: :meth:`classify`, then store).

        Shared by every scan: a race only computes an entry twice. Bounded, for long-lived
        processes: past the limit, they are emptied when a scan asks for them."""
        outside, inside = self._memo
        if len(outside) + len(inside) > _MEMO_LIMIT:
            outside.clear()
            inside.clear()
        return outside, inside

    def classify(self, text: str, inside: bool) -> str:
        """The type of one scanned token's text, inside a contextual block or not."""
        for name, pattern in self._classes:  # the terminal that matched: the first in order
            if pattern.fullmatch(text):
                kw = self._exact.get(text) or self._folded.get(text.lower())
                if kw is not None and self._owner[kw] == name and (inside or text not in self.contextual):
                    return kw
                return name
        return BAD_CHAR

    def tokens(self, text: str) -> list[Token]:
        """Scan ``text``; a character no terminal matches becomes a BAD_CHAR token.

        An unterminated ``/*`` comment is one BAD_CHAR token ``/*``, and scanning stops there.
        No token spans lines (the grammars make newlines layout).
        """
        outside, inside = self.memos()
        memo = outside
        classify = self.classify
        start_mark, end_mark = self.block_marks
        special = {start_mark, end_mark, BAD_CHAR}
        out: list[Token] = []
        append, new, token, length = out.append, _new, Token, len  # locals: this loop is hot
        pos, line, line_start = 0, 1, 0
        for layout, tok in self._scan.findall(text):
            if layout:
                pos += length(layout)
                if "\n" in layout:
                    line += layout.count("\n")
                    line_start = pos - (length(layout) - layout.rindex("\n") - 1)
            t = memo.get(tok)
            if t is None:
                if not tok:
                    break  # the end of the text
                t = memo[tok] = classify(tok, memo is inside)
            if t in special:
                if t == start_mark:
                    memo = inside
                elif t == end_mark:
                    memo = outside
                elif tok == "/" and text.startswith("/*", pos):
                    append(new(token, (BAD_CHAR, "/*", pos, line, pos - line_start + 1)))
                    break  # an unterminated block comment: report it once, then stop
            append(new(token, (t, tok, pos, line, pos - line_start + 1)))
            pos += length(tok)
        return out


_CHAR_RUN = re.compile(
    r"\[((?![\^\-])(?:[^\]\\]|\\.)*(?<![\-\\]))\]\+?"  # a class (not negated, no edge `-`), once or a run
    r"|([^\\.^$*+?{}\[\]|()]|\\[^A-Za-z0-9]|\\[tnrfvsSdDwW])\+?"  # one plain or escaped character
)


def layout_pattern(regexps: list[str]) -> str:
    """The regular expression of any run of layout (what the ignored terminals ``regexps``
    match), in a form Python's ``re`` runs quickly.

    Why: ``(?:ws|comment|bom)*``, the plain form, makes ``re`` enter its general repeat for
    every item (each blank run, each BOM): a third of the scan's time. Here the terminals that
    match single characters or runs of them (``/[ \t\n]+/``, ``/\ufeff/``) become one class
    ``W``, and the layout is ``W*(?:(?:comment|...)W*)*``: the same extent of text, as long
    as no other ignored terminal starts with a character of ``W`` (a comment starts with
    ``/``); tests/unit/lang/test_fast_parse.py holds it equal to the plain form.
    """
    chars: list[str] = []
    others: list[str] = []
    for r in regexps:
        m = _CHAR_RUN.fullmatch(r)
        if m is None:
            others.append(r)
        else:
            chars.append(m.group(1) if m.group(1) is not None else m.group(2))
    if not chars:
        return f"(?:{'|'.join(others)})*" if others else ""
    run = f"[{''.join(chars)}]*"
    return f"{run}(?:(?:{'|'.join(others)}){run})*" if others else run


class ContextualKeywords(PostLex):
    """Lark's own lexer reserves every keyword everywhere; SLEEC reserves the relation
    keywords only inside a relation block (docs/reference/sleec-language.md §3). Outside one, this
    post-lexer turns them back into names.

    Give it to ``Lark(..., lexer="basic", postlex=...)``: that is SLEEC as plain Lark reads
    it, the reference the fast driver is held equal to. Lark needs the post-lexer before it
    builds the grammar, the lexicon is read from the built grammar: set ``lexicon`` then.
    """

    always_accept = ()

    def __init__(self, lexicon: Lexicon | None = None) -> None:
        self.lexicon = lexicon

    def process(self, stream: Iterator[LarkToken]) -> Iterator[LarkToken]:
        """Yield ``stream`` with relation keywords outside a relation block retyped as names."""
        relaxed = self.lexicon.relaxed if self.lexicon is not None else {}
        if not relaxed:
            yield from stream
            return
        assert self.lexicon is not None
        start_mark, end_mark = self.lexicon.block_marks
        inside = False
        for tok in stream:
            t = tok.type
            if t == start_mark:
                inside = True
            elif t == end_mark:
                inside = False
            elif not inside and t in relaxed:
                tok = LarkToken.new_borrow_pos(relaxed[t], tok.value, tok)
            yield tok


def _reachable(
    roots: Iterable[str], rules: Mapping[str, list[tuple[str, ...]]], stop: Collection[str]
) -> set[str]:
    """Every symbol reachable from ``roots`` through the rules, not expanding ``stop``."""
    seen: set[str] = set()
    todo = list(roots)
    while todo:
        sym = todo.pop()
        if sym in seen:
            continue
        seen.add(sym)
        if sym not in stop:
            for expansion in rules.get(sym, ()):
                todo.extend(expansion)
    return seen


def _rules(productions: Iterable[Production]) -> dict[str, list[tuple[str, ...]]]:
    rules: dict[str, list[tuple[str, ...]]] = {}
    for p in productions:
        rules.setdefault(p.origin, []).append(p.symbols)
    return rules


def _contextual(keywords: set[str], productions: Iterable[Production], block: str | None) -> set[str]:
    """The keyword terminals used only inside ``block``: by the rules its body reaches, by no other."""
    if block is None:
        return set()
    rules = _rules(productions)
    body = {sym for expansion in rules.get(block, ()) for sym in expansion if sym in rules}
    outside = _reachable(["start"], rules, stop=body)
    inside = _reachable(body, rules, stop=())
    return {k for k in keywords if k in inside and k not in outside}


def _block_marks(block: str | None, productions: Iterable[Production]) -> tuple[str | None, str | None]:
    """The terminals that open and close ``block`` (the first and last symbol of its rule)."""
    if block is None:
        return None, None
    for expansion in _rules(productions).get(block, ()):
        if len(expansion) >= 2:
            return expansion[0], expansion[-1]
    return None, None
