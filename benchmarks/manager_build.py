"""Building a Manager from the text of N rules: seconds, rules/s and memory per loaded rule.

The rules are ``_rulesets.scaled_rules(N)``: each triggered by its own event, with one
clause over a measure ten rules share. Sizes: 1,000 and 10,000 rules (``--quick``), and
100,000 in a full run when the 10,000-rule build extrapolates to under a minute.

Time: best of a few (a full collection before each, not timed) of ``analyse`` (parse +
check: the baseline, measured in the same run), ``RuleSet.from_text`` (+ compile) and
``Manager.from_text`` (+ the Manager: layers, implementations, priorities, tracker);
``build_over_parse`` is the whole build's time as a multiple of parse + check, and the
phases are the differences. Memory: what the built Manager keeps allocated (tracemalloc,
after a collection, the text not counted), per rule, with the text's own bytes per rule
for scale. ``memory_exponent``: the log-log slope of retained bytes against rules (1:
linear). Targets (issue 16): 10,000 rules built in <= 1 s; memory per rule linear.
"""

from __future__ import annotations

import sys

from _common import args, loglog_slope, report
from _rulesets import build_times, retained_bytes, scaled_rules

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
        t = build_times(text, 1 if size > 10_000 else repeats)
        mem = retained_bytes(text)
        per[size] = {
            "manager_s": t["manager"],
            "parse_check_s": t["parse_check"],
            "ruleset_s": t["ruleset"],
            "bytes": mem,
            "text_bytes": len(text.encode()),
        }
        rows.append(
            (
                f"{size:,} rules",
                f"{t['manager']:.2f} s",
                f"{size / t['manager']:,.0f} rules/s; parse + check {t['parse_check']:.2f} s "
                f"({t['manager'] / t['parse_check']:.1f}x it), compile "
                f"{max(0.0, t['ruleset'] - t['parse_check']):.2f} s, Manager "
                f"{max(0.0, t['manager'] - t['ruleset']):.2f} s",
            )
        )
        rows.append(
            (
                f"{size:,} rules, memory",
                f"{mem / size / 1024:.1f} KiB/rule",
                f"{mem / 2**20:.1f} MiB kept; the text is {len(text.encode()) / size:.0f} B/rule",
            )
        )
        # 100,000 in a full run, when it extrapolates to under a minute (build + memory pass)
        if size == 10_000 and not a.quick and t["manager"] * 10 * 3 < 60:
            sizes.append(100_000)
        n += 1
    s10k = per[10_000]["manager_s"]
    exponent = loglog_slope([float(s) for s in per], [per[s]["bytes"] for s in per])
    time_exponent = loglog_slope([float(s) for s in per], [per[s]["manager_s"] for s in per])
    rows.append(("memory against rules", f"exponent {exponent:.2f}", "log-log slope; 1 is linear"))
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
        "compile_s": {
            str(s): round(max(0.0, v["ruleset_s"] - v["parse_check_s"]), 3) for s, v in per.items()
        },
        "build_over_parse": {str(s): round(v["manager_s"] / v["parse_check_s"], 2) for s, v in per.items()},
        "bytes_per_rule": {str(s): round(v["bytes"] / s) for s, v in per.items()},
        "text_bytes_per_rule": {str(s): round(v["text_bytes"] / s) for s, v in per.items()},
        "manager_build_s_10k_rules": round(s10k, 3),
        "rules_per_s_10k_rules": round(10_000 / s10k),
        "build_over_parse_10k_rules": round(s10k / per[10_000]["parse_check_s"], 2),
        "bytes_per_rule_10k_rules": round(per[10_000]["bytes"] / 10_000),
        "memory_exponent": round(exponent, 2),
        "time_exponent": round(time_exponent, 2),
        "target_s_10k_rules": TARGET_S_10K,
        "quick": a.quick,
    }
    report("manager_build", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
