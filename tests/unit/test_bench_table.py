"""The benchmark table generator (benchmarks/_table.py, run as scripts/bench-table): the table of
docs/benchmarks.md and its headline in README.md, on a small fixture document: no benchmark runs
here (they are slow and timing-flaky)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "tests" / "data" / "bench" / "suite.json"


def _load() -> ModuleType:
    spec = importlib.util.spec_from_file_location("bench_table", ROOT / "benchmarks" / "_table.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["bench_table"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


bt = _load()


@pytest.fixture
def doc() -> dict[str, object]:
    return json.loads(FIXTURE.read_text(encoding="utf-8"))  # type: ignore[no-any-return]


def rows_of(table: str) -> list[list[str]]:
    lines = [ln for ln in table.splitlines() if ln.startswith("| `")]
    return [[c.strip() for c in ln.strip("|").split("|")] for ln in lines]


def test_the_same_document_always_makes_the_same_table(doc: dict[str, object]) -> None:
    first = bt.table(doc)
    assert bt.table(json.loads(json.dumps(doc))) == first
    reordered = dict(reversed(list(doc.items())))  # key order in the JSON does not matter
    assert bt.table(reordered) == first


def test_every_key_has_one_row_in_order(doc: dict[str, object]) -> None:
    rows = rows_of(bt.table(doc))
    assert [(r[0].strip("`"), r[1]) for r in rows] == [(row.benchmark, row.label) for row in bt.ROWS]


def test_figures_are_rendered_with_their_units_and_targets(doc: dict[str, object]) -> None:
    table = bt.table(doc)
    expected = [
        "| `parse_corpus` | parse + check the corpus | 15,210/s | ≥ 20,000/s: **missed** | LEGOS-SLEEC textX ≈ 230 rules/s |",
        "| `cop_dispatch` | layered call, no layer active | 2.47× | ≤ 2.5×: met | plain call, same run |",
        "| `cop_dispatch` | layered call, one layer active | 3.90× | ≤ 5×: met | plain call, same run |",
        "| `scalability_grid` | p99 at 60 × 20, one observer | 1.23 ms | ≤ 80 µs: **missed** |  |",
        "| `scalability_grid` | update flipping a value, 10,000 rules | 16.0 µs | ≤ 30 µs: met |  |",
        "| `scalability_grid` | build a Manager, 10,000 rules | 3.40 s | ≤ 1 s: **missed** |  |",
        "| `manager_build` | memory per loaded rule, 10,000 rules | 7.8 KiB |  |  |",
        "| `cop_dispatch` | ten layers / one layer | 15.6× | ≤ 10×: **missed** | linear growth: ≤ 10 |",
        "| `cop_dispatch` | layered call, ten layers active | 61.0× | ≤ 30×: **missed** | plain call, same run |",
        "| `scaling` | event cost against rules (promise 0) | -0.04 | ≤ 0.2: met |  |",
    ]
    for line in expected:
        assert line in table.splitlines(), line
    assert table.startswith(
        "Measured `--quick`, 2026-11-23 09:00 UTC, commit `0123456789ab`, on CPython 3.11.7, 2 cores, x86_64.\n"
    )


def test_what_the_document_lacks_is_not_measured(doc: dict[str, object]) -> None:
    rows = {(r[0].strip("`"), r[1]): r for r in rows_of(bt.table(doc))}
    benches = doc["benchmarks"]
    assert isinstance(benches, dict)
    for row in bt.ROWS:
        value = benches.get(row.benchmark, {}).get(row.key)
        present = isinstance(value, int | float) and not isinstance(value, bool)
        shown = rows[row.benchmark, row.label][2]
        assert (shown == "not measured") is not present, (row, shown)
        if not present:  # the target is still stated, with no verdict
            assert "met" not in rows[row.benchmark, row.label][3]
    assert rows["ros2_latency", "ROS 2 end to end / raw rclpy round trip, p99"][2:4] == [
        "not measured",
        "≤ 1.8×",
    ]
    # null and a boolean are not figures
    assert rows["scaling", "memory against rules (promise 1)"][2] == "not measured"
    assert rows["manager_build", "memory against rules (1: linear)"][2] == "not measured"


def test_an_empty_document_shows_every_row_as_not_measured() -> None:
    rows = rows_of(bt.table({}))
    assert len(rows) == len(bt.ROWS)
    assert all(r[2] == "not measured" for r in rows)


def test_skipped_and_failed_benchmarks_are_listed_under_the_table(doc: dict[str, object]) -> None:
    table = bt.table(doc)
    assert "- `ros2_latency` skipped: no ROS 2 environment (.venv-ros2: bash scripts/setup-ros)" in table
    assert "- `scaling` failed: exit status 1: scaling: fitted exponent above" in table


def test_every_key_issue_16_names_is_in_the_table() -> None:
    keys = {(row.benchmark, row.key) for row in bt.ROWS}
    named = {
        ("scalability_grid", "p99_us_at_60x20_observer"),
        ("scalability_grid", "p99_us_at_60x20_audit"),
        ("scalability_grid", "mean_ratio_to_handcoded_at_60x20"),
        ("scalability_grid", "update_flip_median_us_10k_rules"),
        ("scalability_grid", "manager_build_s_10k_rules"),
        ("cop_dispatch", "ratio_no_layer"),
        ("cop_dispatch", "ratio_one_layer"),
        ("cop_dispatch", "ratio_ten_layers"),
        ("ros2_latency", "ratio_p99"),
        ("parse_corpus", "rules_per_s"),
    }
    assert named <= keys


def test_the_page_and_the_readme_are_rewritten_between_their_markers_only(
    tmp_path: Path, doc: dict[str, object]
) -> None:
    page = tmp_path / "benchmarks.md"
    page.write_text(f"# title\nbefore\n{bt.START}\nold table\n{bt.END}\nafter\n", encoding="utf-8")
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\nbefore\n{bt.HEAD_START}\nold\n{bt.HEAD_END}\nafter\n", encoding="utf-8")
    results = tmp_path / "bench.json"
    results.write_text(json.dumps(doc), encoding="utf-8")
    files = [str(results), "--page", str(page), "--readme", str(readme)]
    assert bt.main([*files, "--check"]) == 1
    assert bt.main(files) == 0
    text = page.read_text(encoding="utf-8")
    assert text == f"# title\nbefore\n{bt.START}\n{bt.table(doc)}{bt.END}\nafter\n"
    head = readme.read_text(encoding="utf-8")
    assert head == f"# title\nbefore\n{bt.HEAD_START}\n{bt.headline(doc)}{bt.HEAD_END}\nafter\n"
    assert bt.main([*files, "--check"]) == 0
    assert bt.main(files) == 0
    assert page.read_text(encoding="utf-8") == text  # a second run changes nothing
    assert readme.read_text(encoding="utf-8") == head
    readme.write_text(head.replace(bt.headline(doc), "stale\n"), encoding="utf-8")
    assert bt.main([*files, "--check"]) == 1  # a stale headline alone is caught


def test_the_headline_is_rows_of_the_table(doc: dict[str, object]) -> None:
    head, whole = bt.headline(doc).splitlines(), bt.table(doc).splitlines()
    assert head[0] == whole[0]  # the same "Measured ..." line
    rows = [line for line in head if line.startswith("| `")]
    assert len(rows) == len(bt.HEADLINE) and all(line in whole for line in rows)
    assert {(r.benchmark, r.key) for r in bt.ROWS} >= set(bt.HEADLINE)


def test_a_captured_run_whose_last_line_is_the_document_is_read(
    tmp_path: Path, doc: dict[str, object]
) -> None:
    results = tmp_path / "out.txt"
    results.write_text("[1/8] parse_corpus ...\n" + json.dumps(doc) + "\n", encoding="utf-8")
    assert bt.load(results) == doc


def test_a_readme_without_markers_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="bench-table:start"):
        bt.replace("no markers here", "table")
    with pytest.raises(ValueError):
        bt.replace(f"{bt.END}\n{bt.START}\n", "table")


def test_the_repository_has_the_table_on_its_page_and_the_headline_in_its_readme() -> None:
    page = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    assert page.count(bt.START) == 1 and page.count(bt.END) == 1
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert readme.count(bt.HEAD_START) == 1 and readme.count(bt.HEAD_END) == 1
    assert bt.START not in readme and bt.END not in readme
    # one source: the README's figures are lines of the page's table, from the same run
    table = page.split(bt.START, 1)[1].split(bt.END, 1)[0].strip().splitlines()
    head = readme.split(bt.HEAD_START, 1)[1].split(bt.HEAD_END, 1)[0].strip().splitlines()
    assert head[0] == table[0] and head[0].startswith("Measured")
    rows = [line for line in head if line.startswith("| `")]
    assert rows and all(line in table for line in rows), "run bash scripts/bench-table on the same JSON"


def test_scaling_plot_draws_a_png_with_matplotlib(tmp_path: Path) -> None:
    """``scaling --plot FILE.png``, on figures given here (no benchmark runs): real
    matplotlib writes a real PNG (the `bench` extra is part of `dev`)."""
    pytest.importorskip("matplotlib")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        spec = importlib.util.spec_from_file_location("bench_scaling", ROOT / "benchmarks" / "scaling.py")
        assert spec is not None and spec.loader is not None
        scaling = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(scaling)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    series = {
        "update": {100: 28.0, 1000: 28.8, 10000: 31.9},
        "event": {100: 32.0, 1000: 44.8, 10000: 60.1},
        "build": {100: 0.017, 1000: 0.126, 10000: 1.61},
        "memory": {100: 0.71, 1000: 6.92, 10000: 68.7},
    }
    out = tmp_path / "scaling.png"
    scaling.plot(series, str(out))
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
