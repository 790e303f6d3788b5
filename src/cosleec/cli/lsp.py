"""``cosleec lsp``: the language server, for editors (docs/editors.md)."""

from __future__ import annotations

import argparse

from cosleec.errors import UserError


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec lsp``."""
    p = sub.add_parser(
        "lsp",
        help="run the language server over stdio (for editors: VS Code, Neovim, Helix, ...)",
        description="Speak the Language Server Protocol on stdin and stdout: diagnostics as you "
        "type (as `cosleec check`), `cosleec analyse` findings on save, hover, go-to-definition, "
        "references, completion, outline, formatting (as `cosleec fmt`) and rename. Options come "
        "from the client's initializationOptions (docs/editors.md).",
    )
    p.add_argument(
        "--stdio", action="store_true", help="use stdin and stdout (the default; editors often pass it)"
    )
    p.add_argument(
        "--max-message",
        type=_count,
        metavar="BYTES",
        help="refuse (answer with an error, skip) a message longer than this (default 16777216: 16 MiB)",
    )
    p.add_argument(
        "--max-depth",
        type=_count,
        metavar="N",
        help="refuse a message that nests arrays and objects deeper than this (default 100)",
    )
    p.set_defaults(run=run)


def _count(text: str) -> int:
    if not text.isascii() or not text.isdigit() or not 1 <= int(text) <= 2**40:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a whole number from 1 to {2**40}")
    return int(text)


def run(args: argparse.Namespace) -> int:
    """Serve until the client exits."""
    try:  # pygls is the `lsp` extra: every other command works without it
        from cosleec.lsp import Limits, serve_stdio
    except ModuleNotFoundError as e:
        if e.name not in ("pygls", "lsprotocol") and not str(e.name).startswith(("pygls.", "lsprotocol.")):
            raise
        raise UserError(
            f"cosleec lsp needs {e.name}, which is not installed",
            hint="pip install 'cosleec[lsp]' (bash scripts/setup --dev installs it)",
        ) from None
    given = {"max_message": args.max_message, "max_depth": args.max_depth}
    serve_stdio(Limits(**{k: v for k, v in given.items() if v is not None}))
    return 0
