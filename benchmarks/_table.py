"""The benchmark table of the docs site, and its headline in the README, made from the JSON
document of ``bash benchmarks/run all``.

``bash scripts/bench-table FILE.json`` rewrites the table in docs/benchmarks.md between the
markers ``<!-- bench-table:start -->`` and ``<!-- bench-table:end -->``, and the headline in
README.md (a few of the same rows, ``HEADLINE``) between ``<!-- bench-headline:start -->``
and ``<!-- bench-headline:end -->``: one document, one source for both, so the README's
figures are never typed by hand. ``--print`` writes the table to stdout instead, ``--check``
exits 1 when either is not the one FILE makes.

``ROWS`` lists what the table shows: one row per key, in this order, each with its
benchmark, how to print it and its target (if any): issue 16's, or issue 32's ("decisions
near the floor") where that one sets a new one. A key the document does
not have (a benchmark skipped, failed or not run) is shown as "not measured". The output
depends only on the document: the same JSON always makes the same table.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

START = "<!-- bench-table:start -->"
END = "<!-- bench-table:end -->"
HEAD_START = "<!-- bench-headline:start -->"
HEAD_END = "<!-- bench-headline:end -->"
ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "benchmarks.md"
README = ROOT / "README.md"
NOT_MEASURED = "not measured"
PROG = "bash scripts/bench-table"


@dataclass(frozen=True)
class Row:
    """One figure of the table: ``key`` of ``benchmark``'s result (``a.b`` reaches into a dict)."""

    benchmark: str
    key: str
    label: str
    unit: str  # us, ms, s, x, rate, count, exponent, bytes
    target: tuple[str, float] | None = None  # ("<=" or ">=", value)
    baseline: str = ""  # what the figure is measured against, in the same run


