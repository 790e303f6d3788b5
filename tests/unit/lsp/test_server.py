"""``cosleec lsp`` over stdio, driven by pygls's real LSP client, as an editor drives it.

One server process for the module (``python -m cosleec.cli.main lsp``): open a file and get
``cosleec check``'s diagnostics, edit it (an incremental change) and get the new ones,
hover, complete, go to a definition, find references, the outline, rename, format, and on
save ``cosleec analyse``'s findings -- on a file with non-ASCII characters before its names
(positions are UTF-16), on the paper notation, and on the largest corpus file. Expected
answers come from the library (``analyse``, ``format_source``, the analysis), not from
the server.
"""

from __future__ import annotations

import asyncio
import sys
import threading
from collections.abc import Callable, Coroutine, Iterator
from pathlib import Path
from typing import Any, TypeVar

import pytest
from lsprotocol import types as T
from pygls.exceptions import JsonRpcException
from pygls.lsp.client import LanguageClient

from cosleec.analysis import Settings, analyse_spec
from cosleec.lang import analyse, format_source
from cosleec.testing.corpus import corpus_files

ROOT = Path(__file__).resolve().parents[3]
LARGEST = (
    "a-l-partis__SLEEC-ADAPT__AgentAdaption__agentAdaptionCode__scalability__sleecRules__rulestest625.sleec"
)
X = TypeVar("X")

RULES = """// names after characters of two UTF-16 units: 𝔘 (U+1D518), and one: ü
def_start
    event Start
    event Go
    event Stop
    measure level : scale(low, medium, high)
    measure busy : boolean
    constant N = 5
def_end
rule_start
    R1 when Start and level > low then Go within N seconds unless busy then Stop
    /* 𝔘𝔘 ü */ R2 when Go then not Stop within 2 seconds
rule_end
priority_start R1 > R2 priority_end
"""


def utf16(s: str) -> int:
    return len(s.encode("utf-16-le")) // 2


def at(text: str, needle: str, into: int = 0, nth: int = 0) -> T.Position:
    """The LSP position (UTF-16) of ``needle``'s start (plus ``into`` characters)."""
    i = -1
    for _ in range(nth + 1):
        i = text.index(needle, i + 1)
    i += into
    line_start = text.rfind("\n", 0, i) + 1
    return T.Position(line=text.count("\n", 0, i), character=utf16(text[line_start:i]))


def apply(text: str, edits: list[T.TextEdit]) -> str:
    """Apply LSP edits (UTF-16 positions) to a text, last first."""

    def offset(p: T.Position) -> int:
        start = 0
        for _ in range(p.line):
            start = text.index("\n", start) + 1
        units = 0
        i = start
        while units < p.character:
            units += utf16(text[i])
            i += 1
        return i

    for e in sorted(edits, key=lambda e: (e.range.start.line, e.range.start.character), reverse=True):
        text = text[: offset(e.range.start)] + e.new_text + text[offset(e.range.end) :]
    return text


CLIENT = T.ClientCapabilities(
    text_document=T.TextDocumentClientCapabilities(rename=T.RenameClientCapabilities(prepare_support=True))
)


