"""The README is a landing page: its Python block runs as written, its demo excerpt is what the
demo prints, and it maps every page of the documentation site. Its ```console and ```bash
blocks are run and compared by ``tests/unit/test_doc_commands.py``; the reference it used to
hold is on the site, whose Python blocks ``tests/unit/test_docs.py`` runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cosleec.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
PYTHON = re.compile(r"```python\n(.*?)```", re.S)
#: blocks that need a middleware and a running system (ROS): shown, not run here
NEEDS_ROS = ("rclpy", "cosleec_interfaces", "node.create")


def python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return [b for b in PYTHON.findall(text) if not any(word in b for word in NEEDS_ROS)]


@pytest.mark.parametrize("block", python_blocks(), ids=lambda b: b.strip().splitlines()[0][:40])
def test_every_python_block_of_the_readme_runs_as_written(
    block: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(ROOT)  # the README says: from the repository root
    exec(compile(block, "README.md", "exec"), {"__name__": "readme"})
    out = capsys.readouterr().out
    for comment in re.findall(r"^# (\S.*)$", block, re.M):  # an output shown as a comment line
        assert comment in out


def test_the_readme_has_its_embedded_example() -> None:
    blocks = python_blocks()
    assert blocks and any("Manager" in b and "Task" in b for b in blocks)


def test_the_readme_is_a_landing_page_that_maps_the_site() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 300, "reference belongs on the docs site (docs/), not the README"
    site = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    pages = re.findall(r"^\s*- [^:\n]+: ([\w/.-]+\.md)\s*$", site, re.M)
    assert len(pages) >= 15
    for page in pages:
        if page != "index.md":  # the site's home is the map itself
            assert f"](docs/{page})" in text, f"the README's map of the docs does not link docs/{page}"
    assert "example.org" not in site  # no placeholder repository link


def test_the_readme_demo_excerpt_is_what_the_demo_prints(capsys: pytest.CaptureFixture[str]) -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    excerpt = text.split("## The demo", 1)[1].split("```\n", 2)[1]  # the demo's first code block
    main(["demo"])
    printed = " ".join(capsys.readouterr().out.split())  # rich wraps lines at the terminal width
    at = 0
    for part in excerpt.split("\n...\n"):  # `...` marks what the README leaves out
        words = " ".join(part.split())
        assert words in printed[at:], f"not printed (in this order): {words}"
        at = printed.index(words, at) + len(words)
