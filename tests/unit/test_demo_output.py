"""`cosleec demo` as a newcomer runs it: the same bytes on every run whatever the hash seed,
and `--json` output that is JSON and nothing else on stdout (log lines go to stderr)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def demo(*args: str, seed: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(ROOT / "src")}
    return subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", "demo", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_demo_says_the_same_whatever_the_hash_seed() -> None:
    runs = [demo(seed=seed) for seed in ("0", "1", "4242")]
    assert all(r.returncode == 0 for r in runs), runs[0].stderr
    assert runs[0].stdout == runs[1].stdout == runs[2].stdout
    jsons = [demo("--json", seed=seed).stdout for seed in ("0", "7")]
    assert jsons[0] == jsons[1]


def test_demo_json_is_json_lines_and_nothing_else_on_stdout() -> None:
    r = demo("--json", seed="3")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) > 100
    records = [json.loads(line) for line in lines]  # every line, not some
    assert all(isinstance(x, dict) for x in records)
