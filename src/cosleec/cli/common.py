"""Helpers shared by the sub-commands."""

from __future__ import annotations

import sys
from pathlib import Path

from rich.console import Console


def expand(paths: list[str]) -> list[Path]:
    """Files as given; a directory stands for the ``*.sleec`` files below it."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(p.rglob("*.sleec")))
        else:
            out.append(p)
    return out


def console(stderr: bool = False) -> Console:
    """A rich console on stdout (or stderr) without highlighting or hard wraps, so output pipes cleanly."""
    return Console(stderr=stderr, highlight=False, soft_wrap=True, file=sys.stderr if stderr else sys.stdout)
