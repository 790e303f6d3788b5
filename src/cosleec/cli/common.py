"""Helpers shared by the sub-commands."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rich.console import Console

from cosleec.errors import UserError
from cosleec.lang import CANCEL, PRIORITY_SEMANTICS, HedgeSemantics, Unknowns


def expand(paths: list[str]) -> list[Path]:
    """Files as given; a directory stands for the ``*.sleec`` files below it."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(p.rglob("*.sleec"))
            if not found:  # checking nothing must not look like a pass
                raise UserError(
                    "no .sleec file in this directory",
                    where=str(p),
                    hint="give rule files or a directory of them",
                )
            out.extend(found)
        else:
            out.append(p)
    return out


def input_file(path: str, what: str, *, text: bool = False) -> str:
    """``path`` if it names a file that can be opened for reading; else a UserError naming it.

    ``what`` says what the file is for (``the mapping``): "cannot read the mapping: no such
    file", "... is a directory"; with ``text``, a regular file that is not UTF-8 is refused
    too, at the line and column of its first bad byte. Whether its content is right is for
    its reader to say.
    """
    p = Path(path)
    if p.is_dir():
        raise UserError(f"cannot read {what}: it is a directory", where=path, hint=f"give the file of {what}")
    try:
        with p.open("rb"):
            pass
    except OSError as e:
        raise UserError(
            f"cannot read {what}: {e.strerror or e}",
            where=path,
            hint="check the path (relative paths are from the current directory)"
            if isinstance(e, FileNotFoundError)
            else "check the file's permissions",
        ) from None
    if text and p.is_file():
        data = p.read_bytes()
        try:
            data.decode("utf-8")
        except UnicodeDecodeError as e:
            line = data.count(b"\n", 0, e.start) + 1
            col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
            raise UserError(
                f"cannot read {what}: it is not UTF-8 text (byte 0x{data[e.start]:02x})",
                where=f"{path}:{line}:{col}",
                hint="give the text file (YAML), saved as UTF-8",
            ) from None
    return path


def output_file(path: str, what: str, option: str) -> str:
    """``path`` if a file can be written there: its directory exists (none is created) and it is no directory.

    ``what`` says what is written (``the audit log``), ``option`` the option that gave
    ``path`` (``--audit``); a UserError names both and the fix.
    """
    p = Path(path)
    if p.is_dir():
        raise UserError(
            f"cannot open {what}: {option} names a directory",
            where=path,
            hint=f"give a file name, e.g. {option} {p / 'out'}",
        )
    parent = p.parent
    if parent.exists() and not parent.is_dir():
        raise UserError(
            f"cannot open {what}: {parent} is a file, not a directory",
            where=path,
            hint=f"give {option} a path in a directory",
        )
    if not parent.is_dir():
        raise UserError(
            f"cannot open {what}: the directory {parent} does not exist (cosleec creates no directory)",
            where=path,
            hint=f"create it first (mkdir -p {parent}), or give {option} a path in a directory that exists",
        )
    return path


def console(stderr: bool = False) -> Console:
    """A rich console on stdout (or stderr) without highlighting or hard wraps, so output pipes cleanly."""
    return Console(stderr=stderr, highlight=False, soft_wrap=True, file=sys.stderr if stderr else sys.stdout)


def add_clause_options(
    p: argparse.ArgumentParser, *, unknown: bool = True, semantics_help: str | None = None
) -> None:
    """``--semantics`` (and ``--unknown``): how a rule's clauses are chosen, as the user types them."""
    p.add_argument(
        "--semantics",
        choices=[str(s) for s in HedgeSemantics],
        default=None,  # not given: the rule file's semantics block, else last-wins
        help=semantics_help
        or "how the unless clauses of a rule combine (default: the rule file's semantics block, else "
        "last-wins, as SLEEC); one that contradicts the file's block is an error",
    )
    if unknown:
        p.add_argument(
            "--unknown",
            choices=[str(u) for u in Unknowns],
            default=str(Unknowns.UNDETERMINED),
            help="how a clause condition over a measure with no value is read (default: undetermined, fail closed)",
        )


def add_priority_options(p: argparse.ArgumentParser, *, lead: bool = False) -> None:
    """``--priority "H > L"`` (repeatable) and ``--priority-semantics``; with ``lead``, ``--priority-lead``."""
    p.add_argument(
        "--priority",
        action="append",
        default=[],
        metavar='"H > L"',
        help="rule H prevails over rule L when they conflict (repeatable; adds to the file's own priorities)",
    )
    p.add_argument(
        "--priority-semantics",
        choices=list(PRIORITY_SEMANTICS),
        default=CANCEL,
        help="cancel: L is cancelled when H is triggered while L is active (default); "
        "conflict-aware: L holds until H's deadline forces it",
    )
    if lead:
        p.add_argument(
            "--priority-lead",
            type=float,
            default=0.0,
            metavar="SECONDS",
            help="conflict-aware: cancel L this long before H's deadline, so the robot has time to act",
        )


def port(text: str) -> int:
    """An argparse type: a TCP port from 0 to 65535 (0 picks a free one), for ``--web``."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r}: a port is a number from 0 to 65535 (0: a free one)")
    return value
