"""Compiler-style diagnostics: ``path:line:col: error: message`` plus the line and a caret.

Every problem cosleec finds in a rule file becomes a :class:`Diagnostic`; nothing the user
wrote ever surfaces as a Python traceback. :class:`SleecError` is the one exception type
the language front-end raises, and it carries the diagnostics.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping, Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from cosleec.errors import UserError
from cosleec.lang.ast import NO_SPAN, Span

QUOTE_LIMIT = 60
"""How many characters of source text (a name, a unit, a list of literals) a message quotes:
a generated file can hold a name of any length, and a message that repeats it whole makes
the output grow with the product of the two (see :func:`clip`)."""

LINE_WIDTH = 256
"""How many characters of the offending source line :meth:`Diagnostic.render` shows. A
longer line (a generated rule on one line) is cut to a window around the caret, so that
each rendered diagnostic has a bounded size whatever the file. The longest line any
diagnostic of the real corpus quotes is 242 characters: the corpus renders whole."""


def clip(text: str, limit: int = QUOTE_LIMIT) -> str:
    """``text`` cut to at most ``limit`` characters (the cut marked ``...``).

    Use it for every piece of source text a message quotes, so that a message's length does
    not depend on the input's.
    """
    return text if len(text) <= limit else text[: max(limit - 3, 1)] + "..."


class Severity(StrEnum):
    """How serious a :class:`Diagnostic` is; only ``ERROR`` makes a file unusable."""

    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True, slots=True, kw_only=True)
class Diagnostic:
    """One finding, with a stable ``code`` that tests and tools can match on.

    :meth:`to_json` and :meth:`from_json` are its wire format (``cosleec check --json``).
    """

    severity: Severity
    code: str
    message: str
    span: Span = NO_SPAN
    path: str = "<string>"
    hint: str | None = None
    related: tuple[tuple[str, Span], ...] = field(default=())

    @property
    def is_error(self) -> bool:
        """Whether this is an error (not a warning or note): one error makes the file fail."""
        return self.severity is Severity.ERROR

    def header(self) -> str:
        """The first line, ``path:line:col: severity: message`` (``path: ...`` when there is no span)."""
        if self.span.line:
            return f"{self.path}:{self.span.line}:{self.span.col}: {self.severity}: {self.message}"
        return f"{self.path}: {self.severity}: {self.message}"

    def render(self, source: str | None) -> str:
        """The header, then the offending source line with a caret under the span.

        A line longer than :data:`LINE_WIDTH` is shown as a window of that many characters
        around the caret (cuts marked ``...``), so the output stays proportional to the
        number of diagnostics, not to their number times the line's length. Rendering every
        diagnostic of a file splits the source into lines once (:func:`_lines` remembers it).
        """
        out = [self.header()]
        if source is not None and self.span.line:
            lines = _lines(source)
            if 0 < self.span.line <= len(lines):
                text = lines[self.span.line - 1].expandtabs(1)
                start = max(self.span.col - 1, 0)
                if self.span.end_line == self.span.line and self.span.end_col > self.span.col:
                    width = self.span.end_col - self.span.col
                else:
                    width = 1
                text, start = _window(text, start)
                out.append(f"    {text}")
                width = max(1, min(width, max(len(text) - start, 1)))
                out.append("    " + " " * start + "^" + "~" * (width - 1))
        for note, span in self.related:
            out.append(f"{self.path}:{span.line}:{span.col}: note: {note}")
        if self.hint:
            out.append(f"    hint: {self.hint}")
        return "\n".join(out)

    def to_json(self) -> dict[str, object]:
        """A JSON-ready dict of every field; :meth:`from_json` reads it back."""
        return {
            "path": self.path,
            "line": self.span.line,
            "col": self.span.col,
            "end_line": self.span.end_line,
            "end_col": self.span.end_col,
            "severity": str(self.severity),
            "code": self.code,
            "message": self.message,
            "hint": self.hint,
            "related": [{"note": note, "span": list(span)} for note, span in self.related],
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Diagnostic:
        """A diagnostic read back from :meth:`to_json`."""
        return cls(
            severity=Severity(d["severity"]),
            code=str(d["code"]),
            message=str(d["message"]),
            span=Span(int(d["line"]), int(d["col"]), int(d["end_line"]), int(d["end_col"])),
            path=str(d.get("path", "<string>")),
            hint=d.get("hint"),
            related=tuple((str(r["note"]), Span(*(int(x) for x in r["span"]))) for r in d.get("related", ())),
        )


@functools.lru_cache(maxsize=4)
def _lines(source: str) -> list[str]:
    """``source`` split into lines, remembered: :meth:`Diagnostic.render` is called once per
    diagnostic with the same source, and splitting it each time made rendering a file's
    diagnostics quadratic. A str caches its hash, so a lookup costs no rescan."""
    return source.splitlines()


def _window(text: str, start: int) -> tuple[str, int]:
    """At most :data:`LINE_WIDTH` characters of ``text`` around column ``start`` (0-based),
    with the column moved to match; a cut end is marked ``...``."""
    if len(text) <= LINE_WIDTH:
        return text, start
    begin = min(max(start - LINE_WIDTH // 4, 0), len(text) - LINE_WIDTH)
    end = begin + LINE_WIDTH
    head = "..." if begin > 0 else ""
    tail = "..." if end < len(text) else ""
    return head + text[begin:end] + tail, start - begin + len(head)


class SleecError(UserError):
    """Raised when a rule file cannot be used; carries every diagnostic found.

    Catch it around :func:`cosleec.lang.load` or ``RuleSet.from_file`` to show the user
    every problem at once (:meth:`render` gives the compiler-style text with carets).
    """

    def __init__(self, diagnostics: Sequence[Diagnostic], source: str | None = None) -> None:
        self.diagnostics = tuple(diagnostics)
        self.source = source
        errors = [d for d in self.diagnostics if d.is_error] or list(self.diagnostics)
        first = errors[0] if errors else None
        where = ""
        if first is not None:
            where = f"{first.path}:{first.span.line}:{first.span.col}" if first.span.line else first.path
        super().__init__(
            first.header() if first is not None else "invalid SLEEC specification",
            hint=(first.hint or "") if first is not None else "",
            where=where,
        )

    def render(self) -> str:
        """Every diagnostic, each with its source line and a caret under the problem."""
        return "\n".join(d.render(self.source) for d in self.diagnostics)


_RANK = {Severity.NOTE: 0, Severity.WARNING: 1, Severity.ERROR: 2}
_NOUN = {Severity.NOTE: "note", Severity.WARNING: "warning", Severity.ERROR: "error"}


@dataclass
class _Fold:
    """The bookkeeping of one :meth:`DiagnosticSink.folding` block."""

    where: str
    limit: int
    shown: dict[str, int] = field(default_factory=dict)  # code -> diagnostics kept
    folded: dict[str, list[Diagnostic]] = field(default_factory=dict)  # code -> [first, most severe]
    count: dict[str, int] = field(default_factory=dict)  # code -> diagnostics folded

    def admit(self, d: Diagnostic) -> bool:
        """Whether ``d`` is kept; if not, it is counted towards its code's summary."""
        if self.shown.get(d.code, 0) < self.limit:
            self.shown[d.code] = self.shown.get(d.code, 0) + 1
            return True
        kept = self.folded.get(d.code)
        if kept is None:
            self.folded[d.code] = [d, d]
        elif _RANK[d.severity] > _RANK[kept[1].severity]:
            kept[1] = d
        self.count[d.code] = self.count.get(d.code, 0) + 1
        return False

    def summaries(self, path: str) -> list[Diagnostic]:
        """One diagnostic per folded code: as severe as the worst it stands for, at the
        first one's place, so that the file fails exactly when it did without folding."""
        out = []
        for code, (first, worst) in self.folded.items():
            n = self.count[code]
            noun = _NOUN[worst.severity] + ("s" if n > 1 else "")
            out.append(
                Diagnostic(
                    severity=worst.severity,
                    code=code,
                    message=f"... and {n:,} more `{code}` {noun} like this in {self.where} "
                    f"(only the first {self.limit} of each kind are shown)",
                    span=first.span,
                    path=path,
                )
            )
        return out


