"""Scalability of the CO-SLEEC runtime (peers.md §10).

(a) SLEEC@run.time's grid: 10-60 rules x 2-20 clauses, 50 random condition vectors per
    point. Latency from a context update (the rule's clause conditions) to the obligation
    implementation being invoked: update -> layer switch -> trigger -> decision -> dispatch.
    Each configuration timed was met once before (a warm-up), the context then put back.
    Every timed update flips all the triggered rule's measures (a real change every time).
    Baseline in the same run: the same decision hand-coded as a plain if/elif chain
    (it reads the values it was given; the last clause that holds wins) calling the same
    implementation -- the floor -- over the same samples, right after ours; five passes,
    the least disturbed one counts. ``mean_ratio_to_handcoded_at_60x20``: our mean / the
    hand-coded mean at 60 x 20; ``p99_us_at_60x20``: the bare path's p99 there.
(b) 10,000 rules loaded (``_rulesets.scaled_rules``): the median cost of one measure update
    that touches 10 rules and flips the measure's value (every update switches their
    layers), against the same update with only 100 rules loaded (cost must not depend on
    the rules an update does not touch); and the time to build that Manager from the text
    (parse + check + compile + Manager, best of a few).
    At the largest point, a second baseline in the same run: the same records kept by
    straight-line code (``_floor.Floor``: each step reading the clock under the lock and
    letting time pass first; the values checked and stored, the rule's clause conditions
    evaluated again and its layer switch returned; then the occurrence met with what is in
    force, the trigger's decision, obligation, history and the capability under the rule's
    layer, in the depth guard), over the same updates right after ours:
    ``floor_ratio_at_60x20`` (floor / hand-coded) and ``ratio_to_floor_at_60x20``.
(c) What a deployment pays at 60 x 20, interleaved with the bare path in the same run:
    with one observer (``Manager.subscribe``: every record handed to a consumer), with the
    JSON Lines audit log, and with the audit log and the SQLite journal (every step
    committed with its records before the implementation runs); p99 of the pooled samples,
    and medians as ratios to the bare path.
Targets (issue 16): mean <= 5x the hand-coded floor at 60 x 20; p99 <= 100 us with an
observer, <= 200 us with the audit log (SLEEC@run.time: 6.9 s mean); (b) median <= 30 us;
the 10,000-rule Manager built in <= 1 s.
"""

from __future__ import annotations

import random
import statistics
import sys
import tempfile
import time
from collections import deque

from _common import args, report
from _floor import Floor
from _rulesets import Flipper, grid_rules, manager_build, measures_of, scaled_rules
from cosleec.runtime import Manager, VirtualClock
from cosleec.testing import percentile