class Session:
    """A real ``cosleec lsp`` process and pygls's client, on an event loop in a thread."""

    def __init__(self, options: dict[str, Any]) -> None:
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self.thread.start()
        self.published: list[T.PublishDiagnosticsParams] = []
        self.cond = threading.Condition()
        self.client: LanguageClient = self.run(self._client())
        self.run(self.client.start_io(sys.executable, "-m", "cosleec.cli.main", "lsp", "--stdio"))
        self.init = self.run(
            self.client.initialize_async(
                T.InitializeParams(capabilities=CLIENT, initialization_options=options)
            )
        )
        self.call(self.client.initialized, T.InitializedParams())

    async def _client(self) -> LanguageClient:
        client = LanguageClient("cosleec-test", "1")

        @client.feature(T.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def diagnostics(params: T.PublishDiagnosticsParams) -> None:
            with self.cond:
                self.published.append(params)
                self.cond.notify_all()

        return client

    def run(self, coro: Coroutine[Any, Any, X], timeout: float = 30) -> X:
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def call(self, fn: Callable[[Any], None], params: Any) -> None:
        """A notification, sent from the loop's thread."""

        async def send() -> None:
            fn(params)

        self.run(send())

    def mark(self) -> int:
        with self.cond:
            return len(self.published)

    def diagnostics(
        self, uri: str, since: int, ok: Callable[[T.PublishDiagnosticsParams], bool] = lambda p: True
    ) -> list[T.Diagnostic]:
        """The first diagnostics published for ``uri`` after ``since`` that satisfy ``ok``."""
        found: list[T.PublishDiagnosticsParams] = []

        def seen() -> bool:
            found[:] = [p for p in self.published[since:] if p.uri == uri and ok(p)]
            return bool(found)

        with self.cond:
            assert self.cond.wait_for(seen, timeout=60), f"no diagnostics for {uri}"
        return list(found[0].diagnostics)

    def open(self, uri: str, text: str, version: int = 1) -> list[T.Diagnostic]:
        since = self.mark()
        self.call(
            self.client.text_document_did_open,
            T.DidOpenTextDocumentParams(
                T.TextDocumentItem(uri=uri, language_id="sleec", version=version, text=text)
            ),
        )
        return self.diagnostics(uri, since)

    def change(
        self, uri: str, version: int, changes: list[T.TextDocumentContentChangeEvent]
    ) -> list[T.Diagnostic]:
        since = self.mark()
        self.call(
            self.client.text_document_did_change,
            T.DidChangeTextDocumentParams(
                text_document=T.VersionedTextDocumentIdentifier(uri=uri, version=version),
                content_changes=changes,
            ),
        )
        return self.diagnostics(uri, since, lambda p: p.version == version)

    def doc(self, uri: str) -> T.TextDocumentIdentifier:
        return T.TextDocumentIdentifier(uri=uri)

    def close(self) -> None:
        try:
            self.run(self.client.shutdown_async(None))
            self.call(self.client.exit, None)
            self.run(self.client.stop())
        finally:
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(10)


@pytest.fixture(scope="module")
def lsp() -> Iterator[Session]:
    session = Session({"debounce": 0.01, "analysisTimeout": 60})
    yield session
    session.close()


def expected(text: str, path: str) -> list[tuple[str, str, int, int, int, int]]:
    """``cosleec check``'s diagnostics of ``text`` as (code, message, range in UTF-16)."""
    out = []
    lines = text.split("\n")
    for d in analyse(text, path).diagnostics:
        s = d.span
        start = utf16(lines[s.line - 1][: s.col - 1]) if s.line else 0
        end = utf16(lines[s.end_line - 1][: s.end_col - 1]) if s.line else 0
        message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
        out.append((d.code, message, max(s.line - 1, 0), start, max(s.end_line - 1, 0), end))
    return out


def shown(diags: list[T.Diagnostic]) -> list[tuple[str, str, int, int, int, int]]:
    return [
        (
            str(d.code),
            d.message,
            d.range.start.line,
            d.range.start.character,
            d.range.end.line,
            d.range.end.character,
        )
        for d in diags
    ]


def test_the_server_says_what_it_can_do(lsp: Session) -> None:
    caps = lsp.init.capabilities
    assert caps.hover_provider and caps.definition_provider and caps.references_provider
    assert caps.document_symbol_provider and caps.document_formatting_provider
    assert caps.rename_provider == T.RenameOptions(prepare_provider=True)
    assert caps.completion_provider is not None
    assert caps.position_encoding == T.PositionEncodingKind.Utf16
    sync = caps.text_document_sync
    assert isinstance(sync, T.TextDocumentSyncOptions) and sync.change == T.TextDocumentSyncKind.Incremental


def test_diagnostics_follow_edits_with_checks_codes_places_and_hints(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/edits.sleec"
    assert lsp.open(uri, RULES) == []
    # type `x` after the trigger `Go` of R2, which sits after four UTF-16 units of 𝔘𝔘
    where = at(RULES, "Go then not", into=2)
    change = T.TextDocumentContentChangePartial(range=T.Range(start=where, end=where), text="x")
    diags = lsp.change(uri, 2, [change])
    edited = RULES.replace("R2 when Go then", "R2 when Gox then")
    assert shown(diags) == expected(edited, "/tmp/cosleec-lsp/edits.sleec")
    [d] = diags
    assert d.code == "undeclared-event" and d.severity == T.DiagnosticSeverity.Error and d.source == "cosleec"
    assert d.range.start == at(edited, "Gox then") and d.range.end == at(edited, "Gox then", into=3)
    assert "did you mean `Go`?" in d.message  # check's hint comes along
    # two changes in one notification: delete the `x`, then break a deadline's unit
    unit = at(edited, "seconds unless")
    diags = lsp.change(
        uri,
        3,
        [
            T.TextDocumentContentChangePartial(
                range=T.Range(start=where, end=at(edited, "Gox then", into=3)), text=""
            ),
            T.TextDocumentContentChangePartial(
                range=T.Range(start=unit, end=T.Position(unit.line, unit.character + 7)), text="second"
            ),
        ],
    )
    again = RULES.replace("N seconds unless", "N second unless")
    assert shown(diags) == expected(again, "/tmp/cosleec-lsp/edits.sleec") != []
    assert lsp.change(uri, 4, [T.TextDocumentContentChangeWholeDocument(text=RULES)]) == []


def test_hover_names_the_declaration_type_and_the_rules_that_read_or_produce_it(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/hover.sleec"
    lsp.open(uri, RULES)
    hover = lsp.run(
        lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(RULES, "level > low", 2)))
    )
    assert hover is not None and isinstance(hover.contents, T.MarkupContent)
    text = hover.contents.value
    assert "**measure** `level` : `scale(low, medium, high)`" in text and "read by: R1" in text
    assert "declared at line 6" in text
    assert hover.range == T.Range(start=at(RULES, "level >"), end=at(RULES, "level >", 5))
    stop = lsp.run(
        lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(RULES, "Stop within")))
    )
    assert stop is not None and isinstance(stop.contents, T.MarkupContent)
    assert "produced (obliged) by: R1.1" in stop.contents.value and "forbidden by: R2" in stop.contents.value
    value = lsp.run(lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(RULES, "low then"))))
    assert value is not None and "scale value** `low` of measure `level`" in str(value.contents)
    rule = lsp.run(
        lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(RULES, "R2 priority", 1)))
    )
    assert rule is not None and "R2 when Go then not Stop within 2 seconds" in str(rule.contents)
    assert "gives way to: R1" in str(rule.contents)
    none = lsp.run(
        lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(RULES, "within N", 2)))
    )
    assert none is None


