"""A fast scanner that feeds Lark's LALR parser.

Why not Lark's own lexer: it spends about 3.6 µs per token here (a Python-level Token,
line bookkeeping and keyword callbacks per token), which alone caps parsing well below
the project's 20,000 rules/s target. This scanner uses one compiled regular expression
and a keyword table, both *derived from the grammar's own terminal definitions*, so the
``.lark`` file stays the single source of truth for the language.

Keyword reservation follows sleec-language.md §3: the ordinary keywords are reserved
everywhere; the relation keywords (``witness``, ``imply``, ``until``, ...) only between
``relation_start`` and ``relation_end``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

from lark.lexer import Lexer, PatternStr

# Reserved only inside a relation block (§3 "contextual keywords"), plus the two
# non-standard sleecvalDef relation words that the grammar parses only to reject them.
CONTEXTUAL_KEYWORDS = frozenset(
    {
        "witness",
        "mutualExclusive",
        "equal",
        "happenBefore",
        "isContradictoryWith",
        "imply",
        "iff",
        "opposite",
        "invariant",
        "causation",
        "includes",
        "forbid",
        "until",
        "for",
        "conflict",
        "effect",
    }
)

# Reserved everywhere (sleec-language.md §3); the checker rejects them as names.
KEYWORDS = frozenset(
    [
        "def_start",
        "def_end",
        "rule_start",
        "rule_end",
        "concern_start",
        "concern_end",
        "purpose_start",
        "purpose_end",
        "relation_start",
        "relation_end",
        "event",
        "measure",
        "constant",
        "boolean",
        "numeric",
        "scale",
        "when",
        "then",
        "and",
        "or",
        "not",
        "within",
        "otherwise",
        "unless",
        "else",
        "eventually",
        "exists",
        "while",
        "meanwhile",
        "true",
        "false",
        "seconds",
        "minutes",
        "hours",
        "days",
    ]
)

BAD_CHAR = "$BADCHAR"

_IDENT = re.compile(r"\^?[A-Za-z_][A-Za-z0-9_]*\Z")

# One findall over the whole text (it runs in C): each match is the layout (whitespace and
# comments) before a token, then the token in exactly one group. BAD catches any other
# character so that nothing is skipped silently; END lets trailing layout match.
_SCAN = re.compile(
    r"((?:[ \t\f\r\n\ufeff]+|//[^\n]*|/\*[^*]*\*+(?:[^/*][^*]*\*+)*/)*)"
    r"(?:(\^?[A-Za-z_][A-Za-z0-9_]*)"
    r"|(->|<=|>=|<>|[{}()\[\],:=<>+\-*])"
    r"|([0-9]+(?:\.[0-9]+)?)"
    r"|(\Z)"
    r"|([\s\S]))"
)

# A token is a plain tuple (type, value, start_pos, line, column): building it costs a
# fraction of a class instance, and lexing is on the hot path of parsing.
Token = tuple[str, str, int, int, int]


class SleecLexer(Lexer):
    """Scans SLEEC text into the grammar's terminals (see module docstring)."""

    def __init__(self, lexer_conf: Any) -> None:
        self.keywords: dict[str, str] = {}
        self.contextual: dict[str, str] = {}
        self.punct: dict[str, str] = {}
        # The paper notation's keywords are case-insensitive ("when"i): look names up lowered.
        self.fold_case = False
        for term in lexer_conf.terminals:
            pat = term.pattern
            if not isinstance(pat, PatternStr):
                continue
            if _IDENT.match(pat.value):
                table = self.contextual if pat.value in CONTEXTUAL_KEYWORDS else self.keywords
                if "i" in pat.flags:
                    self.fold_case = True
                    table[pat.value.lower()] = term.name
                else:
                    table[pat.value] = term.name
            else:
                self.punct[pat.value] = term.name
        self.relation_start = self.keywords.get("relation_start", "RELATION_START")
        self.relation_end = self.keywords.get("relation_end", "RELATION_END")

    def lex(self, data: Any) -> Iterator[Any]:  # type: ignore[override]
        return iter(self.tokens(data if isinstance(data, str) else data.text))

    def tokens(self, text: str) -> list[Token]:
        keywords, contextual, punct = self.keywords, self.contextual, self.punct
        rel_start, rel_end = self.relation_start, self.relation_end
        out: list[Token] = []
        append = out.append
        pos, line, line_start = 0, 1, 0
        in_relations = False
        fold = self.fold_case
        for layout, name, p, num, _end, bad in _SCAN.findall(text):
            if layout:
                pos += len(layout)
                if "\n" in layout:
                    line += layout.count("\n")
                    line_start = pos - (len(layout) - layout.rindex("\n") - 1)
            if name:
                t = keywords.get(name.lower() if fold else name)
                if t is None:
                    t = contextual.get(name, "NAME") if in_relations else "NAME"
                elif t == rel_start:
                    in_relations = True
                elif t == rel_end:
                    in_relations = False
                append((t, name, pos, line, pos - line_start + 1))
                pos += len(name)
            elif p:
                append((punct.get(p, BAD_CHAR), p, pos, line, pos - line_start + 1))
                pos += len(p)
            elif num:
                append(("DECIMAL" if "." in num else "INT", num, pos, line, pos - line_start + 1))
                pos += len(num)
            elif bad:
                if bad == "/" and text.startswith("/*", pos):
                    bad = "/*"  # an unterminated block comment: report it once, then stop
                    append((BAD_CHAR, bad, pos, line, pos - line_start + 1))
                    break
                append((BAD_CHAR, bad, pos, line, pos - line_start + 1))
                pos += 1
                if bad == "\n":
                    line += 1
                    line_start = pos
        return out
