"""The language server: pygls's connection, the open documents, and when each answer is sent.

Diagnostics follow edits: an edit marks its document changed and schedules a check
``debounce`` seconds later (edits in between coalesce into one check); a request that needs
the current state (hover, definition, ...) checks at once if the check has not run yet. A
save runs ``cosleec analyse`` in another process (onsave.py) and publishes its findings with
the check's diagnostics while the text stays the one analysed; the same process then
repairs them, and code actions offer the verified fixes on the same condition. Messages are read by wire.py,
not pygls's reader: bounded in size and depth, and each one it cannot use answered by the
protocol (:class:`~cosleec.lsp.wire.Limits`).
"""

from __future__ import annotations

import asyncio
import logging
import os
import sys
import threading
from collections.abc import Callable
from importlib import metadata
from typing import Any, BinaryIO, TypeVar

from lsprotocol import types as T
from pygls.exceptions import JsonRpcException, JsonRpcInvalidParams
from pygls.io_ import StdoutWriter
from pygls.lsp.server import LanguageServer

from cosleec.lang import Diagnostic, Severity
from cosleec.lang import ast as A
from cosleec.lsp import features
from cosleec.lsp.document import Document, Settings
from cosleec.lsp.onsave import OnSave, Outcome, timeout_note
from cosleec.lsp.wire import Limits, StdinReader, serve

log = logging.getLogger("cosleec.lsp")

R = TypeVar("R")


def _version() -> str:
    try:
        return metadata.version("cosleec")
    except metadata.PackageNotFoundError:  # pragma: no cover - a source tree, not installed
        return "unknown"


class SleecServer(LanguageServer):
    """cosleec's language server; :func:`build` registers its features."""

    def __init__(self, limits: Limits | None = None) -> None:
        super().__init__("cosleec", _version())
        self.limits = limits or Limits()
        self.settings = Settings()
        self.documents: dict[str, Document] = {}
        self._pending: dict[str, asyncio.TimerHandle] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self.onsave = OnSave(self._analysed)

    def start_io(self, stdin: BinaryIO | None = None, stdout: BinaryIO | None = None) -> None:
        """Serve over ``stdin`` and ``stdout`` until the client exits or closes stdin.

        pygls's own ``start_io``, with its reader replaced by wire.py's, which bounds what it
        reads by :attr:`limits` and answers every message it cannot use.
        """
        self._stop_event = threading.Event()
        reader = StdinReader(stdin or sys.stdin.buffer, self.thread_pool)
        self.protocol.set_writer(StdoutWriter(stdout or sys.stdout.buffer))
        try:
            asyncio.run(serve(reader, self.protocol, self._stop_event, self.limits))
        except BrokenPipeError:
            log.error("the client closed the connection: the server stops")
        except (KeyboardInterrupt, SystemExit):
            pass
        finally:
            self.shutdown()  # type: ignore[no-untyped-call]

    # ------------------------------------------------------------ documents
    def document(self, uri: str) -> Document:
        """The open document ``uri`` (a request about a closed one is refused)."""
        doc = self.documents.get(uri)
        if doc is None:
            raise JsonRpcInvalidParams(f"{uri} is not open")
        return doc

    def encoding(self) -> str:
        """The position encoding agreed with the client."""
        return str(self.workspace.position_encoding or T.PositionEncodingKind.Utf16)

    def changed(self, uri: str) -> None:
        """Schedule the check of ``uri`` after the debounce (replacing one scheduled)."""
        loop = self._loop or asyncio.get_running_loop()
        self._loop = loop
        handle = self._pending.pop(uri, None)
        if handle is not None:
            handle.cancel()
        self._pending[uri] = loop.call_later(self.settings.debounce, self.publish, uri)

    def publish(self, uri: str) -> None:
        """Check ``uri`` (if not done yet) and send its diagnostics."""
        self._pending.pop(uri, None)
        doc = self.documents.get(uri)
        if doc is None:
            return
        self.text_document_publish_diagnostics(
            T.PublishDiagnosticsParams(uri=uri, diagnostics=features.diagnostics(doc), version=doc.version)
        )

    def saved(self, uri: str) -> None:
        """Run the analysis of ``uri``'s text when it checks clean."""
        doc = self.documents.get(uri)
        if doc is None or not self.settings.analysis:
            return
        result = doc.result()
        if not result.ok:
            self.onsave.cancel(uri)
            return
        s = self.settings
        self.onsave.start(
            uri,
            doc.text,
            doc.path,
            options=s.options(),
            dialect=s.dialect,
            timeout=s.analysis_timeout,
            legos_compat=s.legos_compat,
            infer_defs=s.infer_defs,
            repair=s.fixes,
        )

    def _analysed(self, uri: str, outcome: Outcome) -> None:
        """(the watcher thread) hand the outcome to the event loop."""
        if self._loop is not None:
            self._loop.call_soon_threadsafe(self._show_findings, uri, outcome)

    def _show_findings(self, uri: str, outcome: Outcome) -> None:
        doc = self.documents.get(uri)
        if doc is None:
            return
        if outcome.of_repairs:
            self._keep_repairs(doc, outcome)
            return
        found = list(outcome.diagnostics)
        if outcome.timed_out:
            found = [timeout_note(self.settings.analysis_timeout, doc.path)]
        elif outcome.failed:
            found = [_failure("analysis-failed", f"cosleec analyse failed: {outcome.failed}", doc.path)]
        doc.findings, doc.findings_text, doc.repairs = found, outcome.text, None
        if doc.text == outcome.text:
            self.publish(uri)

    def _keep_repairs(self, doc: Document, outcome: Outcome) -> None:
        """Keep the repairs of the findings shown (the code actions offer them); a failure of
        the repairs is said as a note next to the findings."""
        if outcome.text != doc.findings_text:
            return
        doc.repairs = outcome.repairs
        if outcome.failed:
            doc.findings = [
                *doc.findings,
                _failure("repair-failed", f"cosleec analyse --fix failed: {outcome.failed}", doc.path),
            ]
            if doc.text == outcome.text:
                self.publish(doc.uri)

    def answer(self, fn: Callable[[], R]) -> R:
        """Run a request's answer; a refusal becomes the request's error, with its hint."""
        try:
            return fn()
        except features.Refusal as e:
            message = e.message + (f" ({e.hint})" if e.hint else "")
            raise JsonRpcException(message, code=int(T.LSPErrorCodes.RequestFailed)) from None