ROWS = [
    Row(
        "parse_corpus",
        "rules_per_s",
        "parse + check the corpus",
        "rate",
        (">=", 20_000),
        "LEGOS-SLEEC textX ≈ 230 rules/s",
    ),
    Row(
        "parse_corpus",
        "speedup_vs_plain_lark",
        "parse + check vs a plain Lark LALR tree",
        "x",
        (">=", 3),
        "plain Lark, same run",
    ),
    Row(
        "parse_corpus",
        "driver_speedup_vs_lark_transformer",
        "fast LALR driver vs Lark + Transformer",
        "x",
        (">=", 2),
        "Lark + Transformer, same run",
    ),
    Row(
        "cop_dispatch",
        "ratio_no_layer",
        "layered call, no layer active",
        "x",
        ("<=", 2.5),
        "plain call, same run",
    ),
    Row(
        "cop_dispatch",
        "ratio_one_layer",
        "layered call, one layer active",
        "x",
        ("<=", 5),
        "plain call, same run",
    ),
    Row(
        "cop_dispatch",
        "ratio_ten_layers",
        "layered call, ten layers active",
        "x",
        ("<=", 30),
        "plain call, same run",
    ),
    Row(
        "cop_dispatch", "ten_over_one_layer", "ten layers / one layer", "x", ("<=", 10), "linear growth: ≤ 10"
    ),
    Row(
        "dispatch_path",
        "median_us",
        "trigger → decision → capability, median",
        "us",
        None,
        "60 rules × 5 clauses",
    ),
    Row("dispatch_path", "p99_us", "trigger → decision → capability, p99", "us"),
    Row(
        "dispatch_path",
        "ratio_mean",
        "trigger → capability, mean / hand-coded",
        "x",
        ("<=", 25),
        "hand-coded if/elif, same run",
    ),
    Row(
        "dispatch_path",
        "floor_ratio_mean",
        "the same records kept as fast as CPython allows (the floor), mean / hand-coded",
        "x",
        None,
        "the floor of the data model, same run",
    ),
    Row(
        "scalability_grid",
        "mean_us_at_60x20",
        "update → implementation at 60 × 20, mean",
        "us",
        None,
        "SLEEC@run.time: 6.9 s mean",
    ),
    Row(
        "scalability_grid",
        "mean_ratio_to_handcoded_at_60x20",
        "the same, mean / hand-coded",
        "x",
        ("<=", 50),
        "hand-coded if/elif, same run",
    ),
    Row(
        "scalability_grid",
        "floor_ratio_at_60x20",
        "the floor at 60 × 20, mean / hand-coded",
        "x",
        None,
        "the floor of the data model, same run",
    ),
    Row("scalability_grid", "p99_us_at_60x20", "p99 at 60 × 20, bare", "us", ("<=", 60)),
    Row("scalability_grid", "p99_us_at_60x20_observer", "p99 at 60 × 20, one observer", "us", ("<=", 80)),
    Row("scalability_grid", "p99_us_at_60x20_audit", "p99 at 60 × 20, audit log on", "us", ("<=", 120)),
    Row(
        "scalability_grid",
        "p99_us_at_60x20_journal",
        "p99 at 60 × 20, audit log and journal",
        "us",
        ("<=", 1000),
    ),
    Row(
        "scalability_grid",
        "update_flip_median_us_10k_rules",
        "update flipping a value, 10,000 rules",
        "us",
        ("<=", 30),
    ),
    Row(
        "scalability_grid",
        "update_flip_ratio_10k_vs_100",
        "the same, 10,000 rules / 100 rules",
        "x",
        None,
        "100 rules, same run",
    ),
    Row("scalability_grid", "manager_build_s_10k_rules", "build a Manager, 10,000 rules", "s", ("<=", 1)),
    Row("manager_build", "rules_per_s_10k_rules", "Manager build rate, 10,000 rules", "rate"),
    Row(
        "manager_build",
        "build_over_parse_10k_rules",
        "build / parse + check, 10,000 rules",
        "x",
        None,
        "parse + check, same run",
    ),
    Row("manager_build", "bytes_per_rule_10k_rules", "memory per loaded rule, 10,000 rules", "bytes"),
    Row("manager_build", "memory_exponent", "memory against rules (1: linear)", "exponent", ("<=", 1.2)),
    Row("scaling", "exponent_update", "update cost against rules (promise 0)", "exponent", ("<=", 0.2)),
    Row("scaling", "exponent_event", "event cost against rules (promise 0)", "exponent", ("<=", 0.2)),
    Row(
        "scaling",
        "exponent_update_obl",
        "update cost against obligations (promise 0)",
        "exponent",
        ("<=", 0.2),
    ),
    Row(
        "scaling", "exponent_event_obl", "event cost against obligations (promise 0)", "exponent", ("<=", 0.2)
    ),
    Row("scaling", "exponent_build", "build time against rules (promise 1)", "exponent", ("<=", 1.2)),
    Row("scaling", "exponent_start", "Manager.start() against rules (promise 1)", "exponent", ("<=", 1.2)),
    Row("scaling", "exponent_memory", "memory against rules (promise 1)", "exponent", ("<=", 1.2)),
    Row("scaling", "events_per_s_largest", "events per second, at the most rules loaded", "rate"),
    Row("ros2_latency", "e2e_p99_us", "ROS 2 end to end, p99", "us", None, "SLEEC@run.time: 76 ms mean"),
    Row(
        "ros2_latency",
        "ratio_p50",
        "ROS 2 end to end / raw rclpy round trip, p50",
        "x",
        ("<=", 2.0),
        "raw rclpy round trip of the same Event type, same run",
    ),
    Row(
        "ros2_latency",
        "ratio_p99",
        "ROS 2 end to end / raw rclpy round trip, p99",
        "x",
        ("<=", 1.8),
        "raw rclpy round trip of the same Event type, same run (3 hops against 2: floor 1.5×)",
    ),
    Row(
        "ros2_latency",
        "relay_ratio_p50",
        "relays of our nodes' shape that only forward / raw round trip, p50",
        "x",
        None,
        "the floor of the node design, same run",
    ),
    Row(
        "ros2_latency",
        "relay_ratio_p99",
        "relays of our nodes' shape that only forward / raw round trip, p99",
        "x",
        None,
        "the floor of the node design, same run",
    ),
    Row("analyse_case_studies", "total_s", "analyse the 18 case-study files", "s", ("<=", 45)),
    Row(
        "repair_case_studies",
        "repaired_percent",
        "`analyse --fix`: the nine initial files' conflicts, redundancies, concerns, purposes repaired, %",
        "count",
        (">=", 90),
        "SLEEC-PATCH: 75 % (with an LLM)",
    ),
    Row(
        "repair_case_studies",
        "median_s_per_finding",
        "`analyse --fix`: time per finding, median",
        "s",
        ("<=", 5),
        "SLEEC-PATCH: 35.7 s",
    ),
    Row(
        "repair_case_studies",
        "worst_s_per_finding",
        "`analyse --fix`: time per finding, worst",
        "s",
        ("<=", 60),
        "SLEEC-PATCH: 277 s",
    ),
    Row(
        "repair_case_studies",
        "new_findings_with_sets",
        "`analyse --fix`: new findings with each file's patch set applied",
        "count",
        ("<=", 0),
        "analysed again, independently",
    ),
    Row(
        "repair_case_studies",
        "repair_over_analysis",
        "`analyse --fix` / `analyse`, the nine files",
        "x",
        None,
        "`analyse` of the same files, same run",
    ),
    Row(
        "repair_case_studies",
        "expert_agreement",
        "`analyse --fix`: top fix touches a rule the experts changed (share)",
        "count",
    ),
    Row(
        "lsp_incremental",
        "recheck_ms_3000_rules",
        "`cosleec lsp`: a one-character edit of 3,000 rules → its diagnostics",
        "ms",
        ("<=", 200),
        "a whole parse + check of the file: `whole_check_ms_3000_rules`, same run",
    ),
]


