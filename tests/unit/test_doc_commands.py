"""Every ```console and ```bash block of README.md and docs/*.md is run, and what it shows is
what the commands print.

What a block means:

- A ```console block is a terminal session. A line that starts with ``$ `` is a command (a
  line ending with ``\\`` continues on the next); every line after it, up to the next
  command or the end of the block, is its shown output. A command with no line after it
  must print nothing.
- A ```bash block is a script: its commands run in order with ``set -e -o pipefail`` and
  must succeed. A ```text block that follows it with nothing but blank lines between is
  what the whole script prints.
- Commands run with bash from the repository root (a mirror of it: the same files, and what
  a command writes stays in a temporary directory), with ``cosleec`` on PATH (the venv
  running the tests, as ``. .venv/bin/activate`` gives), stdout and stderr interleaved as a
  terminal shows them. The exit status of a console command is not compared: its output is.

When an output matches what is shown (trailing blanks and trailing empty lines ignored):

- a shown line that is exactly ``...`` (or ``…``) stands for any number of lines, none
  included;
- a shown line that ends with ``...`` (or ``…``) stands for one line that starts with the
  text before it (``3 findings ...`` for ``3 findings (0.10 s)``);
- every other shown line is one line of the output, exactly.

README blocks included in docs pages (mkdocs snippets) are read once, from README.md.
Commands that install software or take minutes are not run here (``INSTALLS``: CI runs them
itself), and commands that need ROS are run by ``tests/ros/test_doc_commands.py`` in the ROS
suites; here their command line is parsed by the real parser and the files they name must
exist (``NEEDS_ROS``). Both lists must be exactly what the docs contain.
"""

from __future__ import annotations

import re
import shlex
import sys
from pathlib import Path

import pytest

from cosleec.cli import ros
from cosleec.cli.main import build_parser
from tests.doc_blocks import ROOT, Block, blocks, environment, matches, mirror, shell

#: not run by the unit suite: they install software (as root) and take minutes. CI runs
#: them itself: ``.ci/run`` is ``bash scripts/test``, which runs ``scripts/setup`` and
#: ``scripts/setup-ros`` and then every suite; ``scripts/demo`` is ``scripts/setup`` then
#: ``cosleec demo``, which the README's demo excerpt test runs.
INSTALLS = {
    ("README.md", "bash scripts/demo"),
    ("README.md", "bash scripts/test"),
    ("README.md", "bash scripts/setup-ros"),
    ("docs/getting-started.md", "bash scripts/demo"),
}
#: need ROS 2 or ROS 1: run by tests/ros/test_doc_commands.py (ROS suites, ``unshare --net``)
NEEDS_ROS = {
    ("README.md", ".venv-ros2/bin/cosleec ros2 launch examples/ros/vacuum/ros2.launch.yaml"),
    ("README.md", ".venv-ros1/bin/cosleec ros1 launch examples/ros/vacuum/ros1.launch.yaml"),
}
ROS_WORDS = re.compile(
    r"\bros[12]\b|\bros(?:core|topic|launch|param|node|service|master)\b|\brclpy\b|\brospy\b"
)
INSTALL_WORDS = re.compile(r"\bbash scripts/|\b(?:pip|apt|apt-get) install\b|\bsudo\b")
BLOCKS = blocks()


def command(line: str) -> str:
    """A bash command without its trailing comment (the key of INSTALLS and NEEDS_ROS)."""
    return re.sub(r"\s+#.*$", "", line).strip()


def not_here(block: Block) -> set[tuple[str, str]]:
    """The commands of ``block`` this suite does not run."""
    return {(block.page, command(c.text)) for c in block.commands} & (INSTALLS | NEEDS_ROS)


def test_the_skip_lists_are_exactly_what_the_docs_contain() -> None:
    commands = {(b.page, command(c.text)) for b in BLOCKS for c in b.commands}
    installs = {(page, c) for page, c in commands if INSTALL_WORDS.search(c)}
    assert installs == INSTALLS, (
        "a command that installs software: list it in INSTALLS, or remove it from there"
    )
    ros = {(page, c) for page, c in commands if ROS_WORDS.search(c)} - INSTALLS
    assert ros == NEEDS_ROS, (
        "a command that needs ROS: list it in NEEDS_ROS (and run it in tests/ros), or remove it"
    )


def test_there_are_blocks_to_run() -> None:
    kinds = [b.kind for b in BLOCKS]
    assert kinds.count("console") >= 19 and kinds.count("bash") >= 4


@pytest.fixture(scope="module")
def env() -> dict[str, str]:
    return environment(Path(sys.executable).parent)


@pytest.mark.parametrize("block", BLOCKS, ids=lambda b: b.where)
def test_every_shell_block_prints_what_it_shows(block: Block, env: dict[str, str], tmp_path: Path) -> None:
    where = mirror(tmp_path / "repo")
    skipped = not_here(block)
    if block.kind == "console":
        assert not skipped, f"{block.where}: a console block runs whole"
        for c in block.commands:
            literal = [line for line in c.shown if line.strip() and not line.rstrip().endswith(("...", "…"))]
            assert literal or not c.shown, (
                f"{block.where}: `$ {c.text}` shows only elisions: it checks nothing"
            )
            _, out = shell(c.text, where, env)
            assert matches(c.shown, out), (
                f"{block.where}: `$ {c.text}` printed\n{out}\n-- but the block shows --\n"
                + "\n".join(c.shown)
            )
        return
    script = [c.text for c in block.commands if (block.page, command(c.text)) not in skipped]
    if not script:
        assert block.shown is None, f"{block.where}: an output is shown for commands that are not run"
        return
    assert not (skipped and block.shown is not None), f"{block.where}: output shown for a partly run block"
    status, out = shell("\n".join(script), where, env)
    assert status == 0, f"{block.where}: exit {status}\n{out}"
    if block.shown is not None:
        assert matches(block.shown, out), (
            f"{block.where}: printed\n{out}\n-- but the page shows --\n" + "\n".join(block.shown)
        )


@pytest.mark.parametrize(("page", "line"), sorted(NEEDS_ROS), ids=lambda x: x)
def test_every_ros_command_of_the_docs_parses_and_names_files_that_exist(page: str, line: str) -> None:
    words = shlex.split(line)
    assert Path(words[0]).name == "cosleec", line
    rest, _ = ros.split_ros_args(words[1:])
    build_parser().parse_args(rest)  # exits 2 on a usage error
    for word in rest:
        if re.search(r"\.(sleec|yaml|yml|py|jsonl|json|txt)$", word):
            assert (ROOT / word).is_file(), f"{page}: {line}: no file {word}"


# the rules themselves: a stale output must fail
@pytest.mark.parametrize(
    ("shown", "output", "ok"),
    [
        (["a", "b"], "a\nb\n", True),
        (["a", "b"], "a\nb  \n\n", True),
        (["a", "b"], "a\nc\n", False),
        (["a"], "a\nb\n", False),  # a line not shown is not elided silently
        (["a", "..."], "a\nb\nc\n", True),
        (["...", "c"], "a\nb\nc\n", True),
        (["a", "...", "c"], "a\nc\n", True),
        (["a", "...", "d"], "a\nb\nc\n", False),
        (["3 findings ..."], "3 findings (0.10 s)\n", True),
        (["3 findings …"], "4 findings (0.10 s)\n", False),
        (["a ..."], "a b\nc\n", False),  # one line only
        ([], "", True),
        ([], "something\n", False),
    ],
)
def test_the_matching_rules(shown: list[str], output: str, ok: bool) -> None:
    assert matches(shown, output) is ok
