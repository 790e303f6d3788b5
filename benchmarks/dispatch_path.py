"""The runtime's trigger -> decision -> capability path, against the same decision by hand.

A started Manager with SLEEC@run.time's 60 rules x 5 clauses (``_rulesets.grid_rules``) and
a capability registered for each response event. Before each sample (not timed) the
triggered rule's context changes: one of its measures flips, so the decision is not the
one made last time. Timed: from ``m.event("E{i}")`` to the capability implementation being
invoked (``to_capability``), and to ``m.event`` returning (``to_return``: what the caller
waits). After each sample (not timed) the robot reports the response, fulfilling the
obligation, so that nothing piles up in the tracker.

Baseline, in the same run (rounds interleaved; each round's hand-coded loop runs after our
loop over the same samples, so that a collection our allocations make due does not land in
it): the application written by hand -- a dict from trigger to rule, the context as a
dict, the clauses read last to first, the first that holds chosen (0: the default), the
same implementation called. The hand-coded loop runs 5 times over each round's samples and
the least disturbed pass counts: at well under a microsecond a sample, one preemption of
the process would otherwise multiply its mean, and flatter the ratio. ``ratio_*``: ours /
hand-coded, mean, median and p99.

The floor of the data model, in the same run (``floor_*``): the records a trigger keeps --
its decision (``Decision.at_trigger``), its obligation (a ``Tracked``, indexed by event and
deadline), the history -- and what runs it -- a lock, the re-check before the action
starts, the outcome's collector, the rule's layer active around the capability, the
outcome -- written as straight-line code over the Manager's own compiled rules and Layer
Manager, with none of the runtime's parts. Timed like ours, on records of its own, each
sample right after ours (on the same context). ``floor_ratio_mean``: floor / hand-coded
(what keeping these records costs at best in CPython); ``ratio_to_floor_mean``: ours /
floor (what the runtime's parts add).
"""

from __future__ import annotations

import random
import statistics
import sys
import time

from _common import args, report
from _floor import Floor
from _rulesets import grid_rules
from cosleec.runtime import Manager, Obligation, VirtualClock
from cosleec.testing import percentile

RULES, CLAUSES = 60, 5
PASSES = 5  # of the hand-coded loop over each round's samples: the least disturbed one counts


class Path:
    """The Manager, its capability, the hand-coded application, and the context both read."""

    def __init__(self) -> None:
        self.hits: list[float] = []
        self.done = "Act"  # the response event the last implementation call performed
        self.m = Manager.from_text(grid_rules(RULES, CLAUSES), clock=VirtualClock(), history=64)
        self.m.capability("Act")(self.implementation)
        self.m.capability("Alt")(self.implementation)
        self.m.start()
        self.current = {f"c{i}_{j}": False for i in range(RULES) for j in range(CLAUSES)}
        self.m.update(self.current)
        self.values = dict(self.current)  # the hand-coded application's own context
        self.by_trigger = {f"E{i}": [f"c{i}_{j}" for j in range(CLAUSES)] for i in range(RULES)}
        self.floor = Floor(self.m, {"Act": self.implementation, "Alt": self.implementation})

    def implementation(self, ob: Obligation | None, decision: object) -> None:
        self.hits.append(time.perf_counter())
        self.done = "Act" if ob is None else ob.event

    def round(
        self, samples: int, rng: random.Random
    ) -> tuple[list[float], list[float], list[float], list[float]]:
        """(to capability, to return, hand-coded, floor) seconds for ``samples`` triggers."""
        plan = [
            (f"E{r}", f"c{r}_{rng.randrange(CLAUSES)}")
            for r in (rng.randrange(RULES) for _ in range(samples))
        ]
        m, hits, floor = self.m, self.hits, self.floor
        ours, back, lows = [], [], []
        for event, name in plan:
            self.current[name] = not self.current[name]
            m.update({name: self.current[name]})
            ran = len(hits)
            t0 = time.perf_counter()
            m.event(event)
            t1 = time.perf_counter()
            if len(hits) != ran + 1:
                raise AssertionError(f"{event}: the capability ran {len(hits) - ran} times, not once")
            ours.append(hits[-1] - t0)
            back.append(t1 - t0)
            m.event(self.done)  # the robot did it: the obligation is fulfilled (not timed)
            t0 = time.perf_counter()
            floor.trigger(event)  # the same decision on the same context, straight through
            if len(hits) != ran + 2:
                raise AssertionError(f"{event}: the floor ran {len(hits) - ran - 1} capabilities, not one")
            lows.append(hits[-1] - t0)
            floor.fulfilled()
        values, by_trigger, implementation = self.values, self.by_trigger, self.implementation
        start = dict(values)
        best: list[float] = []
        for _ in range(PASSES):  # the same triggers after the same context changes, by hand
            values.clear()
            values.update(start)
            base = []
            for event, name in plan:
                values[name] = not values[name]
                t0 = time.perf_counter()
                clauses = by_trigger[event]
                chosen = 0
                for j in range(CLAUSES - 1, -1, -1):
                    if values[clauses[j]]:
                        chosen = j + 1
                        break
                implementation(None, chosen)
                base.append(hits[-1] - t0)
            if not best or sum(base) < sum(best):
                best = base
        del hits[:-1]
        return ours, back, best, lows