#: the rows of the README's headline, in the table's order: (benchmark, key) of ``ROWS``
HEADLINE = [
    ("parse_corpus", "rules_per_s"),
    ("scalability_grid", "mean_us_at_60x20"),
    ("scalability_grid", "update_flip_median_us_10k_rules"),
    ("ros2_latency", "e2e_p99_us"),
    ("analyse_case_studies", "total_s"),
]


def lookup(doc: dict[str, object], row: Row) -> object:
    """The figure for ``row`` in the suite document, or None."""
    benches = doc.get("benchmarks")
    value: object = benches.get(row.benchmark) if isinstance(benches, dict) else None
    for part in row.key.split("."):
        value = value.get(part) if isinstance(value, dict) else None
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return value


def figure(value: float, unit: str) -> str:
    if unit == "us":
        return f"{value:,.1f} µs" if value < 1000 else f"{value / 1000:,.2f} ms"
    if unit == "ms":
        return f"{value:,.1f} ms"
    if unit == "s":
        return f"{value:.2f} s"
    if unit == "x":
        return f"{value:.0f}×" if value >= 100 else f"{value:.1f}×" if value >= 10 else f"{value:.2f}×"
    if unit == "rate":
        return f"{value:,.0f}/s"
    if unit == "bytes":
        return f"{value / 1024:,.1f} KiB"
    if unit == "exponent":
        return f"{round(value, 2) + 0.0:.2f}"  # + 0.0: no "-0.00"
    return f"{value:g}"


def target_text(row: Row, value: float | None) -> str:
    if row.target is None:
        return ""
    op, bound = row.target
    unit = {"us": " µs", "ms": " ms", "s": " s", "x": "×", "rate": "/s", "bytes": " B", "exponent": ""}.get(
        row.unit, ""
    )
    want = f"{'≤' if op == '<=' else '≥'} {bound:,g}{unit}"
    if value is None:
        return want
    met = value <= bound if op == "<=" else value >= bound
    return f"{want}: {'met' if met else '**missed**'}"