def run_point(
    n_rules: int,
    n_clauses: int,
    cases: int,
    rng: random.Random,
    persist: str = "none",
    floor: bool = False,
) -> tuple[list[float], list[float], list[float]]:
    """Latencies of our path, of the hand-coded one and (``floor``) of the same records kept
    by straight-line code (``_floor.Floor``, on its own copy of the context, over the same
    updates right after ours); ``persist``: none, observer (one subscriber that keeps the
    records it hears), audit or journal (the audit log and the journal), written to a fresh
    temporary directory."""
    # what the harness itself keeps -- the cases, the updates and their undoing -- is made
    # before the Manager: building the Manager allocates far past the collector's threshold,
    # so these are old by the timed pass. Made after, they were still young when a collection
    # fell in the pass (with the audit log, in 6 of 500 samples), and it walked the harness's
    # 1,200-entry dicts too: those samples took 160-330 us, the p99
    vectors = [(rng.randrange(n_rules), [rng.random() < 0.3 for _ in range(n_clauses)]) for _ in range(cases)]
    names = {(i, j): f"c{i}_{j}" for i in range(n_rules) for j in range(n_clauses)}
    current = dict.fromkeys(names.values(), False)
    warm_ups = []
    for rule, vec in vectors:  # warm-up: first touch of each configuration
        warm = {names[rule, j]: v for j, v in enumerate(vec)}
        current.update(warm)
        warm_ups.append((rule, warm))
    updates = []
    undo = []
    for rule, _vec in vectors:  # every measure of the rule flips: a real change every time
        flip = {names[rule, j]: not current[names[rule, j]] for j in range(n_clauses)}
        undo.append({n: current[n] for n in flip})
        current.update(flip)
        updates.append((rule, flip))
    tmp = tempfile.TemporaryDirectory()
    durable: dict[str, str] = {}
    if persist in ("audit", "journal"):
        durable["audit"] = f"{tmp.name}/audit.jsonl"
    if persist == "journal":
        durable["journal"] = f"{tmp.name}/state.db"
    m = Manager.from_text(grid_rules(n_rules, n_clauses), clock=VirtualClock(), history=64, **durable)
    if persist == "observer":
        heard: deque[object] = deque(maxlen=1000)
        m.subscribe(heard.append)
    hits: list[float] = []

    def implementation(ob, decision) -> None:  # type: ignore[no-untyped-def]
        hits.append(time.perf_counter())

    m.capability("Act")(implementation)
    m.capability("Alt")(implementation)
    m.start()
    m.update(dict.fromkeys(names.values(), False))
    # the floor is built before the warm-up: what building it allocates is the collector's
    # debt, which the warm-up pays, not the timed pass after it (built just before our pass, it
    # cost ours 3.5 us in mean and 45 us in p99 at 60 x 20)
    low = Floor(m, {"Act": implementation, "Alt": implementation}, own_context=True) if floor else None
    ours: list[float] = []
    base: list[float] = []
    for rule, warm in warm_ups:
        m.update(warm)
        m.event(f"E{rule}")
    # the configurations measured are touched too (the flipped vectors: their clauses' COP
    # frames and plans, made the first time a robot is in them), then the context is put back
    # as it was: ours and the floor, measured after, find them alike (the floor used to find
    # the frames our first touch had just made). Put back by undoing each update, last first:
    # updates the size of the pass's own, where one update of all 1,200 measures left the
    # first sample of every pass the slowest (with the audit log, 2 % of samples: the p99)
    for rule, update in updates:
        m.update(update)
        m.event(f"E{rule}")
    for back in reversed(undo):
        m.update(back)
    if low is not None:
        low.take_context(m)  # the context ours starts from
    for rule, update in updates:
        ran = len(hits)
        t0 = time.perf_counter()
        m.update(update)
        m.event(f"E{rule}")
        if len(hits) != ran + 1:
            raise AssertionError(f"E{rule}: the implementation ran {len(hits) - ran} times, not once")
        ours.append(hits[-1] - t0)
    lows: list[float] = []
    for rule, update in updates if low is not None else ():
        ran = len(hits)
        t0 = time.perf_counter()
        low.update(update)  # type: ignore[union-attr]
        low.trigger(f"E{rule}")  # type: ignore[union-attr]
        if len(hits) != ran + 1:
            raise AssertionError(f"E{rule}: the floor ran {len(hits) - ran} implementations, not one")
        lows.append(hits[-1] - t0)
    # baseline: the same decisions written by hand -- it reads the values it was given, picks
    # the last clause that holds (0: the default response) and calls the same implementation.
    # In its own loops after ours: a collection our allocations make due would otherwise land
    # in it (the hand-coded path allocates next to nothing) and dwarf its mean; 5 passes over
    # the same samples, the least disturbed one counts (one preemption of the process in a
    # sub-microsecond floor would multiply its mean, and flatter our ratio).
    for _ in range(5):
        one = []
        for rule, update in updates:
            t0 = time.perf_counter()
            chosen = 0
            for j in range(n_clauses - 1, -1, -1):
                if update[names[rule, j]]:
                    chosen = j + 1
                    break
            implementation(None, chosen)
            one.append(hits[-1] - t0)
        if not base or sum(one) < sum(base):
            base = one
    m.close()
    tmp.cleanup()
    return ours, base, lows


