"""Checking a text that changes a little at a time (an editor's buffer): only what changed is
parsed again.

Parsing is most of what :func:`~cosleec.lang.analyse` costs (about two thirds on a
3,000-rule file), and an edit touches one rule. :class:`IncrementalAnalyser` cuts the rule
block into pieces at the lines where a rule starts (``Name when`` at the start of a line,
outside comments), parses each piece on its own -- placed at its own line, so that every
span is the one a whole parse gives -- and remembers the pieces: the next text parses only
the pieces whose text or first line changed. Everything after parsing (assembling the
blocks, the dialect facts, the checker) runs on the whole file as :func:`analyse` runs it,
through the same function (``frontend.analyse_with``).

Why the pieces read as the whole does: the grammar has no separator between rules, and a
rule ends where the next ``Name when`` begins; the rule block's pieces are parsed between a
``rule_start`` and a ``rule_end`` of their own, the head (what comes before the first
piece) with a ``rule_end`` after it, the last piece with a ``rule_start`` before it. When
any of them has a syntax error, or the text is not cut cleanly (no rule block, an
unterminated comment, the paper notation), the whole text is parsed as :func:`analyse`
parses it, so errors are reported exactly as ``cosleec check`` reports them.
tests/unit/lang/test_incremental.py holds the result equal to :func:`analyse`'s --
diagnostics, spans and specification -- on the corpus and on edits of it.

A text whose lines move (a line added or removed above a rule) parses the rules below the
edit again: their spans changed.
"""

from __future__ import annotations

import bisect
import itertools
import re
from dataclasses import dataclass

from cosleec.lang.checker import Options
from cosleec.lang.diagnostics import DiagnosticSink
from cosleec.lang.frontend import CheckResult, analyse_with
from cosleec.lang.parser import parse_blocks
from cosleec.lang.transformer import Block

_COMMENT = re.compile(r"//[^\n]*|/\*[^*]*\*+(?:[^/*][^*]*\*+)*/|/\*")
"""Comments as the scanner reads them (no token contains `/`, so the first `//` or `/*` not in
a comment opens one); a bare ``/*`` is an unterminated comment."""
_RULE_LINE = re.compile(r"^[ \t\f\r]*\^?[A-Za-z_][A-Za-z0-9_]*[ \t\f\r]+when(?![A-Za-z0-9_])", re.M)
_RULE_START = re.compile(r"(?<![A-Za-z0-9_^])rule_start(?![A-Za-z0-9_])")
_RULE_END = re.compile(r"(?<![A-Za-z0-9_^])rule_end(?![A-Za-z0-9_])")

PIECE_RULES = 8
"""Rules per piece, on average: fewer pieces cost less to parse from scratch (each piece is a
parse of its own), smaller ones less after an edit."""

_Key = tuple[str, int, str]  # (head | middle | last, first line, text)


@dataclass(frozen=True, slots=True)
class Reuse:
    """What the last :meth:`IncrementalAnalyser.analyse` did: how many pieces the text was cut
    into and how many of them it parsed (the others were remembered); ``whole`` when it
    parsed the whole text instead (see the module docstring for when)."""

    pieces: int
    parsed: int
    whole: bool


