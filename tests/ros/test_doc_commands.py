"""The README's ROS commands run as written, on real ROS 2 / ROS 1 (COSLEEC_ROS_BACKEND).

``tests/unit/test_doc_commands.py`` runs every other shell block of the docs and lists these
commands in ``NEEDS_ROS``; here the one for this backend (``.venv-ros2/bin/cosleec ros2
launch examples/ros/vacuum/ros2.launch.yaml``, or ``ros1``) is started from a mirror of the
repository root (``examples`` copied, so the audit log the launch file writes stays in a
temporary directory), must bring up its nodes, and must stop cleanly on SIGTERM. It is
started and stopped by PID.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from pathlib import Path

import pytest

from tests.doc_blocks import ROOT, mirror
from tests.unit.test_doc_commands import NEEDS_ROS


def test_the_readme_launch_command_runs_as_written(
    backend: str, graph: dict[str, str], tmp_path: Path
) -> None:
    from cosleec.ros.launch import stop

    lines = [line for _, line in sorted(NEEDS_ROS) if f"/cosleec {backend} launch " in line]
    assert len(lines) == 1, NEEDS_ROS
    venv = ROOT / f".venv-{backend}" / "bin" / "cosleec"
    if not venv.exists():
        pytest.fail(f"{venv} is missing: bash scripts/setup-ros creates it")
    where = mirror(tmp_path / "repo")
    (where / "examples").unlink()
    shutil.copytree(ROOT / "examples", where / "examples")  # the launch file writes its audit log
    proc = subprocess.Popen(
        ["bash", "-c", "exec " + lines[0]],  # exec: the PID is the launcher's
        env={**os.environ, **graph},
        cwd=where,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        assert proc.stdout is not None
        ready, seen = 0, []
        while ready < 3:  # manager, listener and guard each say when they are up
            line = proc.stdout.readline()
            seen.append(line)
            assert line, "the launcher ended early: " + "".join(seen[-20:])
            ready += ": ready" in line
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        stop(proc)
    assert (where / "examples" / "ros" / "vacuum" / "audit.jsonl").exists()