def main() -> int:
    a = args(__doc__ or "")
    rounds, samples = (20, 500) if a.quick else (50, 1000)
    rng = random.Random(7)
    path = Path()
    path.round(samples, rng)  # warm-up
    ours: list[float] = []
    back: list[float] = []
    base: list[float] = []
    low: list[float] = []
    for _ in range(rounds):
        o, r, b, f = path.round(samples, rng)
        ours += o
        back += r
        base += b
        low += f
    outstanding = len(path.m.outstanding())
    path.m.close()
    us = {
        k: [x * 1e6 for x in v] for k, v in (("ours", ours), ("back", back), ("base", base), ("floor", low))
    }

    def stats(xs: list[float]) -> tuple[float, float, float]:
        return statistics.fmean(xs), statistics.median(xs), percentile(xs, 99)

    o_mean, o_med, o_p99 = stats(us["ours"])
    r_mean, r_med, r_p99 = stats(us["back"])
    b_mean, b_med, b_p99 = stats(us["base"])
    f_mean, f_med, _ = stats(us["floor"])
    result = {
        "benchmark": "dispatch_path",
        "rules": RULES,
        "clauses": CLAUSES,
        "samples": len(ours),
        "mean_us": round(o_mean, 2),
        "median_us": round(o_med, 2),
        "p99_us": round(o_p99, 1),
        "return_mean_us": round(r_mean, 2),
        "return_median_us": round(r_med, 2),
        "return_p99_us": round(r_p99, 1),
        "handcoded_mean_us": round(b_mean, 3),
        "handcoded_median_us": round(b_med, 3),
        "handcoded_p99_us": round(b_p99, 3),
        "ratio_mean": round(o_mean / b_mean, 1),
        "ratio_median": round(o_med / b_med, 1),
        "ratio_p99": round(o_p99 / b_p99, 1),
        "floor_mean_us": round(f_mean, 2),
        "floor_median_us": round(f_med, 2),
        "floor_ratio_mean": round(f_mean / b_mean, 1),
        "ratio_to_floor_mean": round(o_mean / f_mean, 2),
        "outstanding_after": outstanding,
        "quick": a.quick,
    }
    rows = [
        ("trigger -> capability invoked", f"mean {o_mean:.1f} us", f"median {o_med:.1f}, p99 {o_p99:.1f} us"),
        ("trigger -> m.event returns", f"mean {r_mean:.1f} us", f"median {r_med:.1f}, p99 {r_p99:.1f} us"),
        ("hand-coded if/elif + call", f"mean {b_mean:.2f} us", f"median {b_med:.2f}, p99 {b_p99:.2f} us"),
        (
            "ours / hand-coded",
            f"mean {o_mean / b_mean:.1f}x",
            f"median {o_med / b_med:.1f}x, p99 {o_p99 / b_p99:.1f}x",
        ),
        (
            "the same records, straight-line",
            f"mean {f_mean:.1f} us",
            f"{f_mean / b_mean:.1f}x hand-coded; ours {o_mean / f_mean:.2f}x this floor",
        ),
        ("samples", f"{len(ours)}", f"{RULES} rules x {CLAUSES} clauses; obligations left: {outstanding}"),
    ]
    report("dispatch_path", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