def test_definition_and_references_of_events_measures_constants_and_rules(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/defs.sleec"
    lsp.open(uri, RULES)

    def definition(pos: T.Position) -> T.Range:
        got = lsp.run(lsp.client.text_document_definition_async(T.DefinitionParams(lsp.doc(uri), pos)))
        assert isinstance(got, T.Location) and got.uri == uri
        return got.range

    assert definition(at(RULES, "N seconds")).start == at(RULES, "N = 5")
    assert definition(at(RULES, "busy then")).start == at(RULES, "busy : boolean")
    assert definition(at(RULES, "Go within")).start == at(RULES, "Go\n")
    assert definition(at(RULES, "R2 priority")) == T.Range(
        start=at(RULES, "R2 when"), end=at(RULES, "R2 when", 2)
    )
    assert definition(at(RULES, "low then")).start == at(RULES, "low,")

    def refs(pos: T.Position, declaration: bool) -> list[T.Position]:
        got = lsp.run(
            lsp.client.text_document_references_async(
                T.ReferenceParams(
                    text_document=lsp.doc(uri),
                    position=pos,
                    context=T.ReferenceContext(include_declaration=declaration),
                )
            )
        )
        assert got is not None
        return [loc.range.start for loc in got]

    assert refs(at(RULES, "Go within"), True) == [
        at(RULES, "Go\n"),
        at(RULES, "Go within"),
        at(RULES, "Go then"),
    ]
    assert refs(at(RULES, "Go within"), False) == [at(RULES, "Go within"), at(RULES, "Go then")]
    assert refs(at(RULES, "R1 >"), True) == [at(RULES, "R1 when"), at(RULES, "R1 >")]


def test_completion_offers_declared_names_scale_values_and_keywords(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/complete.sleec"
    lsp.open(uri, RULES)

    def labels(pos: T.Position) -> list[str]:
        got = lsp.run(lsp.client.text_document_completion_async(T.CompletionParams(lsp.doc(uri), pos)))
        assert isinstance(got, T.CompletionList)
        return [i.label for i in sorted(got.items, key=lambda i: i.sort_text or i.label)]

    assert labels(at(RULES, "low then")) == ["low", "medium", "high"]  # after `level >`: its scale, in order
    after_then = labels(at(RULES, "Go within"))
    assert after_then[:3] == ["Go", "Start", "Stop"]  # after `then`: events first
    assert {"busy", "level", "N", "when", "unless", "within"} <= set(after_then)
    assert "R1" not in after_then
    assert labels(at(RULES, "R1 > R2", 5))[:2] == ["R1", "R2"]  # in the priority block: rules


def test_outline_lists_declarations_and_rules(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/outline.sleec"
    lsp.open(uri, RULES)
    got = lsp.run(lsp.client.text_document_document_symbol_async(T.DocumentSymbolParams(lsp.doc(uri))))
    assert got is not None
    groups = {s.name: s for s in got if isinstance(s, T.DocumentSymbol)}
    assert list(groups) == ["definitions", "rules"]
    defs = groups["definitions"].children or []
    assert [(s.name, s.kind) for s in defs] == [
        ("Start", T.SymbolKind.Event), ("Go", T.SymbolKind.Event), ("Stop", T.SymbolKind.Event),
        ("level", T.SymbolKind.Variable), ("busy", T.SymbolKind.Variable), ("N", T.SymbolKind.Constant),
    ]  # fmt: skip
    assert [c.name for c in defs[3].children or []] == ["low", "medium", "high"]
    rules = groups["rules"].children or []
    assert [(r.name, r.detail) for r in rules] == [("R1", "when Start"), ("R2", "when Go")]
    r2 = rules[1]
    assert r2.selection_range == T.Range(start=at(RULES, "R2 when"), end=at(RULES, "R2 when", 2))
    assert r2.range.end == at(RULES, "2 seconds\n", len("2 seconds"))


def test_rename_changes_every_use_and_refuses_keywords_and_taken_names(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/rename.sleec"
    lsp.open(uri, RULES)
    prepared = lsp.run(
        lsp.client.text_document_prepare_rename_async(
            T.PrepareRenameParams(lsp.doc(uri), at(RULES, "Go then", 1))
        )
    )
    assert prepared == T.Range(start=at(RULES, "Go then"), end=at(RULES, "Go then", 2))
    edit = lsp.run(
        lsp.client.text_document_rename_async(T.RenameParams(lsp.doc(uri), at(RULES, "Go then"), "Proceed"))
    )
    assert edit is not None and edit.changes is not None
    renamed = apply(RULES, list(edit.changes[uri]))
    assert renamed == RULES.replace("Go", "Proceed")
    assert analyse(renamed).ok
    for bad, why in (("when", "keyword"), ("Stop", "already declared"), ("2go", "not a name")):
        with pytest.raises(JsonRpcException, match=why):
            lsp.run(
                lsp.client.text_document_rename_async(T.RenameParams(lsp.doc(uri), at(RULES, "Go then"), bad))
            )
    with pytest.raises(JsonRpcException, match="scale value cannot be renamed"):
        lsp.run(
            lsp.client.text_document_prepare_rename_async(
                T.PrepareRenameParams(lsp.doc(uri), at(RULES, "low then"))
            )
        )


def test_formatting_is_cosleec_fmt(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/format.sleec"
    messy = RULES.replace("    R1 when Start", "R1   when  Start").replace("event Stop", "event    Stop")
    lsp.open(uri, messy)
    params = T.DocumentFormattingParams(lsp.doc(uri), T.FormattingOptions(tab_size=4, insert_spaces=True))
    edits = lsp.run(lsp.client.text_document_formatting_async(params))
    assert edits
    result = analyse(messy)
    assert result.spec is not None
    assert apply(messy, list(edits)) == format_source(messy, result.spec) != messy
    lsp.change(uri, 2, [T.TextDocumentContentChangeWholeDocument(text=apply(messy, list(edits)))])
    again = lsp.run(lsp.client.text_document_formatting_async(params))
    assert again is not None and list(again) == []  # formatted: nothing to do
    lsp.change(uri, 3, [T.TextDocumentContentChangeWholeDocument(text=RULES.replace("event Go", "event"))])
    with pytest.raises(JsonRpcException, match="has errors"):
        lsp.run(lsp.client.text_document_formatting_async(params))


def test_save_adds_the_findings_of_cosleec_analyse(lsp: Session) -> None:
    path = ROOT / "examples" / "analysis" / "curtains.sleec"
    text = path.read_text(encoding="utf-8")
    uri = path.as_uri()
    assert lsp.open(uri, text) == []
    since = lsp.mark()
    lsp.call(lsp.client.text_document_did_save, T.DidSaveTextDocumentParams(lsp.doc(uri), text=text))
    diags = lsp.diagnostics(uri, since, lambda p: any(d.source == "cosleec analyse" for d in p.diagnostics))
    result = analyse(text, str(path))
    assert result.spec is not None and result.symbols is not None
    findings, _ = analyse_spec(result.spec, dict(result.symbols.constant_values), Settings())
    assert sorted((str(d.code), d.range.start.line) for d in diags) == sorted(
        (f.code, f.span.line - 1) for f in findings
    )
    assert "situational-conflict" in {d.code for d in diags}
    # an edit makes the findings' places uncertain: they wait for the next save
    end = at(text, "rule_end")
    assert (
        lsp.change(uri, 2, [T.TextDocumentContentChangePartial(range=T.Range(start=end, end=end), text="\n")])
        == []
    )


def test_the_paper_notation(lsp: Session) -> None:
    path = ROOT / "examples" / "curtains_paper.txt"
    text = path.read_text(encoding="utf-8")
    uri = path.as_uri()
    assert shown(lsp.open(uri, text)) == expected(text, str(path))
    got = lsp.run(
        lsp.client.text_document_definition_async(
            T.DefinitionParams(lsp.doc(uri), at(text, "OpenCurtains", nth=1))
        )
    )
    assert isinstance(got, T.Location) and got.range.start == at(text, "OpenCurtains")  # inferred: first use
    hover = lsp.run(
        lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), at(text, "UserUndressed")))
    )
    assert hover is not None and "read by: R1.1" in str(hover.contents)
    items = lsp.run(
        lsp.client.text_document_completion_async(T.CompletionParams(lsp.doc(uri), at(text, "THEN")))
    )
    assert isinstance(items, T.CompletionList) and "IN WHICH CASE" in {i.label for i in items.items}


def test_every_request_on_the_largest_corpus_file(lsp: Session) -> None:
    files = [f for f in corpus_files() if f.name == LARGEST]
    if not files:
        pytest.skip("the SLEEC corpus is not here")
    text = files[0].read_text(encoding="utf-8")
    uri = files[0].as_uri()
    result = analyse(text, str(files[0]))
    assert result.spec is not None and len(result.spec.rules) > 600
    assert shown(lsp.open(uri, text)) == expected(text, str(files[0]))
    last = result.spec.rules[-1]
    trigger = T.Position(line=last.trigger.span.line - 1, character=last.trigger.span.col - 1)
    hover = lsp.run(lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), trigger)))
    assert hover is not None and f"**event** `{last.trigger.event}`" in str(hover.contents)
    decl = next(e for e in result.spec.events if e.name == last.trigger.event)
    got = lsp.run(lsp.client.text_document_definition_async(T.DefinitionParams(lsp.doc(uri), trigger)))
    assert isinstance(got, T.Location) and got.range.start == T.Position(
        decl.span.line - 1, decl.span.col - 1
    )
    refs = lsp.run(
        lsp.client.text_document_references_async(
            T.ReferenceParams(
                text_document=lsp.doc(uri),
                position=trigger,
                context=T.ReferenceContext(include_declaration=True),
            )
        )
    )
    assert refs is not None and len(refs) >= 2
    symbols = lsp.run(lsp.client.text_document_document_symbol_async(T.DocumentSymbolParams(lsp.doc(uri))))
    assert symbols is not None
    rules = next(s for s in symbols if isinstance(s, T.DocumentSymbol) and s.name == "rules")
    assert len(rules.children or []) == len(result.spec.rules)
    items = lsp.run(lsp.client.text_document_completion_async(T.CompletionParams(lsp.doc(uri), trigger)))
    assert isinstance(items, T.CompletionList) and last.trigger.event in {i.label for i in items.items}
    edit = lsp.run(
        lsp.client.text_document_rename_async(T.RenameParams(lsp.doc(uri), trigger, "RenamedEvent"))
    )
    assert edit is not None and edit.changes is not None and len(edit.changes[uri]) == len(refs)
    params = T.DocumentFormattingParams(lsp.doc(uri), T.FormattingOptions(tab_size=4, insert_spaces=True))
    edits = lsp.run(lsp.client.text_document_formatting_async(params))
    assert apply(text, list(edits or [])) == format_source(text, result.spec)
    # one character typed in the middle of the file: the diagnostics of the new text
    middle = result.spec.rules[len(result.spec.rules) // 2].trigger.span
    pos = T.Position(middle.line - 1, middle.end_col - 1)
    diags = lsp.change(
        uri, 2, [T.TextDocumentContentChangePartial(range=T.Range(start=pos, end=pos), text="Q")]
    )
    lines = text.split("\n")
    lines[middle.line - 1] = (
        lines[middle.line - 1][: middle.end_col - 1] + "Q" + lines[middle.line - 1][middle.end_col - 1 :]
    )
    assert shown(diags) == expected("\n".join(lines), str(files[0])) != []


def test_closing_a_file_clears_its_diagnostics(lsp: Session) -> None:
    uri = "file:///tmp/cosleec-lsp/closed.sleec"
    assert lsp.open(uri, RULES.replace("event Go", "")) != []
    since = lsp.mark()
    lsp.call(lsp.client.text_document_did_close, T.DidCloseTextDocumentParams(lsp.doc(uri)))
    assert lsp.diagnostics(uri, since) == []
    with pytest.raises(JsonRpcException, match="not open"):
        lsp.run(lsp.client.text_document_hover_async(T.HoverParams(lsp.doc(uri), T.Position(0, 0))))
