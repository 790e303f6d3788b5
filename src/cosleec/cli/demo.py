"""``cosleec demo``: the assistive-care example, embedded in one process (no ROS)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cosleec import demo
from cosleec.cli import timeline
from cosleec.cli.common import add_clause_options, output_file, port
from cosleec.errors import UserError
from cosleec.lang import HedgeSemantics
from cosleec.runtime import Manager
from cosleec.views import Timeline, View, load_view


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
    p.add_argument(
        "--reset-journal",
        action="store_true",
        help="with --journal: start afresh from a journal the Manager refused (a lost or damaged -wal, "
        "an old copy); the reset and what was lost are recorded in the audit trail",
    )
    p.add_argument(
        "--plot",
        metavar="FILE",
        help="draw the run's timeline to FILE once the day is over: .png, .svg or .html (see cosleec timeline)",
    )
    p.add_argument(
        "--web",
        nargs="?",
        const=0,
        type=port,
        metavar="PORT",
        help="serve the live web view on 127.0.0.1:PORT (default: a free port), pace the day for a "
        "watcher, then serve on until Ctrl-C",
    )
    p.add_argument(
        "--pace",
        type=pace,
        default=None,
        metavar="SECONDS",
        help="with --web: seconds between two steps of the day (default 1; 0: no pause)",
    )
    p.set_defaults(run=run)


def pace(text: str) -> float:
    """An argparse type: seconds between two steps, 0 or more (at most an hour)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not 0 <= value <= 3600:
        raise argparse.ArgumentTypeError(f"{text!r}: give 0 to 3600 seconds")
    return value


def _web_view(web_port: int) -> Callable[[Manager], View]:
    """``--web PORT``: how the demo attaches the live web view to its Manager. The view is
    found now, so a missing ``web`` extra is said before the demo opens a file or prints."""
    factory = load_view("web")
    return lambda manager: factory(manager, web_port)


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
    elif args.reset_journal:
        raise UserError("--reset-journal needs --journal", hint="give the journal to start afresh from")
    plot: Callable[[demo.Run], None] | None = None
    if args.plot:
        out, fmt = Path(args.plot), timeline.check_output(Path(args.plot), "--plot")

        def draw(done: demo.Run) -> None:  # the run drawn, as `cosleec timeline` draws an audit log
            timeline.write(Timeline.from_records(done.records(), "cosleec demo"), out, fmt)
            print(f"timeline: {out}", file=sys.stderr if args.json else sys.stdout)

        plot = draw
    if args.pace is not None and args.web is None:
        raise UserError("--pace needs --web", hint="the day is paced for someone watching the live web view")
    web: dict[str, Any] = (
        {"view": _web_view(args.web), "pace": demo.PACE_S if args.pace is None else args.pace}
        if args.web is not None
        else {}
    )
    return demo.main(
        as_json=args.json,
        semantics=args.semantics or str(HedgeSemantics.LAST_WINS),  # the demo's rules declare none
        audit=args.audit,
        journal=args.journal,
        reset_journal=args.reset_journal,
        on_done=plot,
        **web,
    )
