"""``cosleec demo``: the assistive-care example, embedded in one process (no ROS)."""

from __future__ import annotations

import argparse

from cosleec import demo
from cosleec.cli.common import add_clause_options


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec demo`` and its options."""
    p = sub.add_parser("demo", help="run the assistive-care example in one process")
    p.add_argument("--json", action="store_true", help="print runtime events as JSON lines")
    add_clause_options(p, unknown=False)
    p.add_argument("--audit", metavar="FILE", help="also write the audit trail (JSON Lines)")
    p.add_argument(
        "--journal",
        metavar="FILE",
        help="keep the Manager's state in this SQLite journal (restored by the next run, even after a crash)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run the embedded demo (:func:`cosleec.demo.main`)."""
    return demo.main(as_json=args.json, semantics=args.semantics, audit=args.audit, journal=args.journal)
