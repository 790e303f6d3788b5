"""Shared helpers for benchmarks: arguments, timing, the table and the JSON line."""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from rich.table import Table

from cosleec.testing import corpus_dir

ROOT = Path(__file__).resolve().parent.parent
CORPUS = corpus_dir()


def args(
    description: str, extend: Callable[[argparse.ArgumentParser], None] | None = None
) -> argparse.Namespace:
    """--quick and --json, and what ``extend`` adds to the parser."""
    p = argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="finish within about 30 s")
    p.add_argument("--json", action="store_true", help="end with one JSON object on the last line")
    if extend is not None:
        extend(p)
    return p.parse_args()


def best_of(fn: Callable[[], object], repeats: int) -> float:
    """Best wall time of ``repeats`` runs: the least disturbed by a noisy machine."""
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def loglog_slope(xs: list[float], ys: list[float]) -> float:
    """Least-squares slope of log(y) against log(x)."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def machine() -> str:
    return f"{platform.python_implementation()} {platform.python_version()}, {os.cpu_count()} cores, {platform.machine()}"


def report(title: str, rows: list[tuple[str, str, str]], result: dict[str, object], as_json: bool) -> None:
    table = Table(title=title, caption=machine())
    table.add_column("measure")
    table.add_column("value", justify="right")
    table.add_column("note")
    for r in rows:
        table.add_row(*r)
    Console().print(table)
    if as_json:
        print(json.dumps(result))
