"""``cosleec analyse`` on save, then its repairs: z3 in a process of its own, stopped when it
takes too long.

The analysis of a rule file can take seconds to minutes (every check is a solver question),
far longer than an editor may wait and longer than a thread could be stopped. Each save
starts a fresh process (``spawn``: nothing of the server's threads is copied) that checks
the text, analyses it when it checks clean, and sends back the findings as diagnostics;
then, when asked, it looks for their verified repairs (:func:`cosleec.repair.repair_text`)
and sends those as a second message, so the findings are shown without waiting for the
repairs, which take longer. A newer save of the same file, closing it, or the time limit
(for both together) kills it; the repairs get a deadline short of that limit, so that they
usually end with the fixes found so far rather than be killed. The process never writes
to the protocol's stdout: the server moved that away from file descriptor 1 before it
started (``serve_stdio``), and the child points its own 1 at stderr too.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess

from cosleec.analysis import Deadline, analyse_spec
from cosleec.analysis import Settings as AnalysisSettings
from cosleec.lang import Diagnostic, Options, Severity, analyse
from cosleec.lang import ast as A
from cosleec.lsp.fixes import Repaired, repaired
from cosleec.repair import Budget, Reading, repair_text

REPAIR_SHARE = 0.8
"""The share of the time limit (counted from the save) after which the repairs stop looking
for more fixes: what is left is for combining those found into the patch set."""


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """What one analysis came to: its findings as diagnostics, or why there are none; or,
    in a second outcome of the same save, the repairs of those findings (``repairs``)."""

    text: str  # the text analysed
    diagnostics: tuple[Diagnostic, ...] = ()
    timed_out: bool = False
    cancelled: bool = False
    failed: str = ""  # the analysis's (or the repairs') own failure (a bug to report), if any
    of_repairs: bool = False  # the second outcome of a save: its findings' repairs
    repairs: Repaired | None = None  # what the repairs found (None when they failed)


Done = Callable[[str, Outcome], None]
"""Called with the document's URI and the outcome, on the runner's watcher thread."""


@dataclass(frozen=True)
class _Job:
    """What the child is asked to do (picklable: it crosses to the new process)."""

    text: str
    path: str
    options: Options
    dialect: str
    legos_compat: bool
    infer_defs: bool
    repair_until: float | None  # wall-clock time the repairs stop at; None: no repairs


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
        infer_defs: bool = False,
        repair: bool = False,
    ) -> None:
        """Analyse ``text`` in a new process (and with ``repair``, repair its findings); the
        outcomes go to ``done`` (not when cancelled by a newer start)."""
        ctx = multiprocessing.get_context("spawn")
        receive, send = ctx.Pipe(duplex=False)
        until = time.time() + timeout * REPAIR_SHARE if repair else None
        job = _Job(text, path, options, dialect, legos_compat, infer_defs, until)
        process = ctx.Process(target=_analyse, args=(send, job), daemon=True)
        with self._lock:
            self._kill(uri)
            process.start()
            self._running[uri] = process
        send.close()
        threading.Thread(
            target=self._watch,
            args=(uri, text, process, receive, time.monotonic() + timeout),
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

    def _current(self, uri: str, process: BaseProcess) -> bool:
        with self._lock:
            return self._running.get(uri) is process

    def _watch(self, uri: str, text: str, process: BaseProcess, receive: Connection, until: float) -> None:
        """Hand each message of the child to ``done`` while it is the document's current
        analysis: the findings (or that they timed out), then the repairs if asked for.
        Repairs past the time limit are dropped: their findings are already shown."""
        first = True
        try:
            while True:
                if not receive.poll(max(0.0, until - time.monotonic())):
                    if first:
                        self._deliver(uri, process, Outcome(text=text, timed_out=True))
                    break
                of_repairs, diagnostics, failed, fixes = receive.recv()
                outcome = Outcome(
                    text=text,
                    diagnostics=tuple(diagnostics),
                    failed=failed,
                    of_repairs=of_repairs,
                    repairs=fixes,
                )
                self._deliver(uri, process, outcome)
                first = False
        except (EOFError, OSError):  # the child is done, or killed: by a newer save, a close, the shutdown
            pass
        finally:
            receive.close()
        with self._lock:
            if self._running.get(uri) is process:
                self._kill(uri)
        process.join(5)

    def _deliver(self, uri: str, process: BaseProcess, outcome: Outcome) -> None:
        if self._current(uri, process):
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


def _analyse(send: Connection, job: _Job) -> None:  # pragma: no cover - runs in the child process
    """The child's work: check, then analyse as ``cosleec analyse`` does and send the
    findings; then, when asked and there are findings, repair them and send the repairs."""
    os.dup2(2, 1)  # whatever is printed goes to stderr, never to a protocol
    settings = AnalysisSettings(semantics=job.options.semantics)
    try:
        result = analyse(
            job.text,
            job.path,
            dialect=job.dialect,
            options=job.options,
            legos_compat=job.legos_compat,
            infer_defs=job.infer_defs,
        )
        found: list[Diagnostic] = []
        if result.ok and result.spec is not None and result.symbols is not None:
            findings, _ = analyse_spec(result.spec, dict(result.symbols.constant_values), settings)
            found = [f.diagnostic() for f in findings]
        send.send((False, found, "", None))
    except Exception as e:  # a bug of the analysis: said once, in the editor, not a crash
        send.send((False, [], f"{type(e).__name__}: {e}", None))
        found = []
    try:
        if found and job.repair_until is not None:
            reading = Reading(job.path, settings, job.legos_compat, job.infer_defs)
            budget = Budget(deadline=Deadline.after(job.repair_until - time.time()))
            send.send((True, [], "", repaired(repair_text(job.text, reading, budget))))
    except Exception as e:  # a bug of the repairs: the findings stay, the fixes are not offered
        send.send((True, [], f"{type(e).__name__}: {e}", None))
    finally:
        send.close()