def table(doc: dict[str, object], rows: list[Row] | None = None) -> str:
    """The Markdown table of ``rows`` (all of ``ROWS`` by default), with the line that says
    where and when it was measured."""
    quick = " `--quick`," if doc.get("quick") else ""
    cores = doc.get("cores")
    where = (
        f"Measured{quick} {doc.get('date', 'at an unknown date')}, commit `{doc.get('commit') or 'unknown'}`, "
        f"on {doc.get('machine', 'an unknown machine')}"
        + (f" ({cores} cores)" if cores and f"{cores} cores" not in str(doc.get("machine", "")) else "")
        + "."
    )
    lines = [
        where,
        "",
        "| benchmark | measure | figure | target | baseline or reference |",
        "|---|---|---|---|---|",
    ]
    for row in ROWS if rows is None else rows:
        value = lookup(doc, row)
        shown = NOT_MEASURED if value is None else figure(float(value), row.unit)  # type: ignore[arg-type]
        target = target_text(row, None if value is None else float(value))  # type: ignore[arg-type]
        lines.append(f"| `{row.benchmark}` | {row.label} | {shown} | {target} | {row.baseline} |")
    if rows is not None:
        return "\n".join(lines) + "\n"
    notes = []
    for kind in ("skipped", "failed"):
        entries = doc.get(kind)
        if isinstance(entries, dict):
            notes += [f"`{name}` {kind}: {why}" for name, why in sorted(entries.items())]
    if notes:
        lines += ["", *(f"- {n}" for n in notes)]
    return "\n".join(lines) + "\n"


def headline(doc: dict[str, object]) -> str:
    """The README's few figures: the ``HEADLINE`` rows of :func:`table`, made the same way
    from the same document (skipped and failed benchmarks are listed on the docs page only)."""
    return table(doc, [row for row in ROWS if (row.benchmark, row.key) in HEADLINE])


def replace(text: str, body: str, start: str = START, end: str = END) -> str:
    """``text`` with what is between the markers ``start`` and ``end`` replaced by ``body``."""
    if text.count(start) != 1 or text.count(end) != 1 or text.index(start) > text.index(end):
        raise ValueError(f"needs one {start} and, after it, one {end}")
    head, rest = text.split(start)
    _, tail = rest.split(end)
    return f"{head}{start}\n{body}{end}{tail}"


def load(path: Path) -> object:
    """The JSON document in ``path``: the whole file, or its last line (a captured run's output)."""
    text = path.read_text(encoding="utf-8").strip()
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return json.loads(text.splitlines()[-1] if text else "")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("results", help="the JSON document of `bash benchmarks/run all --json` (or -o FILE)")
    p.add_argument("--page", default=str(PAGE), help="the page whose table to rewrite (docs/benchmarks.md)")
    p.add_argument("--readme", default=str(README), help="the file whose headline to rewrite (README.md)")
    how = p.add_mutually_exclusive_group()
    how.add_argument("--print", action="store_true", help="write the table to stdout, change nothing")
    how.add_argument("--check", action="store_true", help="exit 1 when table or headline differ")
    a = p.parse_args(argv)
    try:
        doc = load(Path(a.results))
    except (OSError, ValueError) as e:
        print(f"bench-table: cannot read {a.results}: {e}", file=sys.stderr)
        return 2
    if not isinstance(doc, dict):
        print(f"bench-table: {a.results} is not a JSON object", file=sys.stderr)
        return 2
    if a.print:
        sys.stdout.write(table(doc))
        return 0
    status = 0
    for path, body, start, end in (
        (Path(a.page), table(doc), START, END),
        (Path(a.readme), headline(doc), HEAD_START, HEAD_END),
    ):
        status = max(status, rewrite(path, body, start, end, check=a.check, results=a.results))
    return status


def rewrite(path: Path, body: str, start: str, end: str, *, check: bool, results: str) -> int:
    """Put ``body`` between the markers of ``path`` (or, with ``check``, say whether it is
    there): 0 done or already so, 1 not so (``check``), 2 the file or its markers are wrong."""
    try:
        old = path.read_text(encoding="utf-8")
        new = replace(old, body, start, end)
    except (OSError, ValueError) as e:
        print(f"bench-table: {path}: {e}", file=sys.stderr)
        return 2
    if check:
        if new != old:
            print(f"bench-table: the figures in {path} are not the ones {results} makes", file=sys.stderr)
            return 1
        return 0
    if new != old:
        path.write_text(new, encoding="utf-8")
    print(f"bench-table: {path} {'updated' if new != old else 'already up to date'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
