"""Compiler-style diagnostics: ``path:line:col: error: message`` plus the line and a caret.

Every problem cosleec finds in a rule file becomes a :class:`Diagnostic`; nothing the user
wrote ever surfaces as a Python traceback. :class:`SleecError` is the one exception type
the language front-end raises, and it carries the diagnostics.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from cosleec.errors import UserError
from cosleec.lang.ast import NO_SPAN, Span


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
        """The header, then the offending source line with a caret under the span."""
        out = [self.header()]
        if source is not None and self.span.line:
            lines = source.splitlines()
            if 0 < self.span.line <= len(lines):
                text = lines[self.span.line - 1].expandtabs(1)
                out.append(f"    {text}")
                start = max(self.span.col - 1, 0)
                if self.span.end_line == self.span.line and self.span.end_col > self.span.col:
                    width = self.span.end_col - self.span.col
                else:
                    width = 1
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


class DiagnosticSink:
    """Collects diagnostics for one file so that all of them are reported in one run."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.items: list[Diagnostic] = []

    def error(self, code: str, message: str, span: Span = NO_SPAN, **kw: object) -> None:
        """Record an error; ``kw`` (``hint``, ``related``) goes to the :class:`Diagnostic`."""
        self.items.append(
            Diagnostic(severity=Severity.ERROR, code=code, message=message, span=span, path=self.path, **kw)  # type: ignore[arg-type]
        )

    def warning(self, code: str, message: str, span: Span = NO_SPAN, **kw: object) -> None:
        """Record a warning; ``kw`` (``hint``, ``related``) goes to the :class:`Diagnostic`."""
        self.items.append(
            Diagnostic(severity=Severity.WARNING, code=code, message=message, span=span, path=self.path, **kw)  # type: ignore[arg-type]
        )

    def note(self, code: str, message: str, span: Span = NO_SPAN) -> None:
        """Record a note: information that never makes the file fail."""
        self.items.append(
            Diagnostic(severity=Severity.NOTE, code=code, message=message, span=span, path=self.path)
        )

    def extend(self, diags: Iterable[Diagnostic]) -> None:
        """Add diagnostics built elsewhere, unchanged (their own path is kept)."""
        self.items.extend(diags)

    def sorted(self) -> list[Diagnostic]:
        """The diagnostics in source order (line, then column; span-less ones first)."""
        return sorted(self.items, key=lambda d: (d.span.line, d.span.col))
