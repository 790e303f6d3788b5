"""The behaviour-tree tests need py_trees (the ``bt`` extra, in ``scripts/setup --dev``):
skipped where it is not installed, except under CI, where a missing extra is a failure."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

RULES = Path(__file__).resolve().parents[3] / "src" / "cosleec" / "demo" / "assistive_care" / "rules.sleec"

if importlib.util.find_spec("py_trees") is None:
    if os.environ.get("CI"):
        raise RuntimeError(
            "py_trees is not installed: CI installs it with `bash scripts/setup --dev` (the bt extra)"
        )
    collect_ignore_glob = ["test_*.py"]


@pytest.fixture(autouse=True)
def fresh_blackboard() -> Iterator[None]:
    """py_trees keeps one blackboard per process: each test starts with an empty one."""
    import py_trees

    py_trees.blackboard.Blackboard.enable_activity_stream(maximum_size=100)
    yield
    py_trees.blackboard.Blackboard.clear()
    py_trees.blackboard.Blackboard.disable_activity_stream()
