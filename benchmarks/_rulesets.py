"""Rule sets the benchmarks load, and the measurements several of them share.

``scaled_rules(n)``: ``n`` rules, each triggered by its own event ``E{i}``, each with one
clause over a boolean measure ``s{i // 10}`` (every measure is read by ten rules), obliging
``A`` (default) or ``B`` (the clause) within a minute. An update of one measure therefore
touches ten rules whatever ``n`` is, and one event triggers one rule: what
``scalability_grid``, ``manager_build`` and ``scaling`` load, so that their figures agree.

``grid_rules(r, c)``: SLEEC@run.time's grid -- ``r`` rules ``R{i} when E{i} then Act``, each
with ``c`` clauses ``unless c{i}_{j} then Alt within j+1 seconds`` over its own measures.
"""

from __future__ import annotations

import ctypes
import gc
import os
import sys
import tempfile
import time
from typing import Any

from cosleec.lang import analyse
from cosleec.runtime import Manager, VirtualClock

FANOUT = 10  # rules that read each measure


def scaled_rules(n_rules: int, extra: str = "") -> str:
    """``extra``: more declarations and rules (``"event Go ... | Hold when Go then ..."``)."""
    declared, _, more = extra.partition("|")
    shared = max(1, n_rules // FANOUT)
    events = " ".join(f"event E{i}" for i in range(n_rules))
    measures = " ".join(f"measure s{k} : boolean" for k in range(shared))
    rules = " ".join(
        f"R{i} when E{i} then A within 60 seconds unless s{i // FANOUT % shared} then B within 60 seconds"
        for i in range(n_rules)
    )
    return (
        f"def_start {events} event A event B {measures} {declared} def_end rule_start {rules} {more} rule_end"
    )


def grid_rules(n_rules: int, n_clauses: int) -> str:
    events = [f"event E{i}" for i in range(n_rules)] + ["event Act", "event Alt"]
    measures = [f"measure c{i}_{j} : boolean" for i in range(n_rules) for j in range(n_clauses)]
    rules = []
    for i in range(n_rules):
        clauses = " ".join(f"unless c{i}_{j} then Alt within {j + 1} seconds" for j in range(n_clauses))
        rules.append(f"R{i} when E{i} then Act within 60 seconds {clauses}")
    return f"def_start {' '.join(events)} {' '.join(measures)} def_end rule_start {' '.join(rules)} rule_end"


def measures_of(n_rules: int) -> int:
    return max(1, n_rules // FANOUT)


def parse_check_s(text: str) -> float:
    """Wall time of ``analyse(text)`` (parse + check: a build's baseline), after a full
    collection (not timed)."""
    gc.collect()
    t = time.perf_counter()
    analyse(text, "<bench>")
    return time.perf_counter() - t


def manager_build(text: str, repeats: int) -> tuple[float, Manager, int | None]:
    """Best wall time of ``Manager.from_text(text)`` (parse + check + compile + Manager), each
    build after a full collection (not timed); the last Manager built (not started); and
    the bytes it keeps (:func:`allocated_bytes` after a collection, less before; None
    where that cannot be measured)."""
    best = float("inf")
    m: Manager | None = None
    kept: int | None = None
    for _ in range(repeats):
        if m is not None:
            m.close()
            m = None
        gc.collect()
        before = allocated_bytes()
        t = time.perf_counter()
        m = Manager.from_text(text, clock=VirtualClock())
        best = min(best, time.perf_counter() - t)
        gc.collect()
        after = allocated_bytes()
        kept = None if before is None or after is None else after - before
    assert m is not None
    return best, m, kept


class _MallInfo2(ctypes.Structure):
    _fields_ = [
        (n, ctypes.c_size_t)
        for n in (
            "arena",
            "ordblks",
            "smblks",
            "hblks",
            "hblkhd",
            "usmblks",
            "fsmblks",
            "uordblks",
            "fordblks",
            "keepcost",
        )
    ]


def _mallinfo2() -> Any:
    try:
        fn = ctypes.CDLL("libc.so.6").mallinfo2
    except (OSError, AttributeError):
        return None
    fn.restype = _MallInfo2
    return fn


_MALLINFO2 = _mallinfo2()


def allocated_bytes() -> int | None:
    """Bytes this process has allocated and not freed: Python's small-object allocator's
    blocks in use (``sys._debugmallocstats``) plus glibc malloc's bytes in use (``mallinfo2``:
    large objects, C allocations). Exact, whatever freed memory gets reused; allocator
    overhead (free space in pools and arenas) is not counted. None without glibc >= 2.33."""
    if _MALLINFO2 is None:
        return None
    saved = os.dup(2)
    with tempfile.TemporaryFile() as f:
        os.dup2(f.fileno(), 2)  # _debugmallocstats writes to the C stderr
        try:
            sys._debugmallocstats()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        f.seek(0)
        stats = f.read().decode(errors="replace")
    small = next(
        int(line.split("=")[1].replace(",", ""))
        for line in stats.splitlines()
        if line.startswith("# bytes in allocated blocks")
    )
    mi = _MALLINFO2()
    return small + mi.uordblks + mi.hblkhd


class Flipper:
    """Updates of ``m`` that flip one measure each, ``s{k}`` with k cycling over the measures
    (so every update switches the layers of the rules that read it); successive calls of
    :meth:`run` go on where the last one stopped."""

    def __init__(self, m: Manager, shared: int) -> None:
        self.m = m
        self.names = [f"s{k}" for k in range(shared)]
        self.state = [False] * shared
        m.update(dict.fromkeys(self.names, False))
        self.next = 0

    def run(self, repeats: int) -> list[float]:
        """Seconds of each of ``repeats`` updates. Raises when one switched no layer: the
        figure would be of a no-op."""
        m, names, state = self.m, self.names, self.state
        costs, switched = [], []
        for _ in range(repeats):
            k = self.next
            self.next = (k + 1) % len(names)
            state[k] = not state[k]
            update = {names[k]: state[k]}
            t0 = time.perf_counter()
            switches = m.update(update)
            costs.append(time.perf_counter() - t0)
            switched.append(len(switches))
        if switched and min(switched) == 0:
            raise AssertionError("an update switched no layer: the benchmark measures no change")
        return costs
