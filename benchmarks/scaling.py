"""How the runtime's costs grow: with the rules loaded and with the obligations outstanding.

Rules (``_rulesets.scaled_rules``: each rule triggered by its own event, each measure read
by ten rules): 100 -> 100,000 loaded (``--quick``: 100, 1,000, 10,000). At each size:

- ``update``: median cost of ``m.update`` flipping one measure (ten rules switch layers);
- ``event``: median cost of one event triggering one rule, from ``m.event`` to its return
  (decision and capability dispatch included; the obligation it starts is fulfilled after
  each sample, not timed); ``events_per_s`` = 1 / the mean of that cost;
- ``build``: seconds to build the Manager from the text (parse + check + compile);
- ``start``: seconds of registering two capabilities and ``m.start()`` (the binding check
  and the analysis of possible conflicts), which every deployment runs once; a size whose
  start would take over two minutes by the smaller sizes' slope is measured no further;
- ``memory``: what the built Manager keeps (``_rulesets.allocated_bytes`` after a
  collection, less before: Python's and malloc's bytes in use).

Obligations: 1,000 rules loaded, plus ``Hold when Go then Owed within 1000000 seconds``
triggered until 10 -> 100,000 obligations are outstanding (``--quick``: to 10,000), none
due; at each level the same ``update`` and ``event`` costs (``update_obl``, ``event_obl``).

The Managers of every size (every level) are built first, then measured in turn, in ten
rounds, so that the machine's noise falls on all sizes alike and not on one.

Each cost is printed at every size with, as its baseline, the cost at the smallest size
(the ratio), and a fitted exponent: the least-squares slope of log(cost) against
log(size). The design promises 0 for update and event costs (they depend on the rules and
obligations an operation touches, not on how many are loaded) and 1 for build time and
memory. Nothing is asserted in CI (timings there are flaky); but this benchmark exits 1,
naming the measure, when a fitted exponent exceeds its promise by more than 0.2.
``--plot FILE.png`` draws the costs against size, log-log (matplotlib: ``pip install
-e '.[bench]'``; ``benchmarks/run`` installs it when asked for a plot).
"""

from __future__ import annotations

import argparse
import importlib.util
import random
import statistics
import sys
import time

from _common import args, loglog_slope, report
from _rulesets import Flipper, manager_build, measures_of, scaled_rules
from cosleec.runtime import Manager, Obligation

TOLERANCE = 0.2
# measure -> (what it is, unit, the exponent the design promises)
MEASURES = {
    "update": ("update flipping one measure, against rules loaded", "us", 0.0),
    "event": ("event triggering one rule, against rules loaded", "us", 0.0),
    "build": ("Manager build, against rules loaded", "s", 1.0),
    "start": ("Manager.start() (binding check, conflict analysis), against rules loaded", "s", 1.0),
    "memory": ("memory kept by the Manager, against rules loaded", "MiB", 1.0),
    "update_obl": ("update flipping one measure, against obligations outstanding", "us", 0.0),
    "event_obl": ("event triggering one rule, against obligations outstanding", "us", 0.0),
}
ROUNDS = 10
START_BUDGET_S = 120.0  # a larger size whose start() projects beyond this is left out (full runs)
HOLD = "event Go event Owed | Hold when Go then Owed within 1000000 seconds"


class Driver:
    """A started Manager with a capability for A and B, and the samples taken on it."""

    def __init__(self, m: Manager, n_rules: int) -> None:
        self.m, self.n_rules = m, n_rules
        self.done = "A"
        self.ev: list[float] = []  # samples taken, seconds
        self.up: list[float] = []
        m.capability("A")(self.implementation)
        m.capability("B")(self.implementation)
        if "Owed" in m.ruleset.responds:  # Hold's response: accepted, never reported done
            m.capability("Owed")(lambda ob, decision: None)
        m.start()
        self.flipper = Flipper(m, measures_of(n_rules))

    def implementation(self, ob: Obligation, decision: object) -> None:
        self.done = ob.event

    def events(self, samples: int, rng: random.Random) -> list[float]:
        """Seconds of ``m.event(E{i})`` for random rules, each obligation fulfilled after (not timed)."""
        m = self.m
        costs = []
        for i in (rng.randrange(self.n_rules) for _ in range(samples)):
            name = f"E{i}"
            t0 = time.perf_counter()
            m.event(name)
            costs.append(time.perf_counter() - t0)
            m.event(self.done)
        return costs

    def sample(self, samples: int, rng: random.Random) -> None:
        self.ev += self.events(samples, rng)
        self.up += self.flipper.run(samples)