class _Folding:
    """The context manager :meth:`DiagnosticSink.folding` returns."""

    __slots__ = ("fold", "outer", "sink")

    def __init__(self, sink: DiagnosticSink, fold: _Fold) -> None:
        self.sink = sink
        self.fold = fold
        self.outer: _Fold | None = None

    def __enter__(self) -> None:
        sink = self.sink
        self.outer = sink._fold
        sink._fold = self.fold

    def __exit__(self, *exc: object) -> None:
        sink = self.sink
        sink._fold = self.outer
        if self.fold.folded:
            sink.items.extend(self.fold.summaries(sink.path))


class DiagnosticSink:
    """Collects diagnostics for one file so that all of them are reported in one run."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.items: list[Diagnostic] = []
        self._fold: _Fold | None = None

    def _add(self, d: Diagnostic) -> None:
        if self._fold is None or self._fold.admit(d):
            self.items.append(d)

    def error(self, code: str, message: str, span: Span = NO_SPAN, **kw: object) -> None:
        """Record an error; ``kw`` (``hint``, ``related``) goes to the :class:`Diagnostic`."""
        self._add(
            Diagnostic(severity=Severity.ERROR, code=code, message=message, span=span, path=self.path, **kw)  # type: ignore[arg-type]
        )

    def warning(self, code: str, message: str, span: Span = NO_SPAN, **kw: object) -> None:
        """Record a warning; ``kw`` (``hint``, ``related``) goes to the :class:`Diagnostic`."""
        self._add(
            Diagnostic(severity=Severity.WARNING, code=code, message=message, span=span, path=self.path, **kw)  # type: ignore[arg-type]
        )

    def note(self, code: str, message: str, span: Span = NO_SPAN) -> None:
        """Record a note: information that never makes the file fail."""
        self._add(Diagnostic(severity=Severity.NOTE, code=code, message=message, span=span, path=self.path))

    def folding(self, where: str, limit: int) -> AbstractContextManager[None]:
        """Inside the block, keep the first ``limit`` diagnostics of each code; fold the rest
        into one summary per code (``... and 19,980 more ...``), added when the block ends.

        The checker wraps each rule in one: a generated rule with 20,000 ``unless`` clauses
        that all draw the same warning then reports 20 of them and a count, not 20,000.
        ``where`` names the block in the summary (``rule `R1```). A ``limit`` of 0 or less
        folds nothing. Blocks do not nest: an inner block takes over until it ends.
        """
        if limit <= 0:
            return nullcontext()
        return _Folding(self, _Fold(where, limit))  # one per rule: cheaper than @contextmanager

    def shown(self, code: str) -> bool:
        """Whether a diagnostic with ``code`` recorded now would be kept (not folded): lets a
        caller skip work, such as a "did you mean" search, for one that would not be."""
        fold = self._fold
        return fold is None or fold.shown.get(code, 0) < fold.limit

    def extend(self, diags: Iterable[Diagnostic]) -> None:
        """Add diagnostics built elsewhere, unchanged (their own path is kept)."""
        self.items.extend(diags)

    def sorted(self) -> list[Diagnostic]:
        """The diagnostics in source order (line, then column; span-less ones first)."""
        return sorted(self.items, key=lambda d: (d.span.line, d.span.col))
