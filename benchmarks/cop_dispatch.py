"""COP dispatch overhead, as cop-runtime.md §7 measures it.

Ratio = time of a call to a layered function / time of a plain call of its base, both in
this process, best of N timeit repeats. B-min: ``return x + 1`` (the stress case). B-rule:
builds a small frozen, slotted obligation record (what a SLEEC base does). Layers are
pass-through ``around`` partials. contextpy3 is measured on B-min when it is installed.
"""

from __future__ import annotations

import sys
import timeit
from contextlib import ExitStack

from _common import args, report
from _cop_cases import LAYERS, layered_min, layered_rule, plain_min, plain_rule
from cosleec.cop import activate, active_layers

TARGETS = {
    "ratio_no_layer": 2.0,
    "ratio_one_layer": 4.0,
    "rule_ratio_no_layer": 1.2,
    "rule_ratio_one_layer": 1.5,
}


def per_call(fn, arg, number: int, repeat: int) -> float:  # type: ignore[no-untyped-def]
    return min(timeit.repeat(lambda: fn(arg), number=number, repeat=repeat)) / number * 1e9


def measure(fn, arg, layers: int, number: int, repeat: int) -> float:  # type: ignore[no-untyped-def]
    with ExitStack() as stack:
        for la in LAYERS[:layers]:
            stack.enter_context(activate(la))
        assert len(active_layers()) == layers
        return per_call(fn, arg, number, repeat)


def contextpy3_ratio(base_ns: float, number: int, repeat: int) -> float | None:
    try:
        import _contextpy_case as cp  # type: ignore[import-not-found]
    except ImportError:
        return None
    return per_call(cp.bmin, 1, number, repeat) / base_ns


def main() -> int:
    a = args(__doc__ or "")
    number, repeat = (50_000, 5) if a.quick else (200_000, 7)
    # the lambda wrapper costs the same on both sides of each ratio
    p_min = per_call(plain_min, 1, number, repeat)
    p_rule = per_call(plain_rule, "E", number, repeat)
    r = {
        "ratio_no_layer": measure(layered_min, 1, 0, number, repeat) / p_min,
        "ratio_one_layer": measure(layered_min, 1, 1, number, repeat) / p_min,
        "ratio_ten_layers": measure(layered_min, 1, 10, number, repeat) / p_min,
        "rule_ratio_no_layer": measure(layered_rule, "E", 0, number, repeat) / p_rule,
        "rule_ratio_one_layer": measure(layered_rule, "E", 1, number, repeat) / p_rule,
    }
    with ExitStack():
        from timeit import timeit as _t

        enter_exit = (
            _t(lambda: activate(LAYERS[0]).__enter__().__exit__(None, None, None), number=number) / number
        )
    cp = contextpy3_ratio(p_min, number // 10, repeat)
    result: dict[str, object] = {k: round(v, 2) for k, v in r.items()}
    result.update(
        benchmark="cop_dispatch",
        plain_min_ns=round(p_min, 1),
        plain_rule_ns=round(p_rule, 1),
        activate_enter_exit_ns=round(enter_exit * 1e9),
        ratio_contextpy3=None if cp is None else round(cp, 1),
        targets=TARGETS,
        quick=a.quick,
    )
    rows = [
        ("plain call, B-min / B-rule", f"{p_min:.0f} / {p_rule:.0f} ns", "the baselines"),
    ]
    for k, v in r.items():
        t = TARGETS.get(k)
        note = "" if t is None else f"target <= {t}x: {'met' if v <= t else 'NOT met'}"
        rows.append((k, f"{v:.2f}x", note))
    rows.append(("with activate(L): pass", f"{enter_exit * 1e9:.0f} ns", "enter + exit"))
    rows.append(
        ("contextpy3, B-min, no layer", "n/a" if cp is None else f"{cp:.1f}x", "same machine, same run")
    )
    report("cop_dispatch", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
