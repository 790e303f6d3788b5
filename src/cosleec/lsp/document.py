"""One open rule file: its text as the editor has it, and what cosleec makes of it.

The editor sends edits, not files; :meth:`Document.apply` keeps the text, counting lines and
characters as LSP does. Checking is lazy and incremental: :meth:`Document.result` checks the
text the first time it is asked after an edit, with an
:class:`~cosleec.lang.IncrementalAnalyser` that parses again only the rules the edits
touched; the index of names is built the first time a request needs it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from urllib.parse import unquote, urlparse

from lsprotocol import types as T

from cosleec.lang import WIDTH, CheckResult, Diagnostic, HedgeSemantics, IncrementalAnalyser, Options
from cosleec.lang import ast as A
from cosleec.lsp.fixes import Repaired
from cosleec.lsp.index import Index, Kind, names_of
from cosleec.lsp.positions import LineIndex


@dataclass(frozen=True, kw_only=True)
class Settings:
    """What the editor may set (LSP ``initializationOptions``, names in camelCase): the
    options of ``cosleec check`` and ``cosleec fmt``, and the analysis run on save."""

    dialect: str = "auto"
    strict: bool = False
    infer_defs: bool = False
    lint: bool = False
    strict_precedence: bool = False
    legos_compat: bool = False
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
    format_width: int = WIDTH
    analysis: bool = True  # run `cosleec analyse` on save
    analysis_timeout: float = 60.0  # seconds for the whole analysis of a file (and its repairs)
    fixes: bool = True  # repair the findings on save too, and offer the fixes as quick fixes
    debounce: float = 0.03  # seconds between an edit and its diagnostics (edits in between coalesce)

    @classmethod
    def from_json(cls, data: object) -> Settings:
        """Settings from ``initializationOptions`` (unknown keys ignored, wrong types refused
        with ``ValueError``)."""
        if not isinstance(data, dict):
            return cls()
        names = {
            "dialect": str,
            "strict": bool,
            "inferDefs": bool,
            "lint": bool,
            "strictPrecedence": bool,
            "legosCompat": bool,
            "semantics": str,
            "formatWidth": int,
            "analysis": bool,
            "analysisTimeout": float,
            "fixes": bool,
            "debounce": float,
        }
        given: dict[str, object] = {}
        for key, kind in names.items():
            if key in data:
                value = data[key]
                ok = (
                    isinstance(value, int | float) and not isinstance(value, bool)
                    if kind is float
                    else isinstance(value, kind)
                )
                if not ok:
                    raise ValueError(f"initializationOptions.{key} must be a {kind.__name__}, not {value!r}")
                snake = "".join(f"_{c.lower()}" if c.isupper() else c for c in key)
                given[snake] = HedgeSemantics(value) if key == "semantics" else value
        return cls(**given)  # type: ignore[arg-type]

    def options(self) -> Options:
        """The checker's options, as ``cosleec check`` builds them from its flags."""
        return Options(
            strict_precedence=self.strict_precedence,
            lint=self.lint,
            semantics=self.semantics,
            legos_compat=self.legos_compat,
        )


def uri_path(uri: str) -> str:
    """The file path of a ``file:`` URI (the URI itself for others: ``untitled:``)."""
    parsed = urlparse(uri)
    return unquote(parsed.path) if parsed.scheme == "file" else uri


@dataclass
class Document:
    """One open document. ``findings`` are the last on-save analysis's diagnostics, shown
    while the text is the one analysed (``findings_text``): after an edit their places may
    be wrong, so they wait for the next save. ``repairs`` are their verified fixes, offered
    as quick fixes on the same condition (``repairs.text`` is the text repaired)."""

    uri: str
    text: str
    version: int | None
    settings: Settings = field(default_factory=Settings)
    encoding: str = "utf-16"
    findings: list[Diagnostic] = field(default_factory=list)
    findings_text: str | None = None
    repairs: Repaired | None = None
    _analyser: IncrementalAnalyser | None = field(default=None, init=False, repr=False)
    _result: CheckResult | None = field(default=None, init=False, repr=False)
    _lines: LineIndex | None = field(default=None, init=False, repr=False)
    _index: Index | None = field(default=None, init=False, repr=False)
    # the declared names of the last text that parsed
    _known: list[tuple[Kind, str, str]] = field(default_factory=list, init=False, repr=False)

    @property
    def path(self) -> str:
        """The file's path, as diagnostics name it."""
        return uri_path(self.uri)

    def apply(self, changes: Sequence[T.TextDocumentContentChangeEvent], version: int | None) -> None:
        """Apply an editor's changes, in order (a change without a range replaces the text)."""
        text = self.text
        for change in changes:
            if isinstance(change, T.TextDocumentContentChangePartial):
                lines = LineIndex(text, self.encoding)
                start, end = lines.to_offset(change.range.start), lines.to_offset(change.range.end)
                text = text[:start] + change.text + text[max(start, end) :]
            else:
                text = change.text
        self.set_text(text, version)

    def set_text(self, text: str, version: int | None) -> None:
        """Replace the text (what an editor's full synchronisation sends)."""
        self.text, self.version = text, version
        self._result = self._lines = self._index = None

    @property
    def lines(self) -> LineIndex:
        """The line table of the current text."""
        if self._lines is None:
            self._lines = LineIndex(self.text, self.encoding)
        return self._lines

    def result(self) -> CheckResult:
        """The current text, parsed and checked as ``cosleec check`` would (incrementally)."""
        if self._result is None:
            if self._analyser is None:
                s = self.settings
                self._analyser = IncrementalAnalyser(
                    self.path,
                    dialect=s.dialect,
                    strict=s.strict,
                    infer_defs=s.infer_defs,
                    options=s.options(),
                    legos_compat=s.legos_compat,
                )
            self._result = self._analyser.analyse(self.text)
            if self._result.spec is not None:
                self._known = list(names_of(self._result.spec))
        return self._result

    def index(self) -> Index:
        """Where every name of the current text is declared and used."""
        if self._index is None:
            self._index = Index.build(self.result(), self.lines)
        return self._index

    def known_names(self) -> list[tuple[Kind, str, str]]:
        """The declared names of the last text that parsed: what completion offers while the
        current text has a syntax error (typing usually makes one)."""
        self.result()
        return self._known

    @property
    def is_paper(self) -> bool:
        """Whether the document is in the paper notation."""
        result = self.result()
        return result.dialect is A.Dialect.PAPER
