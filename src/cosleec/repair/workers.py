"""Repairing a file's findings side by side: one process per core, each repairing whole
findings.

Each finding's repair is independent of the others' (its candidates are verified against the
original file), so the findings are shared out among worker processes and the results put
back in the analysis' order; the patch set is then built in the calling process. Workers
are started fresh (``spawn``): a process that has used the solver is never forked. Each
reads and analyses the file once itself -- the analysis is deterministic, and a worker
that finds other findings than the caller refuses to go on -- and sends back plain records.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

from cosleec.analysis import Finding
from cosleec.lang import CheckResult
from cosleec.repair.fixes import Repairs
from cosleec.repair.repairing import Budget, repairs_of
from cosleec.repair.verify import Reading, key

_State = tuple[str, Reading, CheckResult, list[Finding]]
_state: _State | None = None  # what a worker read, once (set by _start)


def _start(source: str, reading: Reading) -> None:
    """A worker's start: check and analyse the file, as the caller did."""
    global _state
    checked = reading.check(source)
    found, _, _ = reading.analyse(checked)
    _state = (source, reading, checked, found)


def _repair(i: int, expected: tuple[str, str], budget: Budget) -> Repairs:
    """Repair finding ``i`` (``expected`` names it: a mismatch is a bug, never a guess)."""
    assert _state is not None
    source, reading, checked, found = _state
    if i >= len(found) or key(found[i]) != expected:
        raise RuntimeError(f"worker's analysis differs from the caller's at finding {i} ({expected})")
    r = repairs_of(found[i], source, checked, found, reading, budget)
    # the patched texts' check results stay here: they are rebuilt where needed
    r.fixes = [dataclasses.replace(f, verdict=dataclasses.replace(f.verdict, checked=None)) for f in r.fixes]
    return r


def in_parallel(
    source: str, reading: Reading, found: list[Finding], budget: Budget, workers: int
) -> list[Repairs]:
    """Each finding of ``found`` repaired, by ``workers`` processes, in ``found``'s order."""
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        workers, mp_context=context, initializer=_start, initargs=(source, reading)
    ) as pool:
        jobs = [pool.submit(_repair, i, key(f), budget) for i, f in enumerate(found)]
        out = [j.result() for j in jobs]
    for mine, theirs in zip(found, out, strict=True):
        theirs.finding = mine  # the caller's own record (equal, and the one its report holds)
    return out


__all__ = ["in_parallel"]
