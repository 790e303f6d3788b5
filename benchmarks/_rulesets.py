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

import gc
import statistics
import time
import tracemalloc
from collections.abc import Callable

from cosleec.lang import analyse
from cosleec.runtime import Manager, RuleSet, VirtualClock

FANOUT = 10  # rules that read each measure


def scaled_rules(n_rules: int) -> str:
    shared = max(1, n_rules // FANOUT)
    events = " ".join(f"event E{i}" for i in range(n_rules))
    measures = " ".join(f"measure s{k} : boolean" for k in range(shared))
    rules = " ".join(
        f"R{i} when E{i} then A within 60 seconds unless s{i // FANOUT % shared} then B within 60 seconds"
        for i in range(n_rules)
    )
    return f"def_start {events} event A event B {measures} def_end rule_start {rules} rule_end"


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


def build_times(text: str, repeats: int) -> dict[str, float]:
    """Best wall time of each phase of building a Manager from ``text``: ``parse_check``
    (``analyse``: the baseline), ``ruleset`` (parse + check + compile) and ``manager``
    (all of it, ``Manager.from_text``), each after a full collection (not timed)."""
    fns: dict[str, Callable[[], object]] = {
        "parse_check": lambda: analyse(text, "<bench>"),
        "ruleset": lambda: RuleSet.from_text(text),
        "manager": lambda: Manager.from_text(text, clock=VirtualClock()),
    }
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeats):
        for name, fn in fns.items():
            gc.collect()
            t = time.perf_counter()
            built = fn()
            best[name] = min(best[name], time.perf_counter() - t)
            del built
    return best


def manager_build(text: str, repeats: int) -> tuple[float, Manager]:
    """Best wall time of ``Manager.from_text(text)`` (parse + check + compile + Manager), each
    build after a full collection (not timed), and the last Manager built (not started)."""
    best = float("inf")
    m: Manager | None = None
    for _ in range(repeats):
        if m is not None:
            m.close()
            m = None
        gc.collect()
        t = time.perf_counter()
        m = Manager.from_text(text, clock=VirtualClock())
        best = min(best, time.perf_counter() - t)
    assert m is not None
    return best, m


def retained_bytes(text: str) -> int:
    """Bytes a Manager built from ``text`` keeps allocated (tracemalloc: Python allocations
    still live once it is built and the garbage collected; the text itself not counted)."""
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        m = Manager.from_text(text, clock=VirtualClock())
        gc.collect()
        after = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    m.close()
    return after - before


def update_flips(m: Manager, shared: int, repeats: int) -> list[float]:
    """Seconds per ``m.update({s{k}: v})``, k cycling over the measures, each update flipping
    the measure it sets (so every update switches the layers of the rules that read it).

    Raises when an update switched no layer: the figure would be of a no-op."""
    state = [False] * shared
    m.update({f"s{k}": False for k in range(shared)})
    costs, switched = [], []
    names = [f"s{k}" for k in range(shared)]
    for r in range(repeats):
        k = r % shared
        state[k] = not state[k]
        update = {names[k]: state[k]}
        t0 = time.perf_counter()
        switches = m.update(update)
        costs.append(time.perf_counter() - t0)
        switched.append(len(switches))
    if min(switched) == 0:
        raise AssertionError("an update switched no layer: the benchmark measures no change")
    return costs


def median_us(xs: list[float]) -> float:
    return statistics.median(xs) * 1e6
