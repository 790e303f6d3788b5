"""COP dispatch overhead, as the COP semantics' performance section measures it.

Ratio = time of a call to a layered function / time of a plain call of its base, both in
this process, best of N timeit repeats; only ratios of one run are comparable. B-min:
``return x + 1`` (the stress case). B-rule: builds a small frozen, slotted obligation
record (what a SLEEC base does). Layers are pass-through ``around`` partials.

Each dispatcher (``reference``, the readable one; ``fast``, the generated default) is
measured two ways: called directly (``fn(arg)`` as a ``timeit`` statement on both sides, no
wrapper: the overhead as a caller sees it -- the headline ``ratio_no_layer``,
``ratio_one_layer``, ``ratio_ten_layers``: the default dispatcher, B-min), and through a
``lambda`` on both sides (``timeit``'s callable form, as runs before issue 16 did: the
lambda's own cost dilutes the ratio; kept under ``lambda`` for comparison).
Targets (issue 16): <= 2x with no layer active, <= 4x with one, and no worse than linear
in the active layers (``ten_over_one_layer`` <= 10). ``runtime_*``: the SLEEC runtime's pattern -- a rule's function dispatched under
``run_with(Snapshot(<the active clause layers of 60 rules>))``, the snapshot kept or built
anew for each call -- against a plain B-rule call. contextpy3 is measured on B-min when
it is installed.
"""

from __future__ import annotations

import random
import sys
import timeit
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any

from _common import args, report
from _cop_cases import DISPATCHERS, LAYERS, RULES, plain_min, plain_rule
from cosleec.cop import Snapshot, activate, active_layers, run_with
from cosleec.cop.decorate import FAST_BY_DEFAULT

# layered / plain, at most: issue 32's for B-min (0, 1, 10 layers), issue 16's for B-rule
TARGETS = {"min_0": 2.5, "min_1": 5.0, "min_10": 30.0, "rule_0": 1.2, "rule_1": 1.5}
DEFAULT = "fast" if FAST_BY_DEFAULT else "reference"


def per_call(fn: Callable[..., Any], arg: object, direct: bool, number: int) -> float:
    """ns per call of one timing run: ``fn(arg)`` as a statement, or through a lambda."""
    if direct:
        t = timeit.timeit("fn(arg)", globals={"fn": fn, "arg": arg}, number=number)
    else:
        t = timeit.timeit(lambda: fn(arg), number=number)
    return t / number * 1e9


class Timing:
    """Best-of timings, every layered sample taken right after a plain one (a noisy machine
    slows both alike), so that the ratios of one run compare like with like."""

    def __init__(self, direct: bool, number: int, repeat: int) -> None:
        self.direct, self.number, self.repeat = direct, number, repeat
        self.plain: dict[str, float] = {"min": float("inf"), "rule": float("inf")}

    def ratio(self, kind: str, fn: Callable[..., Any], layers: int = 0) -> float:
        base, arg = (plain_min, 1) if kind == "min" else (plain_rule, "E")
        best = float("inf")
        with ExitStack() as stack:
            for la in LAYERS[:layers]:
                stack.enter_context(activate(la))
            assert len(active_layers()) == layers
            for _ in range(self.repeat):
                self.plain[kind] = min(self.plain[kind], per_call(base, arg, self.direct, self.number))
                best = min(best, per_call(fn, arg, self.direct, self.number))
        return best / self.plain[kind]


def ratios(direct: bool, number: int, repeat: int) -> dict[str, dict[str, float]]:
    timing = Timing(direct, number, repeat)
    out: dict[str, dict[str, float]] = {}
    for name, (lmin, lrule) in DISPATCHERS.items():
        out[name] = {}
        for n in (0, 1, 10):
            out[name][f"min_{n}"] = timing.ratio("min", lmin, n)
            out[name][f"rule_{n}"] = timing.ratio("rule", lrule, n)
    out["plain_ns"] = timing.plain
    return out


def runtime_pattern(number: int, repeat: int) -> dict[str, float]:
    """The SLEEC runtime's dispatch: ``run_with(Snapshot(60 rules' clause layers), rule, event)``."""
    rng = random.Random(1)
    plain = float("inf")
    out: dict[str, float] = {}
    for name, rules in RULES.items():
        layers = tuple(rng.choice(clauses) for _, clauses in rules)
        fn = rules[0][0]
        g = {"run_with": run_with, "Snapshot": Snapshot, "snap": Snapshot(layers), "layers": layers, "fn": fn}
        for label, stmt in (
            ("kept", "run_with(snap, fn, 'E')"),
            ("fresh", "run_with(Snapshot(layers), fn, 'E')"),
        ):
            best = float("inf")
            for _ in range(repeat):
                plain = min(plain, per_call(plain_rule, "E", True, number))
                best = min(best, timeit.timeit(stmt, globals=g, number=number) / number * 1e9)
            out[f"{name}_{label}"] = best
    return {k: v / plain for k, v in out.items()}


