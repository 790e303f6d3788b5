"""Between cosleec's places and the editor's: spans (1-based line and column, in characters,
lines ended by ``\\n``) and LSP positions (0-based line and character, in the units the
client and server agreed on: UTF-16 by default, UTF-8 or UTF-32 when asked).

Why its own line table: the scanner counts only ``\\n`` as a line break, LSP counts ``\\r\\n``,
``\\r`` and ``\\n``, and a character outside the Basic Multilingual Plane is one column to us
and two UTF-16 units to VS Code. Everything goes through offsets into the text.
"""

from __future__ import annotations

import bisect
import re

from lsprotocol import types as T

from cosleec.lang import ast as A

_LSP_BREAK = re.compile(r"\r\n|\r|\n")


class LineIndex:
    """The lines of one text, both ways; build one per text (it is immutable).

    ``encoding`` is the position encoding agreed at initialisation (``utf-16``, ``utf-8``
    or ``utf-32``).
    """

    def __init__(self, text: str, encoding: str = "utf-16") -> None:
        self.text = text
        self.encoding = encoding
        self._ours = [0, *(m.end() for m in re.finditer("\n", text))]
        if "\r" in text.replace("\r\n", ""):
            self._lsp = [0, *(m.end() for m in _LSP_BREAK.finditer(text))]
        else:  # the usual case: the same lines (a `\r` before `\n` ends no line of its own)
            self._lsp = self._ours

    # ---------------------------------------------------------------- ours -> offsets
    def offset(self, line: int, col: int) -> int:
        """The offset of 1-based ``line`` and ``col`` (a span's start or end), clamped to the text."""
        if line < 1:
            return 0
        if line > len(self._ours):
            return len(self.text)
        return min(self._ours[line - 1] + max(col - 1, 0), len(self.text))

    def span_offsets(self, span: A.Span) -> tuple[int, int]:
        """The offsets a span covers, start and end (exclusive)."""
        return self.offset(span.line, span.col), self.offset(span.end_line, span.end_col)

    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based line and column of an offset: where a span would say it is."""
        line = bisect.bisect_right(self._ours, offset)
        return line, offset - self._ours[line - 1] + 1

    # ---------------------------------------------------------------- offsets <-> LSP
    def position(self, offset: int) -> T.Position:
        """The LSP position of an offset."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect.bisect_right(self._lsp, offset) - 1
        return T.Position(line=line, character=self._units(self.text[self._lsp[line] : offset]))

    def range(self, start: int, end: int) -> T.Range:
        """The LSP range between two offsets."""
        return T.Range(start=self.position(start), end=self.position(max(start, end)))

    def span_range(self, span: A.Span) -> T.Range:
        """The LSP range of a span; a file-wide finding (no span) is placed at the start."""
        if not span.line:
            return self.range(0, 0)
        return self.range(*self.span_offsets(span))

    def to_offset(self, pos: T.Position) -> int:
        """The offset of an LSP position (a position past a line's end is its end)."""
        if pos.line >= len(self._lsp):
            return len(self.text)
        start = self._lsp[pos.line]
        end = self._lsp[pos.line + 1] if pos.line + 1 < len(self._lsp) else len(self.text)
        line = self.text[start:end]
        if line.endswith("\r\n"):
            line = line[:-2]
        elif line.endswith(("\n", "\r")):
            line = line[:-1]
        if self.encoding == "utf-32" or line.isascii():
            return start + min(pos.character, len(line))
        units = 0
        for i, ch in enumerate(line):
            if units >= pos.character:
                return start + i
            units += self._units(ch)
        return start + len(line)

    def _units(self, s: str) -> int:
        if self.encoding == "utf-32" or s.isascii():
            return len(s)
        if self.encoding == "utf-8":
            return len(s.encode("utf-8", "surrogatepass"))
        return len(s.encode("utf-16-le", "surrogatepass")) // 2
