"""``cosleec analyse`` on save: z3 in a process of its own, stopped when it takes too long.

The analysis of a rule file can take seconds to minutes (every check is a solver question),
far longer than an editor may wait and longer than a thread could be stopped. Each save
starts a fresh process (``spawn``: nothing of the server's threads is copied) that checks
the text, analyses it when it checks clean, and sends back the findings as diagnostics; a
newer save of the same file, closing it, or the time limit kills it. The process never
writes to the protocol's stdout: the server moved that away from file descriptor 1 before
it started (``serve_stdio``), and the child points its own 1 at stderr too.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess

from cosleec.analysis import Settings as AnalysisSettings
from cosleec.analysis import analyse_spec
from cosleec.lang import Diagnostic, Options, Severity, analyse
from cosleec.lang import ast as A


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """What one analysis came to: its findings as diagnostics, or why there are none."""

    text: str  # the text analysed
    diagnostics: tuple[Diagnostic, ...] = ()
    timed_out: bool = False
    cancelled: bool = False
    failed: str = ""  # the analysis's own failure (a bug to report), if any


Done = Callable[[str, Outcome], None]
"""Called with the document's URI and the outcome, on the runner's watcher thread."""


class OnSave:
    """Runs at most one analysis per document; :meth:`start` replaces a running one."""

    def __init__(self, done: Done) -> None:
        self._done = done
        self._running: dict[str, BaseProcess] = {}
        self._lock = threading.Lock()

    def start(
        self,
        uri: str,
        text: str,
        path: str,
        *,
        options: Options,
        dialect: str,
        timeout: float,
        legos_compat: bool,
    ) -> None:
        """Analyse ``text`` in a new process; the outcome goes to ``done`` (not when cancelled
        by a newer start)."""
        ctx = multiprocessing.get_context("spawn")
        receive, send = ctx.Pipe(duplex=False)
        process = ctx.Process(
            target=_analyse, args=(send, text, path, options, dialect, legos_compat), daemon=True
        )
        with self._lock:
            self._kill(uri)
            process.start()
            self._running[uri] = process
        send.close()
        threading.Thread(
            target=self._watch,
            args=(uri, text, process, receive, timeout),
            name=f"cosleec-analyse {path}",
            daemon=True,
        ).start()

    def cancel(self, uri: str) -> None:
        """Stop the analysis of ``uri``, if one runs (its outcome is dropped)."""
        with self._lock:
            self._kill(uri)

    def close(self) -> None:
        """Stop every analysis (the server is shutting down)."""
        with self._lock:
            for uri in list(self._running):
                self._kill(uri)

    def _kill(self, uri: str) -> None:
        process = self._running.pop(uri, None)
        if process is not None and process.is_alive():
            process.kill()

    def _watch(self, uri: str, text: str, process: BaseProcess, receive: Connection, timeout: float) -> None:
        outcome: Outcome
        try:
            if receive.poll(timeout):
                diagnostics, failed = receive.recv()
                outcome = Outcome(text=text, diagnostics=tuple(diagnostics), failed=failed)
            else:
                outcome = Outcome(text=text, timed_out=True)
        except (EOFError, OSError):  # killed: by a newer save, a close, or the shutdown
            outcome = Outcome(text=text, cancelled=True)
        finally:
            receive.close()
        with self._lock:
            current = self._running.get(uri) is process
            if current:
                self._kill(uri)
        process.join(5)
        if current and not outcome.cancelled:
            self._done(uri, outcome)


def timeout_note(seconds: float, path: str) -> Diagnostic:
    """What the editor shows when the analysis did not finish in time."""
    return Diagnostic(
        severity=Severity.NOTE,
        code="analysis-timeout",
        message=f"cosleec analyse did not finish within {seconds:g} s, so its findings are not shown",
        span=A.Span(1, 1, 1, 1),
        path=path,
        hint=f"run `cosleec analyse {path}` in a terminal, or raise analysisTimeout",
    )


def _analyse(
    send: Connection, text: str, path: str, options: Options, dialect: str, legos_compat: bool
) -> None:  # pragma: no cover - runs in the child process (the LSP test drives it)
    """The child's work: check, then analyse as ``cosleec analyse`` does; send the findings."""
    os.dup2(2, 1)  # whatever is printed goes to stderr, never to a protocol
    try:
        result = analyse(text, path, dialect=dialect, options=options, legos_compat=legos_compat)
        found: list[Diagnostic] = []
        if result.ok and result.spec is not None and result.symbols is not None:
            findings, _ = analyse_spec(
                result.spec,
                dict(result.symbols.constant_values),
                AnalysisSettings(semantics=options.semantics),
            )
            found = [f.diagnostic() for f in findings]
        send.send((found, ""))
    except Exception as e:  # a bug of the analysis: said once, in the editor, not a crash
        send.send(([], f"{type(e).__name__}: {e}"))
    finally:
        send.close()