def _failure(code: str, message: str, path: str) -> Diagnostic:
    """The note for a failure of the on-save analysis or repairs: a bug, said in the editor."""
    return Diagnostic(
        severity=Severity.NOTE,
        code=code,
        message=f"{message} (please report this)",
        span=A.Span(1, 1, 1, 1),
        path=path,
    )


def build(limits: Limits | None = None) -> SleecServer:
    """A server with every feature registered (not started), reading within ``limits``."""
    server = SleecServer(limits)

    @server.feature(T.INITIALIZE)
    def initialize(ls: SleecServer, params: T.InitializeParams) -> None:
        try:
            ls.settings = Settings.from_json(params.initialization_options)
        except ValueError as e:
            raise JsonRpcInvalidParams(str(e)) from None

    @server.feature(T.SHUTDOWN)
    def shutdown(ls: SleecServer, params: Any) -> None:
        ls.onsave.close()

    @server.feature(T.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: SleecServer, params: T.DidOpenTextDocumentParams) -> None:
        item = params.text_document
        ls._loop = asyncio.get_running_loop()
        ls.documents[item.uri] = Document(
            uri=item.uri, text=item.text, version=item.version, settings=ls.settings, encoding=ls.encoding()
        )
        ls.publish(item.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: SleecServer, params: T.DidChangeTextDocumentParams) -> None:
        doc = ls.documents.get(params.text_document.uri)
        if doc is not None:
            doc.apply(params.content_changes, params.text_document.version)
            ls.changed(doc.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_SAVE, T.SaveOptions(include_text=True))
    def did_save(ls: SleecServer, params: T.DidSaveTextDocumentParams) -> None:
        doc = ls.documents.get(params.text_document.uri)
        if doc is None:
            return
        if params.text is not None and params.text != doc.text:
            doc.set_text(params.text, doc.version)
        if doc.uri in ls._pending:
            ls.publish(doc.uri)
        ls.saved(doc.uri)

    @server.feature(T.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: SleecServer, params: T.DidCloseTextDocumentParams) -> None:
        uri = params.text_document.uri
        ls.documents.pop(uri, None)
        handle = ls._pending.pop(uri, None)
        if handle is not None:
            handle.cancel()
        ls.onsave.cancel(uri)
        ls.text_document_publish_diagnostics(T.PublishDiagnosticsParams(uri=uri, diagnostics=[]))

    @server.feature(T.TEXT_DOCUMENT_HOVER)
    def hover(ls: SleecServer, params: T.HoverParams) -> T.Hover | None:
        return ls.answer(lambda: features.hover(ls.document(params.text_document.uri), params.position))

    @server.feature(T.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: SleecServer, params: T.DefinitionParams) -> T.Location | None:
        return ls.answer(lambda: features.definition(ls.document(params.text_document.uri), params.position))

    @server.feature(T.TEXT_DOCUMENT_REFERENCES)
    def references(ls: SleecServer, params: T.ReferenceParams) -> list[T.Location]:
        doc = ls.document(params.text_document.uri)
        return ls.answer(
            lambda: features.references(doc, params.position, params.context.include_declaration)
        )

    @server.feature(T.TEXT_DOCUMENT_COMPLETION, T.CompletionOptions(trigger_characters=["=", "{"]))
    def completion(ls: SleecServer, params: T.CompletionParams) -> T.CompletionList:
        return ls.answer(lambda: features.completion(ls.document(params.text_document.uri), params.position))

    @server.feature(T.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def symbols(ls: SleecServer, params: T.DocumentSymbolParams) -> list[T.DocumentSymbol]:
        return ls.answer(lambda: features.document_symbols(ls.document(params.text_document.uri)))

    @server.feature(T.TEXT_DOCUMENT_FORMATTING)
    def formatting(ls: SleecServer, params: T.DocumentFormattingParams) -> list[T.TextEdit]:
        return ls.answer(lambda: features.formatting(ls.document(params.text_document.uri)))

    @server.feature(
        T.TEXT_DOCUMENT_CODE_ACTION,
        T.CodeActionOptions(code_action_kinds=[T.CodeActionKind.QuickFix, features.FIX_ALL]),
    )
    def code_action(ls: SleecServer, params: T.CodeActionParams) -> list[T.CodeAction]:
        return ls.answer(lambda: features.code_actions(ls.document(params.text_document.uri), params))

    @server.feature(T.TEXT_DOCUMENT_PREPARE_RENAME)
    def prepare_rename(ls: SleecServer, params: T.PrepareRenameParams) -> T.Range | None:
        return ls.answer(
            lambda: features.prepare_rename(ls.document(params.text_document.uri), params.position)
        )

    @server.feature(T.TEXT_DOCUMENT_RENAME)
    def rename(ls: SleecServer, params: T.RenameParams) -> T.WorkspaceEdit:
        doc = ls.document(params.text_document.uri)
        return ls.answer(lambda: features.rename(doc, params.position, params.new_name))

    return server


def serve_stdio(limits: Limits | None = None) -> None:
    """Serve one client over stdin and stdout until it exits, reading within ``limits``.

    Only the protocol may write to stdout: the protocol keeps the real stdout (a copy of
    file descriptor 1), and descriptor 1 and ``sys.stdout`` then point at stderr, so that
    nothing printed by any code in the process (or its children) can corrupt a message.
    """
    logging.basicConfig(
        level=logging.WARNING, stream=sys.stderr, format="cosleec lsp: %(levelname)s: %(message)s"
    )
    # pygls logs a traceback for params of the wrong shape; wire.py answers and logs one line
    logging.getLogger("pygls.protocol.json_rpc").addFilter(_no_deserialize_traceback)
    sys.stdout.flush()
    protocol_fd = os.dup(1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    with os.fdopen(protocol_fd, "wb") as out:
        server = build(limits)
        try:
            server.start_io(sys.stdin.buffer, out)
        finally:
            server.onsave.close()


def _no_deserialize_traceback(record: logging.LogRecord) -> bool:
    """A logging filter: drop pygls's "Unable to deserialize message" and its traceback."""
    return not str(record.msg).startswith("Unable to deserialize message")