def interleaved(drivers: list[Driver], samples: int, rng: random.Random) -> None:
    """``samples`` events and updates on each driver, in ten rounds that take each driver in
    turn: a burst of machine noise hits every size alike, not one of them."""
    for d in drivers:  # warm-up
        d.events(100, rng)
        d.flipper.run(100)
    for _ in range(ROUNDS):
        for d in drivers:
            d.sample(samples // ROUNDS, rng)


def projection(measured: dict[int, float], n: int) -> float:
    """Seconds a cost measured at smaller sizes would reach at ``n``, extrapolated along the
    slope of its last two points (0 when fewer than two)."""
    if len(measured) < 2:
        return 0.0
    (n1, y1), (n2, y2) = list(measured.items())[-2:]
    return y2 * (n / n2) ** loglog_slope([float(n1), float(n2)], [y1, y2])


def median_us(xs: list[float]) -> float:
    return statistics.median(xs) * 1e6


def extend(p: argparse.ArgumentParser) -> None:
    p.add_argument("--plot", metavar="FILE.png", help="draw the costs against size (log-log) with matplotlib")


def main() -> int:
    a = args(__doc__ or "", extend)
    if a.plot and importlib.util.find_spec("matplotlib") is None:
        print("scaling: --plot needs matplotlib: pip install -e '.[bench]'", file=sys.stderr)
        return 2
    rule_sizes = [100, 1_000, 10_000] if a.quick else [100, 1_000, 10_000, 100_000]
    obligation_sizes = [10, 100, 1_000, 10_000] if a.quick else [10, 100, 1_000, 10_000, 100_000]
    samples = 1000 if a.quick else 5000
    rng = random.Random(3)
    series: dict[str, dict[int, float]] = {k: {} for k in MEASURES}
    events_per_s: dict[int, float] = {}
    drivers = []
    not_measured: list[str] = []
    for n in rule_sizes:  # built one after another (build time and memory), then measured in turn
        build_s, m, kept = manager_build(scaled_rules(n), 1)
        series["build"][n] = build_s
        if kept is not None:
            series["memory"][n] = kept / 2**20
        projected = projection(series["start"], n)
        if projected > START_BUDGET_S:
            m.close()
            not_measured.append(
                f"{n:,} rules: Manager.start() would take about {projected:,.0f} s (from the smaller sizes); "
                "their update, event and start costs are not measured"
            )
            break
        t = time.perf_counter()
        drivers.append(Driver(m, n))  # registers two capabilities, then starts the Manager
        series["start"][n] = time.perf_counter() - t
    measured = [d.n_rules for d in drivers]
    interleaved(drivers, samples, rng)
    for n, d in zip(measured, drivers):
        series["event"][n] = median_us(d.ev)
        series["update"][n] = median_us(d.up)
        events_per_s[n] = 1 / statistics.fmean(d.ev)
        d.m.close()
    del drivers
    # obligations outstanding: 1,000 rules and one rule whose obligations are never due, a
    # Manager for each level
    drivers = []
    for level in obligation_sizes:
        _, m, _ = manager_build(scaled_rules(1_000, HOLD), 1)
        d = Driver(m, 1_000)
        for _ in range(level):
            m.event("Go")
        drivers.append(d)
    interleaved(drivers, samples, rng)
    for level, d in zip(obligation_sizes, drivers):
        series["event_obl"][level] = median_us(d.ev)
        series["update_obl"][level] = median_us(d.up)
        outstanding = len(d.m.outstanding())
        d.m.close()
        if outstanding != level:
            raise AssertionError(f"{outstanding} obligations outstanding, {level} expected")
    del drivers
    series = {k: v for k, v in series.items() if len(v) >= 2}  # memory: not measurable without glibc
    exponents = {k: loglog_slope([float(x) for x in v], list(v.values())) for k, v in series.items()}
    exceeded = [k for k, x in exponents.items() if x > MEASURES[k][2] + TOLERANCE]
    rows = []
    for k, (what, unit, promise) in MEASURES.items():
        if k not in series:
            why = "needs glibc's mallinfo2" if k == "memory" else "fewer than two sizes measured"
            rows.append((f"{what} ({unit})", "not measured", why))
            continue
        v = series[k]
        first = next(iter(v.values()))
        fmt = "{:.1f}" if unit == "us" else "{:.3g}"
        at = ", ".join(f"{size:,}: {fmt.format(x)}" for size, x in v.items())
        ratio = list(v.values())[-1] / first
        verdict = "EXCEEDS the promise" if k in exceeded else "within"
        rows.append(
            (
                f"{what} ({unit})",
                f"exponent {exponents[k]:.2f}",
                f"{at}; largest / smallest {ratio:.2f}x; promise {promise:g} (+{TOLERANCE}): {verdict}",
            )
        )
    rows.append(
        (
            "events per second, one rule per event",
            f"{events_per_s[measured[-1]]:,.0f}",
            ", ".join(f"{s:,} rules: {x:,.0f}" for s, x in events_per_s.items()),
        )
    )
    result: dict[str, object] = {
        "benchmark": "scaling",
        "rules": rule_sizes,
        "obligations": obligation_sizes,
        "costs": {
            k: {str(s): round(x, 2 if MEASURES[k][1] == "us" else 3) for s, x in v.items()}
            for k, v in series.items()
        },
        "units": {k: unit for k, (_, unit, _) in MEASURES.items()},
        "exponents": {k: round(x, 2) for k, x in exponents.items()},
        "promised": {k: p for k, (_, _, p) in MEASURES.items()},
        "tolerance": TOLERANCE,
        "exceeded": exceeded,
        "events_per_s": {str(s): round(x) for s, x in events_per_s.items()},
        "events_per_s_largest": round(events_per_s[measured[-1]]),
        "not_measured": not_measured,
        "bytes_per_rule_largest": round(series["memory"][rule_sizes[-1]] * 2**20 / rule_sizes[-1])
        if "memory" in series
        else None,
        "quick": a.quick,
    }
    for k in MEASURES:
        result[f"exponent_{k}"] = round(exponents[k], 2) if k in exponents else None
    if a.plot:
        plot(series, a.plot)
        rows.append(("plot", a.plot, "log-log, one line per measure"))
    for note in not_measured:
        rows.append(("not measured", "-", note))
    report("scaling", rows, result, a.json)
    if exceeded:
        print(
            "scaling: fitted exponent above the design's promise (+0.2): "
            + ", ".join(f"{k} {exponents[k]:.2f} > {MEASURES[k][2]:g}" for k in exceeded),
            file=sys.stderr,
        )
        return 1
    return 0


def plot(series: dict[str, dict[int, float]], path: str) -> None:
    """Two log-log panels: per-operation latency (us) against size; build time and memory against rules."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (lat, grow) = plt.subplots(1, 2, figsize=(12, 5))
    for k, (what, unit, _) in MEASURES.items():
        if k not in series:
            continue
        v = series[k]
        axis = lat if unit == "us" else grow
        axis.plot(list(v), list(v.values()), marker="o", label=f"{what} ({unit})")
    lat.set(
        xscale="log", yscale="log", xlabel="rules loaded / obligations outstanding", ylabel="us per operation"
    )
    lat.set_title("latency against size (promise: flat)")
    spread = [x for k, v in series.items() if MEASURES[k][1] == "us" for x in v.values()]
    if spread:  # at least a decade shown: a flat line must look flat
        low, high = min(spread), max(spread)
        middle = (low * high) ** 0.5
        lat.set_ylim(min(low / 1.5, middle / 4), max(high * 1.5, middle * 4))
    grow.set(xscale="log", yscale="log", xlabel="rules loaded", ylabel="s / MiB")
    grow.set_title("build time and memory (promise: linear)")
    for axis in (lat, grow):
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
