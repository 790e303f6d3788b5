"""Parse and check the whole SLEEC corpus; report rules per second on one core.

Baseline, measured in the same run: Lark's own LALR parser building a plain parse tree
from the same grammar (no AST, no checks) -- what a straightforward Lark front-end costs.
Target: >= 20,000 rules/s (LEGOS-SLEEC's textX parser manages about 230 rules/s).
"""

from __future__ import annotations

import contextlib
import sys
from importlib import resources

from lark import Lark

from _common import CORPUS, args, best_of, report
from cosleec.lang import analyse

TARGET = 20_000


def main() -> int:
    a = args(__doc__ or "")
    files = sorted(CORPUS.glob("*.sleec"))
    if not files:
        print(f"parse_corpus: corpus not found at {CORPUS}", file=sys.stderr)
        return 2
    texts = [f.read_text(encoding="utf-8", errors="replace") for f in files]
    results = [analyse(t, str(f)) for t, f in zip(texts, files)]
    rules = sum(len(r.spec.rules) for r in results if r.spec is not None)
    repeats = 3 if a.quick else 10

    def ours() -> None:
        for t in texts:
            analyse(t)

    grammar = resources.files("cosleec.lang").joinpath("grammar/sleec.lark").read_text()
    plain = Lark(grammar, parser="lalr", lexer="contextual", maybe_placeholders=True)

    def baseline() -> None:
        for t in texts:
            # malformed corpus files: the error path is part of the work
            with contextlib.suppress(Exception):
                plain.parse(t)

    t_ours = best_of(ours, repeats)
    t_base = best_of(baseline, repeats)
    rate, base_rate = rules / t_ours, rules / t_base
    result = {
        "benchmark": "parse_corpus",
        "files": len(files),
        "rules": rules,
        "seconds": round(t_ours, 4),
        "rules_per_s": round(rate),
        "baseline_rules_per_s": round(base_rate),
        "speedup_vs_plain_lark": round(rate / base_rate, 2),
        "target_rules_per_s": TARGET,
        "meets_target": rate >= TARGET,
        "quick": a.quick,
    }
    rows = [
        ("corpus", f"{len(files)} files, {rules} rules", "parsed and checked (diagnostics included)"),
        ("cosleec parse + check", f"{rate:,.0f} rules/s", f"best of {repeats}: {t_ours * 1000:.0f} ms"),
        ("baseline: plain Lark LALR tree", f"{base_rate:,.0f} rules/s", "same grammar, no AST, no checks"),
        (
            "ratio",
            f"{rate / base_rate:.2f}x",
            f"target {TARGET:,} rules/s: {'met' if rate >= TARGET else 'NOT met'}",
        ),
    ]
    report("parse_corpus", rows, result, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