def main() -> int:
    a = args(__doc__ or "")
    # many short runs rather than a few long ones: the best of them finds the machine's quiet moments
    number, repeat = (20_000, 12) if a.quick else (100_000, 15)
    through_lambda = ratios(False, number, repeat)
    direct = ratios(True, number, repeat)
    runtime = runtime_pattern(number // 5, repeat)
    enter_exit = (
        min(
            timeit.repeat(
                lambda: activate(LAYERS[0]).__enter__().__exit__(None, None, None),
                number=number,
                repeat=repeat,
            )
        )
        / number
    )
    cp = contextpy3_ratio(direct["plain_ns"]["min"], number // 10, repeat)
    d = direct[DEFAULT]
    result: dict[str, object] = {
        "benchmark": "cop_dispatch",
        "default_dispatcher": DEFAULT,
        # the default dispatcher, B-min, both sides called directly
        "ratio_no_layer": round(d["min_0"], 2),
        "ratio_one_layer": round(d["min_1"], 2),
        "ratio_ten_layers": round(d["min_10"], 2),
        "ten_over_one_layer": round(d["min_10"] / d["min_1"], 2),
        "rule_ratio_no_layer": round(d["rule_0"], 2),
        "rule_ratio_one_layer": round(d["rule_1"], 2),
        "rule_ratio_ten_layers": round(d["rule_10"], 2),
        "lambda": {k: {m: round(v, 2) for m, v in t.items()} for k, t in through_lambda.items()},
        "direct": {k: {m: round(v, 2) for m, v in t.items()} for k, t in direct.items()},
        "runtime_rule_60_layers": {k: round(v, 2) for k, v in runtime.items()},
        "plain_min_ns": round(direct["plain_ns"]["min"], 1),
        "plain_rule_ns": round(direct["plain_ns"]["rule"], 1),
        "layered_min_ns": {
            f"{n}_layers": round(d[f"min_{n}"] * direct["plain_ns"]["min"], 1) for n in (0, 1, 10)
        },
        "activate_enter_exit_ns": round(enter_exit * 1e9),
        "ratio_contextpy3": None if cp is None else round(cp, 1),
        "targets": TARGETS,
        "quick": a.quick,
    }
    report("cop_dispatch", rows(through_lambda, direct, runtime, enter_exit, cp), result, a.json)
    return 0


def rows(
    through_lambda: dict[str, dict[str, float]],
    direct: dict[str, dict[str, float]],
    runtime: dict[str, float],
    enter_exit: float,
    cp: float | None,
) -> list[tuple[str, str, str]]:
    out = [
        (
            "plain call, B-min / B-rule",
            f"{through_lambda['plain_ns']['min']:.0f} / {through_lambda['plain_ns']['rule']:.0f} ns (lambda), "
            f"{direct['plain_ns']['min']:.0f} / {direct['plain_ns']['rule']:.0f} ns (direct)",
            "the baselines",
        )
    ]
    for how, table in (("direct", direct), ("lambda", through_lambda)):
        for name in DISPATCHERS:
            for key, v in table[name].items():
                t = TARGETS.get(key)
                note = "" if t is None else f"target <= {t}x: {'met' if v <= t else 'NOT met'}"
                out.append((f"{name}, {how}: {key.replace('_', ', ')} layers", f"{v:.2f}x", note))
    for key, v in runtime.items():
        out.append((f"run_with(Snapshot(60 layers)), B-rule, {key}", f"{v:.2f}x", "vs a plain B-rule call"))
    out.append(("with activate(L): pass", f"{enter_exit * 1e9:.0f} ns", "enter + exit"))
    out.append(
        ("contextpy3, B-min, no layer", "n/a" if cp is None else f"{cp:.1f}x", "same machine, same run")
    )
    return out


def contextpy3_ratio(base_ns: float, number: int, repeat: int) -> float | None:
    try:
        import _contextpy_case as cp  # type: ignore[import-not-found]
    except ImportError:
        return None
    return min(per_call(cp.bmin, 1, True, number) for _ in range(repeat)) / base_ns


if __name__ == "__main__":
    sys.exit(main())
