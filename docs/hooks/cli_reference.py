"""MkDocs hook: the command-line reference, generated from the argument parser (not written twice).

`docs/cli.md` holds the marker `<!-- cli-reference -->`; this replaces it with the help of
`cosleec` and of every sub-command, as `cosleec ... --help` prints it.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

MARKER = "<!-- cli-reference -->"


def _helps(parser: argparse.ArgumentParser, words: list[str]) -> list[tuple[str, str]]:
    out = [(" ".join(words), parser.format_help())]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if sub.prog.endswith(name) and name not in {w for w in words}:
                    out += _helps(sub, [*words, name])
    return out


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """MkDocs calls it for every page: the page with the help texts in place of the marker."""
    if MARKER not in markdown:
        return markdown
    from cosleec.cli.main import build_parser

    os.environ["COLUMNS"] = "100"  # argparse wraps at the terminal width: the same text everywhere
    seen: set[str] = set()
    parts = []
    for words, text in _helps(build_parser(), ["cosleec"]):
        if words in seen:
            continue
        seen.add(words)
        level = "##" if words.count(" ") <= 1 else "###"
        parts.append(f"{level} `{words}`\n\n```text\n{text.rstrip()}\n```\n")
    return markdown.replace(MARKER, "\n".join(parts))
