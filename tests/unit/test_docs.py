"""The documentation site builds (`mkdocs build --strict`: no broken link, no missing page),
and every Python block of its pages runs. Its ```console and ```bash blocks are run and
compared by ``tests/unit/test_doc_commands.py``."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PYTHON = re.compile(r"```python\n(.*?)```", re.S)


def test_the_site_builds_strictly(tmp_path: Path) -> None:
    if importlib.util.find_spec("mkdocs") is None:
        if os.environ.get("CI"):
            pytest.fail("mkdocs is not installed: bash scripts/setup --dev installs it")
        pytest.skip("mkdocs is not installed here (bash scripts/setup --dev)")
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    site = tmp_path / "site"
    cli = (site / "cli" / "index.html").read_text(encoding="utf-8")
    for command in ("cosleec check", "cosleec analyse", "cosleec ros2 guard", "cosleec ros1 manager"):
        assert command in cli  # the reference is generated from the parser: every command is there
    assert "Manager.reload" in (site / "api" / "index.html").read_text(encoding="utf-8")
    assert not (site / "hooks").exists()


def pages() -> list[Path]:
    return sorted(p for p in DOCS.glob("*.md"))


@pytest.mark.parametrize(
    "block",
    [
        b
        for p in pages()
        if p.name != "tutorial.md"  # run by tests/unit/test_tutorial.py, with its files
        for b in PYTHON.findall(p.read_text(encoding="utf-8"))
        if "rclpy" not in b
    ],
    ids=lambda b: b.strip().splitlines()[0][:40],
)
def test_every_python_block_of_the_docs_runs(block: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    exec(compile(block, "docs", "exec"), {"__name__": "docs"})
