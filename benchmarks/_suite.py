"""Run every benchmark, one after another, and write one JSON document of all their results.

``bash benchmarks/run all [--quick] [--json] [-o FILE] [--no-ros]``

Each benchmark runs as ``bash benchmarks/run NAME [--quick] --json`` in a process of its
own (never two at once: they would disturb each other's timings); its result is the JSON
object its output ends with. ``ros2_latency`` needs ROS 2 and a private network namespace:
it runs, inside ``unshare --net`` with only loopback up, when the ROS 2 environment exists
(``.venv-ros2``, made by ``bash scripts/setup-ros``) and the namespace can be made;
otherwise (or with ``--no-ros``) it is listed under ``skipped`` with the reason, and the
table shows it as not measured.

The document: ``machine``, ``cores``, ``python``, ``commit``, ``date``, ``quick``,
``seconds`` (the whole run), ``durations_s`` (each benchmark), ``benchmarks`` (name ->
its JSON result), ``skipped`` (name -> why) and ``failed`` (name -> why: a crash, a
timeout, or a benchmark that reported a broken promise with its exit status, such as
``scaling``'s exponents; its result, when it printed one, is kept under ``benchmarks``).
It goes to stdout with ``--json`` (the tables then go to stderr), to FILE with ``-o``.
``bash scripts/bench-table FILE`` makes the benchmark table (docs/benchmarks.md) and the README's headline from it. Exit status: 0 when
every benchmark that ran succeeded, 1 otherwise.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

from _common import ROOT, machine

HERE = Path(__file__).resolve().parent
PROG = "bash benchmarks/run all"
#: the order they run in: quick ones first
ORDER = [
    "parse_corpus",
    "cop_dispatch",
    "dispatch_path",
    "scalability_grid",
    "manager_build",
    "scaling",
    "analyse_case_studies",
    "ros2_latency",
]
TIMEOUT_S = {True: 600, False: 3600}  # per benchmark: --quick, full


def benchmarks() -> list[str]:
    """Every benchmark (``benchmarks/NAME.py``, no leading underscore), in ``ORDER`` first."""
    found = sorted(p.stem for p in HERE.glob("*.py") if not p.stem.startswith("_"))
    return [n for n in ORDER if n in found] + [n for n in found if n not in ORDER]


def ros_unavailable() -> str | None:
    """Why ros2_latency cannot run here, or None when it can."""
    python = ROOT / ".venv-ros2" / "bin" / "python"
    if not python.exists():
        return "no ROS 2 environment (.venv-ros2: bash scripts/setup-ros)"
    if shutil.which("unshare") is None:
        return "no unshare: a private network namespace cannot be made"
    if namespace() is None:
        return "unshare --net failed: a private network namespace cannot be made here"
    probe = subprocess.run([str(python), "-c", "import rclpy"], capture_output=True)
    if probe.returncode != 0:
        return "rclpy does not import in .venv-ros2"
    return None


def namespace() -> list[str] | None:
    """How to enter a new network namespace here (as root, or mapped to root, as scripts/test
    does), or None."""
    for how in (["unshare", "--net"], ["unshare", "--map-root-user", "--net"]):
        if subprocess.run([*how, "true"], capture_output=True).returncode == 0:
            return how
    return None


def command(name: str, quick: bool) -> list[str]:
    cmd = ["bash", str(HERE / "run"), name, "--json", *(["--quick"] if quick else [])]
    if name == "ros2_latency":  # only loopback: no discovery or data traffic leaves the machine
        return [
            *(namespace() or ["unshare", "--net"]),
            "--",
            "bash",
            "-c",
            'ip link set lo up && exec "$@"',
            "isolated",
            "env",
            "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST",
            f"ROS_DOMAIN_ID={random.randint(1, 100)}",
            *cmd,
        ]
    return cmd


def last_json(out: str) -> dict[str, object] | None:
    for line in reversed(out.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                parsed = json.loads(line)
            except json.JSONDecodeError:
                return None
            return parsed if isinstance(parsed, dict) else None
    return None


def commit() -> str | None:
    try:
        head = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short=12", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return f"{head}+changes" if dirty else head


def main() -> int:
    p = argparse.ArgumentParser(
        prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--quick", action="store_true", help="every benchmark's --quick: the whole run in minutes")
    p.add_argument("--json", action="store_true", help="write the JSON document to stdout (tables to stderr)")
    p.add_argument("-o", "--output", metavar="FILE", help="write the JSON document to FILE")
    p.add_argument("--no-ros", action="store_true", help="skip ros2_latency")
    p.add_argument("--only", metavar="NAME", action="append", help="run only these benchmarks (repeatable)")
    a = p.parse_args()
    names = benchmarks()
    if a.only:
        unknown = sorted(set(a.only) - set(names))
        if unknown:
            print(f"benchmarks/run all: no benchmark named {', '.join(unknown)}", file=sys.stderr)
            return 2
        names = [n for n in names if n in a.only]
    tables = sys.stderr if a.json else sys.stdout
    doc: dict[str, object] = {
        "suite": "cosleec benchmarks",
        "quick": a.quick,
        "machine": machine(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "commit": commit(),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
    }
    results: dict[str, object] = {}
    durations: dict[str, float] = {}
    skipped: dict[str, str] = {}
    failed: dict[str, str] = {}
    start = time.perf_counter()
    for i, name in enumerate(names, 1):
        if name == "ros2_latency":
            why = "--no-ros" if a.no_ros else ros_unavailable()
            if why is not None:
                skipped[name] = why
                print(f"[{i}/{len(names)}] {name}: skipped ({why})", file=sys.stderr, flush=True)
                continue
        print(f"[{i}/{len(names)}] {name} ...", file=sys.stderr, flush=True)
        t = time.perf_counter()
        try:
            run = subprocess.run(
                command(name, a.quick), capture_output=True, text=True, timeout=TIMEOUT_S[a.quick], cwd=ROOT
            )
        except subprocess.TimeoutExpired:
            durations[name] = round(time.perf_counter() - t, 1)
            failed[name] = f"timed out after {TIMEOUT_S[a.quick]} s"
            print(f"    {failed[name]}", file=sys.stderr, flush=True)
            continue
        durations[name] = round(time.perf_counter() - t, 1)
        result = last_json(run.stdout)
        shown = "\n".join(line for line in run.stdout.splitlines() if not line.startswith("{"))
        print(shown, file=tables, flush=True)
        if result is not None:
            results[name] = result
        if run.returncode != 0 or result is None:
            tail = " | ".join(run.stderr.strip().splitlines()[-3:])
            failed[name] = f"exit status {run.returncode}" + (f": {tail}" if tail else "")
            if result is None:
                failed[name] += " (no JSON result)"
        status = "FAILED: " + failed[name] if name in failed else "ok"
        print(f"    {durations[name]:.1f} s, {status}", file=sys.stderr, flush=True)
    doc["seconds"] = round(time.perf_counter() - start, 1)
    doc["durations_s"] = durations
    doc["benchmarks"] = results
    doc["skipped"] = skipped
    doc["failed"] = failed
    if a.output:
        Path(a.output).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {a.output} ({doc['seconds']} s)", file=sys.stderr)
    if a.json:  # one line, as every benchmark's --json
        print(json.dumps(doc))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