def jitter_control(median_us: float, samples: int) -> tuple[float, float]:
    """(median, p99) of a plain busy loop calibrated to ``median_us``: the tail any operation
    of that length shows on this machine (VM scheduling, interrupts), whatever it does."""

    def work(n: int) -> int:
        s = 0
        for i in range(n):
            s += i * i
        return s

    n = 100
    while True:  # calibrate the loop length to the measured median
        t0 = time.perf_counter()
        work(n)
        took = (time.perf_counter() - t0) * 1e6
        if took >= median_us:
            break
        n = int(n * max(1.1, median_us / max(took, 0.1)))
    xs = []
    for _ in range(samples):
        t0 = time.perf_counter()
        work(n)
        xs.append((time.perf_counter() - t0) * 1e6)
    return statistics.median(xs), percentile(xs, 99)


def update_costs(sizes: tuple[int, ...], repeats: int, build_repeats: int) -> tuple[dict[int, float], float]:
    """Median seconds of an update that flips one measure read by 10 rules, with each of
    ``sizes`` rules loaded (the Managers measured in turn, ten rounds: noise hits them
    alike), and the best seconds to build the Manager of the first size."""
    build_s, first, _ = manager_build(scaled_rules(sizes[0]), build_repeats)
    managers = [first] + [manager_build(scaled_rules(n), 1)[1] for n in sizes[1:]]
    flippers = [Flipper(m, measures_of(n)) for m, n in zip(managers, sizes)]
    costs: dict[int, list[float]] = {n: [] for n in sizes}
    for f in flippers:
        f.run(200)  # warm-up
    for _ in range(10):
        for f, n in zip(flippers, sizes):
            costs[n] += f.run(repeats // 10)
    for m in managers:
        m.close()
    return {n: statistics.median(v) for n, v in costs.items()}, build_s


def main() -> int:
    a = args(__doc__ or "")
    rng = random.Random(42)
    rules_axis = [10, 60] if a.quick else [10, 20, 30, 40, 50, 60]
    clause_axis = [2, 20] if a.quick else [2, 5, 10, 15, 20]
    cases = 50
    rounds = 3 if a.quick else 10
    grid: dict[str, dict[str, float]] = {}
    rows = []
    means: dict[str, tuple[float, float]] = {}  # point -> (our mean, hand-coded mean), us
    low: list[float] = []  # the floor at the largest point
    for nr in rules_axis:
        for nc in clause_axis:
            ours: list[float] = []
            base: list[float] = []
            top_point = nr == rules_axis[-1] and nc == clause_axis[-1]
            for _ in range(rounds):
                o, b, f = run_point(nr, nc, cases, rng, floor=top_point)
                ours += o
                base += b
                low += f
            us = [x * 1e6 for x in ours]
            base_us = [x * 1e6 for x in base]
            means[f"{nr}x{nc}"] = (statistics.fmean(us), statistics.fmean(base_us))
            point = {
                "mean_us": round(statistics.fmean(us), 1),
                "median_us": round(statistics.median(us), 1),
                "p90_us": round(percentile(us, 90), 1),
                "p99_us": round(percentile(us, 99), 1),
                "baseline_mean_us": round(statistics.fmean(base_us), 2),
                "baseline_p99_us": round(percentile(base_us, 99), 2),
                "mean_ratio_to_handcoded": round(statistics.fmean(us) / statistics.fmean(base_us), 1),
            }
            grid[f"{nr}x{nc}"] = point
            rows.append(
                (
                    f"{nr} rules x {nc} clauses",
                    f"p99 {point['p99_us']:.1f} us",
                    f"mean {point['mean_us']:.1f} = {point['mean_ratio_to_handcoded']}x the hand-coded "
                    f"{point['baseline_mean_us']} us; p90 {point['p90_us']:.1f}",
                )
            )
    nr, nc = rules_axis[-1], clause_axis[-1]
    top = f"{nr}x{nc}"
    last = grid[top]
    mean_ratio = means[top][0] / means[top][1]
    ctl_median, ctl_p99 = jitter_control(last["median_us"], cases * rounds)
    floor_mean = statistics.fmean(low) * 1e6
    rows.append(
        (
            f"{nr} x {nc}: the same records, straight-line",
            f"mean {floor_mean:.1f} us",
            f"{floor_mean / means[top][1]:.1f}x the hand-coded; ours {means[top][0] / floor_mean:.2f}x this floor",
        )
    )
    rows.append(
        (
            "control: busy loop of the same median",
            f"p99 {ctl_p99:.1f} us",
            f"median {ctl_median:.1f} us: this machine's own tail for an operation that long",
        )
    )
    # (c) what a deployment pays at the largest point, interleaved with the bare path (same run)
    kinds = ("none", "observer", "audit", "journal")
    pooled: dict[str, list[float]] = {k: [] for k in kinds}
    for _ in range(rounds):
        for persist in kinds:
            o, _b, _f = run_point(nr, nc, cases, rng, persist)
            pooled[persist] += [x * 1e6 for x in o]
    durable = {k: (statistics.median(v), percentile(v, 99), statistics.fmean(v)) for k, v in pooled.items()}
    for k, label in (
        ("none", "bare (interleaved with the rows below)"),
        ("observer", "with one observer"),
        ("audit", "with the audit log"),
        ("journal", "with audit log and journal"),
    ):
        rows.append(
            (
                f"{nr} x {nc} {label}",
                f"p99 {durable[k][1]:.1f} us",
                f"median {durable[k][0]:.1f} us = {durable[k][0] / durable['none'][0]:.2f}x the bare path",
            )
        )
    repeats = 2000 if a.quick else 20000
    medians, build10k = update_costs((10_000, 100), repeats, 2 if a.quick else 3)
    u10k, u100 = medians[10_000] * 1e6, medians[100] * 1e6
    rows.append(
        (
            "update flipping a measure 10 rules read, 10,000 loaded",
            f"{u10k:.1f} us",
            "median; target <= 30 us",
        )
    )
    rows.append(("same update, 100 rules loaded", f"{u100:.1f} us", f"ratio 10k/100 = {u10k / u100:.2f}"))
    rows.append(
        ("build a Manager from 10,000 rules' text", f"{build10k:.2f} s", "best of a few; target <= 1 s")
    )
    result = {
        "benchmark": "scalability_grid",
        "grid": grid,
        "cases_per_point": cases * rounds,
        "p99_us_at_60x20": last["p99_us"],
        "median_us_at_60x20": last["median_us"],
        "mean_us_at_60x20": last["mean_us"],
        "handcoded_mean_us_at_60x20": round(means[top][1], 2),
        "mean_ratio_to_handcoded_at_60x20": round(mean_ratio, 1),
        "floor_mean_us_at_60x20": round(floor_mean, 1),
        "floor_ratio_at_60x20": round(floor_mean / means[top][1], 1),
        "ratio_to_floor_at_60x20": round(means[top][0] / floor_mean, 2),
        "p99_us_at_60x20_bare": round(durable["none"][1], 1),
        "p99_us_at_60x20_observer": round(durable["observer"][1], 1),
        "p99_us_at_60x20_audit": round(durable["audit"][1], 1),
        "p99_us_at_60x20_journal": round(durable["journal"][1], 1),
        "control_p99_us": round(ctl_p99, 1),
        "p99_over_control": round(last["p99_us"] / ctl_p99, 2),
        "update_flip_median_us_10k_rules": round(u10k, 2),
        "update_flip_median_us_100_rules": round(u100, 2),
        "update_flip_ratio_10k_vs_100": round(u10k / u100, 2),
        "manager_build_s_10k_rules": round(build10k, 3),
        "durable_median_us_at_60x20": {k: round(v[0], 1) for k, v in durable.items()},
        "durable_mean_us_at_60x20": {k: round(v[2], 1) for k, v in durable.items()},
        "durable_p99_us_at_60x20": {k: round(v[1], 1) for k, v in durable.items()},
        "observer_over_bare": round(durable["observer"][0] / durable["none"][0], 2),
        "audit_over_bare": round(durable["audit"][0] / durable["none"][0], 2),
        "journal_over_bare": round(durable["journal"][0] / durable["none"][0], 2),
        "targets": {
            "mean_ratio_to_handcoded_at_60x20": 5,
            "p99_us_at_60x20_observer": 100,
            "p99_us_at_60x20_audit": 200,
            "update_flip_median_us_10k_rules": 30,
            "manager_build_s_10k_rules": 1.0,
        },
        "sleec_at_runtime_mean_s_at_60x20": 6.9,
        "quick": a.quick,
    }
    report("scalability_grid", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
