"""``cosleec demo``: the assistive-care example, embedded in one process (no ROS)."""

from __future__ import annotations

import argparse
from pathlib import Path

from cosleec import demo
from cosleec.cli.common import add_clause_options, output_file
from cosleec.errors import UserError


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec demo`` and its options."""
    p = sub.add_parser("demo", help="run the assistive-care example in one process")
    p.add_argument("--json", action="store_true", help="print runtime events as JSON lines")
    add_clause_options(p, unknown=False)
    p.add_argument(
        "--audit",
        metavar="FILE",
        help="also write the audit trail (JSON Lines) to FILE, a new file in a directory that exists",
    )
    p.add_argument(
        "--append",
        action="store_true",
        help="with --audit: add this run's records to an existing audit trail (default: refuse to)",
    )
    p.add_argument(
        "--journal",
        metavar="FILE",
        help="keep the Manager's state in this SQLite journal (restored by the next run, even after a crash)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run the embedded demo (:func:`cosleec.demo.main`).

    ``--audit`` and ``--journal`` are checked first, so a mistake is said before the demo
    prints anything: no directory is created, and an existing audit trail is not added to
    without ``--append`` (one log must not silently mix two runs). An existing journal is
    meant: the next run restores it.
    """
    if args.append and not args.audit:
        raise UserError("--append needs --audit FILE", hint="give the audit trail to append to with --audit")
    if args.audit:
        output_file(args.audit, "the audit log", "--audit")
        if not args.append and Path(args.audit).exists():
            raise UserError(
                "cannot open the audit log: the file exists, and an audit trail must not mix two runs",
                where=args.audit,
                hint="remove it, give --audit a new file name, or add --append to add this run to it",
            )
    if args.journal:
        output_file(args.journal, "the journal", "--journal")
    return demo.main(as_json=args.json, semantics=args.semantics, audit=args.audit, journal=args.journal)
