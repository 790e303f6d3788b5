"""The shell blocks of README.md and docs/*.md, as the documentation tests run them.

Shared by ``tests/unit/test_doc_commands.py`` (everything that runs without middleware) and
``tests/ros/test_doc_commands.py`` (the commands that need ROS 2 or ROS 1). The rules that
say what a block means and when its output matches are in the unit test's docstring.
"""

from __future__ import annotations

import os
import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the pages whose blocks are read; docs/*.md also include README sections (mkdocs snippets,
#: ``--8<-- "README.md:NAME"``): those blocks are read once, from README.md
PAGES = ["README.md", *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)
ELIDED = ("...", "…")


@dataclass
class Command:
    """One command of a block (continuation lines joined) and the output shown for it."""

    text: str
    shown: list[str] = field(default_factory=list)


@dataclass
class Block:
    """A ```console or ```bash block: where it is and its commands."""

    page: str
    line: int  # of the opening fence, 1-based
    kind: str  # "console" or "bash"
    commands: list[Command]
    shown: list[str] | None = None  # bash: the ```text block right after it, if any

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"


def logical_lines(lines: list[str]) -> list[str]:
    """Lines with their ``\\`` continuations joined (as the shell joins them)."""
    out: list[str] = []
    pending = ""
    for line in lines:
        if line.endswith("\\"):
            pending += line[:-1].rstrip() + " "
            continue
        out.append(pending + line.strip() if pending else line)
        pending = ""
    if pending:
        out.append(pending.rstrip())
    return out


def blocks(pages: list[str] = PAGES) -> list[Block]:
    """Every ```console and ```bash block of ``pages``, in page order."""
    out: list[Block] = []
    for page in pages:
        text = (ROOT / page).read_text(encoding="utf-8")
        fences = list(FENCE.finditer(text))
        for i, m in enumerate(fences):
            kind, body = m.group(1), m.group(2)
            if kind not in ("console", "bash"):
                continue
            line = text.count("\n", 0, m.start()) + 1
            lines = body.rstrip("\n").split("\n")
            if kind == "console":
                out.append(Block(page, line, kind, console_commands(lines, f"{page}:{line}")))
                continue
            commands = [
                Command(c) for c in logical_lines(lines) if c.strip() and not c.lstrip().startswith("#")
            ]
            shown = None
            after = fences[i + 1] if i + 1 < len(fences) else None
            if after is not None and after.group(1) == "text" and not text[m.end() : after.start()].strip():
                shown = after.group(2).rstrip("\n").split("\n")
            out.append(Block(page, line, kind, commands, shown))
    return out


def console_commands(lines: list[str], where: str) -> list[Command]:
    """The ``$ `` commands of a console block, each with the lines shown after it."""
    commands: list[Command] = []
    continued = False
    for line in lines:
        if continued:
            commands[-1].text += " " + line.strip().removesuffix("\\").rstrip()
            continued = line.endswith("\\")
        elif line.startswith("$ "):
            commands.append(Command(line[2:].removesuffix("\\").rstrip()))
            continued = line.endswith("\\")
        else:
            if not commands:
                raise ValueError(f"{where}: a console block must start with a `$ ` command: {line!r}")
            commands[-1].shown.append(line)
    return commands


def pattern(shown: list[str]) -> re.Pattern[str]:
    """The output ``shown`` stands for, as a regular expression over the whole output."""
    parts = []
    for line in shown:
        line = line.rstrip()
        if line in ELIDED:
            parts.append(r"(?:[^\n]*\n)*?")  # any number of whole lines, none included
        elif line.endswith(ELIDED):
            prefix = line.removesuffix("...").removesuffix("…")
            parts.append(re.escape(prefix) + r"[^\n]*\n")
        else:
            parts.append(re.escape(line) + r"\n")
    return re.compile("".join(parts))


def normalise(output: str) -> str:
    """The output as compared: trailing blanks of each line and trailing empty lines dropped."""
    lines = [line.rstrip() for line in output.split("\n")]
    while lines and not lines[-1]:
        lines.pop()
    return "".join(line + "\n" for line in lines)


def matches(shown: list[str], output: str) -> bool:
    """Whether ``output`` is what ``shown`` shows (the elision rules of the unit test)."""
    while shown and not shown[-1].strip():
        shown = shown[:-1]
    return pattern(shown).fullmatch(normalise(output)) is not None


def mirror(into: Path) -> Path:
    """A directory that looks like the repository root (a symlink to each top-level entry but
    ``.git``) where commands may write files (``run.jsonl``) without touching the repository."""
    into.mkdir(parents=True, exist_ok=True)
    for entry in ROOT.iterdir():
        if entry.name != ".git":
            (into / entry.name).symlink_to(entry)
    return into


def shell(command: str, cwd: Path, env: dict[str, str], *, timeout: float = 120) -> tuple[int, str]:
    """Run ``command`` with bash (``set -e -o pipefail``); exit status and output (stdout and
    stderr interleaved, as a terminal shows them)."""
    done = subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", command],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=timeout,
    )
    return done.returncode, done.stdout


def environment(bin_dir: Path) -> dict[str, str]:
    """The environment the docs assume: ``cosleec`` on PATH (an active venv), unbuffered
    output so that stdout and stderr interleave as on a terminal."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    env.update(
        PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
        PYTHONUNBUFFERED="1",
        PYTHONIOENCODING="utf-8",
        COLUMNS="100",
    )
    return env
