"""``cosleec fmt``: rule files in canonical form, comments and blank lines kept.

Three ways to use it, as with the formatters programmers know: print the formatted file
(the default), ``--check`` (exit 1 and show a diff when a file is not formatted: for CI and
pre-commit hooks) and ``--in-place`` (rewrite the files that change, atomically).
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import sys
from pathlib import Path

from cosleec.cli.atomic import replace_file
from cosleec.errors import UserError
from cosleec.lang import WIDTH, SleecError, analyse_file, format_source


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec fmt`` and its options."""
    p = sub.add_parser(
        "fmt",
        help="format rule files: canonical form, comments kept, long rules one clause per line",
        description="Print FILE in canonical form, keeping its comments and blank lines; "
        "rules longer than --width are printed one clause per line. With --check or "
        "--in-place, any number of files.",
    )
    p.add_argument("files", nargs="+", metavar="FILE", help="the rule files")
    p.add_argument(
        "--dialect",
        choices=["tk", "legos", "paper"],
        default=None,
        help="notation to print in (default: each file's own); `paper` is the CO-SLEEC "
        "paper's WHEN ... THEN ... UNLESS ... IN WHICH CASE ...",
    )
    mode = p.add_mutually_exclusive_group()
    mode.add_argument(
        "--check",
        action="store_true",
        help="change nothing; exit 1 and print a diff if any file is not formatted",
    )
    mode.add_argument(
        "-i", "--in-place", action="store_true", help="rewrite the files that are not formatted"
    )
    p.add_argument(
        "--width",
        type=_width,
        default=WIDTH,
        help=f"print a rule one clause per line when it is longer than this (default {WIDTH})",
    )
    p.add_argument(
        "--infer-defs", action="store_true", help="infer declarations for files without a def block"
    )
    p.set_defaults(run=run)


def _width(text: str) -> int:
    try:
        width = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if width < 20:
        raise argparse.ArgumentTypeError(f"{width} is too narrow: give 20 or more")
    return width


def run(args: argparse.Namespace) -> int:
    """Format each file; 0 when all is well, 1 on a rule error or (``--check``) an unformatted file."""
    files: list[str] = args.files
    if len(files) > 1 and not (args.check or args.in_place):
        print(
            "cosleec fmt: error: several files need --check or --in-place "
            "(printing them one after another would make one file of them)",
            file=sys.stderr,
        )
        return 2
    status = 0
    for path in files:
        status = max(status, _one(path, args))
    return status


def _one(path: str, args: argparse.Namespace) -> int:
    result = analyse_file(path, infer_defs=args.infer_defs)
    # a file mixing the dialects is what `--dialect` is for: its conversion is checked below
    mixed = args.dialect in ("tk", "legos") and all(d.code == "mixed-dialect" for d in result.errors)
    if result.spec is None or not (result.ok or mixed):
        print(result.render(), file=sys.stderr)
        return 1
    try:
        text = format_source(result.source, result.spec, args.dialect, args.width)
    except SleecError as e:
        print(e.render(), file=sys.stderr)
        return 1
    source = result.source
    if source.startswith("\ufeff"):
        text = "\ufeff" + text
    if "\r\n" in source:
        text = text.replace("\n", "\r\n")
    if args.check:
        if text == source:
            return 0
        diff = difflib.unified_diff(_lines(source), _lines(text), fromfile=path, tofile=f"{path} (formatted)")
        for line in diff:  # as diff(1) writes it, so that patch(1) applies it
            sys.stdout.write(line if line.endswith("\n") else line + "\n\\ No newline at end of file\n")
        print(f"{path}: would be reformatted (cosleec fmt --in-place {path})", file=sys.stderr)
        return 1
    if args.in_place:
        if text != source:
            _replace(Path(path), text)
            print(f"{path}: reformatted", file=sys.stderr)
        return 0
    sys.stdout.write(text)
    return 0


def _lines(text: str) -> list[str]:
    """Lines as SLEEC and diff(1) see them: ended by "\\n" only (not by U+2028, form feeds...)."""
    return re.findall(r"[^\n]*\n|[^\n]+$", text)


def _replace(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (atomic.py), a read-only file refused first."""
    if not os.access(path.resolve(), os.W_OK):
        raise UserError(
            f"{path.resolve()}: the file is read-only", hint="make it writable, or print to stdout"
        )
    replace_file(path, text)