class IncrementalAnalyser:
    """:func:`~cosleec.lang.analyse` for one document that is checked again after each edit
    (the language server's): the same result, parsing only the rules that changed.

    Give it the options :func:`analyse` takes, once; call :meth:`analyse` with each new
    text. One instance serves one document, from one thread at a time.
    """

    def __init__(
        self,
        path: str = "<string>",
        *,
        dialect: str = "auto",
        strict: bool = False,
        infer_defs: bool = False,
        options: Options | None = None,
        legos_compat: bool = False,
    ) -> None:
        self.path = path
        self._dialect, self._strict, self._infer_defs = dialect, strict, infer_defs
        self._options, self._legos_compat = options, legos_compat
        self._pieces: dict[_Key, list[Block]] = {}
        self.reuse = Reuse(pieces=0, parsed=0, whole=True)

    def analyse(self, text: str) -> CheckResult:
        """Parse and check ``text`` as :func:`~cosleec.lang.analyse` does (the same result)."""
        self.reuse = Reuse(pieces=0, parsed=0, whole=True)  # until the pieces are read
        return analyse_with(
            self._parse,
            text,
            self.path,
            dialect=self._dialect,
            strict=self._strict,
            infer_defs=self._infer_defs,
            options=self._options,
            legos_compat=self._legos_compat,
        )

    def _parse(self, text: str, sink: DiagnosticSink) -> list[Block] | None:
        """``parse_blocks(text, sink)``, from the pieces remembered where it can."""
        keys = _cut(text)
        if keys is None:
            self._pieces = {}
            return parse_blocks(text, sink)
        old, new = self._pieces, {}
        parsed = 0
        for key in keys:
            blocks = old.get(key)
            if blocks is None:
                parsed += 1
                blocks = _parse_piece(key)
                if blocks is None:  # a syntax error: the whole parse reports it as check does
                    self._pieces = {}
                    return parse_blocks(text, sink)
            new[key] = blocks
        self._pieces = new
        self.reuse = Reuse(pieces=len(keys), parsed=parsed, whole=False)
        head, *middle, last = (new[k] for k in keys)
        rules = [*head[-1].items]
        for blocks in middle:
            rules += blocks[0].items
        rules += last[0].items
        return [*head[:-1], Block("rule", head[-1].span, rules), *last[1:]]


def _cut(text: str) -> list[_Key] | None:
    """The pieces of ``text``: the head (up to the first line where a rule starts), one piece
    per rule line of the rule block, the last running to the end; None when the text cannot
    be cut (see the module docstring)."""
    comments: list[int] = []  # start, end, start, end, ...: the offsets the comments cover
    for m in _COMMENT.finditer(text):
        if m.end() - m.start() == 2 and m.group() == "/*":
            return None  # unterminated: the scanner stops there
        comments += (m.start(), m.end())

    def commented(at: int) -> bool:
        return bisect.bisect_right(comments, at) % 2 == 1

    start = next((m for m in _RULE_START.finditer(text) if not commented(m.start())), None)
    if start is None:
        return None
    end = next((m for m in _RULE_END.finditer(text, start.end()) if not commented(m.start())), None)
    stop = end.start() if end is not None else len(text)
    cuts: list[int] = []
    for m in _RULE_LINE.finditer(text, start.end(), stop):
        at = m.start()
        # a line's start (not the search's), outside comments; after the first, a rule line
        # whose text hashes to 0 mod PIECE_RULES: pieces of that many rules on average, cut
        # where the text says, so that an edit moves no other cut
        if text[at - 1] == "\n" and not commented(at) and (not cuts or hash(m.group()) % PIECE_RULES == 0):
            cuts.append(at)
    if not cuts:
        return None
    keys: list[_Key] = [("head", 1, text[: cuts[0]])]
    line = 1 + text.count("\n", 0, cuts[0])
    for a, b in itertools.pairwise(cuts):
        keys.append(("middle", line, text[a:b]))
        line += text.count("\n", a, b)
    keys.append(("last", line, text[cuts[-1] :]))
    return keys


def _parse_piece(key: _Key) -> list[Block] | None:
    """The blocks of one piece, parsed at its own line; None on any syntax error."""
    kind, line, piece = key
    if kind == "head":
        synthetic = piece + "rule_end"
    else:  # the piece starts a line (line >= 2: the head holds `rule_start`)
        synthetic = "\n" * (line - 2) + "rule_start\n" + piece + ("rule_end" if kind == "middle" else "")
    sink = DiagnosticSink("<piece>")
    blocks = parse_blocks(synthetic, sink)
    if blocks is None or sink.items:
        return None
    if kind == "head":
        return blocks if blocks and blocks[-1].kind == "rule" else None
    if not blocks or blocks[0].kind != "rule" or (kind == "middle" and len(blocks) != 1):
        return None
    return blocks


__all__ = ["IncrementalAnalyser", "Reuse"]
