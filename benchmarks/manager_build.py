"""Building a Manager from the text of N rules: seconds, rules/s and memory per loaded rule.

The rules are ``_rulesets.scaled_rules(N)``: each triggered by its own event, with one
clause over a measure ten rules share. Sizes: 1,000 and 10,000 rules (``--quick``), and
100,000 in a full run when the 10,000-rule build extrapolates to under a minute.

Time: best of a few rounds (one at 10,000 rules in ``--quick``, and at 100,000), each round
timing ``analyse`` (parse + check: the baseline, measured in the same run) then
``Manager.from_text`` (parse + check + compile + the Manager: layers, implementations,
priorities, tracker), a full collection before each (not timed). ``build_over_parse``: the
build's time as a multiple of parse + check. Memory: what the built Manager keeps
(``_rulesets.allocated_bytes`` after a collection, less before: Python's and malloc's bytes
in use), per rule, with the text's own bytes per rule for scale; ``memory_exponent`` and
``time_exponent``: log-log slopes against rules (1: linear). Targets (issue 16): 10,000
rules built in <= 1 s; memory per rule stated, and linear.
"""

from __future__ import annotations

import sys

from _common import args, loglog_slope, report
from _rulesets import manager_build, parse_check_s, scaled_rules

TARGET_S_10K = 1.0


def main() -> int:
    a = args(__doc__ or "")
    sizes = [1_000, 10_000]
    repeats = 2 if a.quick else 3
    per: dict[int, dict[str, float]] = {}
    rows = []
    n = 0
    while n < len(sizes):
        size = sizes[n]
        text = scaled_rules(size)
        parse, build, kept = float("inf"), float("inf"), None
        for _ in range(1 if size > 10_000 or (a.quick and size >= 10_000) else repeats):
            parse = min(parse, parse_check_s(text))
            s, m, kept = manager_build(text, 1)
            build = min(build, s)
            m.close()
            del m
        per[size] = {"manager_s": build, "parse_check_s": parse, "text_bytes": len(text.encode())}
        rows.append(
            (
                f"{size:,} rules",
                f"{build:.2f} s",
                f"{size / build:,.0f} rules/s; parse + check {parse:.2f} s (the build is {build / parse:.1f}x it)",
            )
        )
        if kept is not None:
            per[size]["bytes"] = kept
            rows.append(
                (
                    f"{size:,} rules, memory",
                    f"{kept / size / 1024:.1f} KiB/rule",
                    f"{kept / 2**20:.1f} MiB kept; the text is {len(text.encode()) / size:.0f} B/rule",
                )
            )
        # 100,000 in a full run, when it extrapolates to under a minute
        if size == 10_000 and not a.quick and build * 10 * 1.5 < 60:
            sizes.append(100_000)
        n += 1
    s10k = per[10_000]["manager_s"]
    measured = [s for s in per if "bytes" in per[s]]
    exponent = (
        loglog_slope([float(s) for s in measured], [per[s]["bytes"] for s in measured]) if measured else None
    )
    time_exponent = loglog_slope([float(s) for s in per], [per[s]["manager_s"] for s in per])
    rows.append(
        (
            "memory against rules",
            "not measured" if exponent is None else f"exponent {exponent:.2f}",
            "log-log slope; 1 is linear",
        )
    )
    rows.append(("build time against rules", f"exponent {time_exponent:.2f}", "log-log slope; 1 is linear"))
    rows.append(
        (
            "10,000 rules",
            f"{s10k:.2f} s",
            f"target <= {TARGET_S_10K:g} s: {'met' if s10k <= TARGET_S_10K else 'NOT met'}",
        )
    )
    result: dict[str, object] = {
        "benchmark": "manager_build",
        "sizes": list(per),
        "seconds": {str(s): round(v["manager_s"], 3) for s, v in per.items()},
        "rules_per_s": {str(s): round(s / v["manager_s"]) for s, v in per.items()},
        "parse_check_s": {str(s): round(v["parse_check_s"], 3) for s, v in per.items()},
        "build_over_parse": {str(s): round(v["manager_s"] / v["parse_check_s"], 2) for s, v in per.items()},
        "bytes_per_rule": {str(s): round(per[s]["bytes"] / s) for s in measured},
        "text_bytes_per_rule": {str(s): round(v["text_bytes"] / s) for s, v in per.items()},
        "manager_build_s_10k_rules": round(s10k, 3),
        "rules_per_s_10k_rules": round(10_000 / s10k),
        "build_over_parse_10k_rules": round(s10k / per[10_000]["parse_check_s"], 2),
        "bytes_per_rule_10k_rules": round(per[10_000]["bytes"] / 10_000) if "bytes" in per[10_000] else None,
        "memory_exponent": None if exponent is None else round(exponent, 2),
        "time_exponent": round(time_exponent, 2),
        "target_s_10k_rules": TARGET_S_10K,
        "quick": a.quick,
    }
    report("manager_build", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
