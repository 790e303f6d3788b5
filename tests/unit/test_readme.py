"""The README's `cosleec conforms` and `cosleec decide` sessions are real: each command is
run and its output compared with what the README shows. Its `cosleec analyse` sessions are
abridged: every line they show must be a line of the output, in the same order."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from cosleec.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
SESSION = re.compile(r"```console\n(.*?)```", re.S)


def sessions(command: str = "conforms") -> list[tuple[list[str], str]]:
    """(arguments, expected output) of each README ``cosleec COMMAND`` whose output is shown."""
    out = []
    for block in SESSION.findall((ROOT / "README.md").read_text(encoding="utf-8")):
        lines = block.splitlines()
        for i, line in enumerate(lines):
            if not line.startswith(f"$ cosleec {command}") or "&&" in line:
                continue
            shown = []
            for later in lines[i + 1 :]:
                if later.startswith("$ "):
                    break
                shown.append(later)
            out.append((shlex.split(line[2:])[1:], "\n".join(shown)))
    return out


@pytest.mark.parametrize(
    ("argv", "shown"), sessions(), ids=lambda x: " ".join(x) if isinstance(x, list) else ""
)
def test_the_readme_shows_what_the_command_prints(
    argv: list[str], shown: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    main(argv)
    assert capsys.readouterr().out.strip() == shown.strip()


def test_there_are_readme_sessions_to_check() -> None:
    assert len(sessions()) >= 2


@pytest.mark.parametrize(
    ("argv", "shown"), sessions("analyse"), ids=lambda x: " ".join(x) if isinstance(x, list) else ""
)
def test_the_readme_shows_lines_the_analysis_prints(
    argv: list[str], shown: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    assert main(argv) == 1  # every README example finds something
    out = capsys.readouterr().out.splitlines()
    at = 0
    for line in shown.splitlines():
        assert line in out[at:], f"not in the output (after line {at}): {line}"
        at = out.index(line, at) + 1


def test_there_are_readme_analyse_sessions() -> None:
    assert len(sessions("analyse")) >= 3


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


def test_some_python_blocks_run() -> None:
    assert len(python_blocks()) >= 2


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
