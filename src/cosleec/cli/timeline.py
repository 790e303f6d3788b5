"""``cosleec timeline``: a recorded run over time, as a picture (PNG, SVG) or an interactive page (HTML)."""

from __future__ import annotations

import argparse
from pathlib import Path

from cosleec.cli.common import output_file
from cosleec.errors import UserError
from cosleec.views import TIMELINE_FORMATS, Timeline, timeline_html, timeline_image


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec timeline`` and its options."""
    p = sub.add_parser(
        "timeline",
        help="draw a recorded run over time: measures, active layers, decisions, obligations and their outcomes",
        description="Draw a run from its audit log (AUDIT.jsonl, e.g. cosleec demo --audit FILE) or a Manager "
        "node's recording (RUN.mcap): measure values as steps, each rule's active layer as bands, triggers and "
        "decisions as markers, each obligation as a bar from trigger to deadline coloured by outcome, "
        "otherwise chains as arrows.",
    )
    p.add_argument(
        "run_file",
        metavar="AUDIT.jsonl|RUN.mcap|BAG",
        help="the audit log or MCAP recording of a run, or (with --mapping and --rules) a field bag of the "
        "robot's own topics",
    )
    p.add_argument(
        "--mapping",
        metavar="MAPPING.yaml",
        help="with a field bag (rosbag2 MCAP or SQLite 3, ROS 1 .bag): the Context Listener's mapping that "
        "turns its topics into measures and events",
    )
    p.add_argument("--rules", metavar="RULES", help="with --mapping: the rule file the bag is run through")
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="write here; the format follows the extension: .png or .svg (matplotlib), .html (Plotly, "
        "interactive, opens offline). Default: the input's name with .html",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Draw; exit 0, or 1 for a run file that cannot be read, an output that cannot be written
    (or would replace the input), an unknown format, or a missing matplotlib/Plotly."""
    source = Path(args.run_file)
    out = Path(args.output) if args.output is not None else source.with_suffix(".html")
    fmt = check_output(out, "-o" if args.output is not None else "the default output")
    if out.exists() and source.exists() and out.resolve() == source.resolve():
        raise UserError(
            "refusing to overwrite the run file with its own picture",
            where=str(out),
            hint="give -o another file name (.png, .svg or .html)",
        )
    tl = _bag(args, source) if args.mapping is not None or args.rules is not None else Timeline.read(source)
    write(tl, out, fmt)
    print(
        f"{out}: {len(tl.rules)} rule(s), {len(tl.bars)} obligation(s), t = {tl.start:g} to {tl.end:g} s ({fmt})"
    )
    return 0


def _bag(args: argparse.Namespace, source: Path) -> Timeline:
    """A field bag's timeline: its steps through the mapping and the rules (bag_timeline.py)."""
    if args.mapping is None or args.rules is None:
        given, missing = ("--mapping", "--rules") if args.mapping is not None else ("--rules", "--mapping")
        raise UserError(
            f"{given} draws a field bag, which also needs {missing}",
            hint="cosleec timeline BAG --mapping MAPPING.yaml --rules RULES.sleec",
        )
    from cosleec.cli.bag_timeline import bag_records  # (rosbags: the bags extra, only here)

    return Timeline.from_records(bag_records(str(source), args.mapping, args.rules), source=str(source))


def check_output(out: Path, option: str) -> str:
    """The format ``out`` asks for (its extension), once it is known that it can be written there.

    UserError for an extension not in :data:`cosleec.views.TIMELINE_FORMATS` or a directory
    that does not exist (none is created).
    """
    fmt = out.suffix.lower().lstrip(".")
    if fmt not in TIMELINE_FORMATS:
        raise UserError(
            f"cannot tell what to draw {out} as: {out.suffix or 'no extension'}",
            where=str(out),
            hint=f"end the file name with one of {', '.join('.' + f for f in TIMELINE_FORMATS)}",
        )
    output_file(str(out), "the timeline", option)
    return fmt


def write(tl: Timeline, out: Path, fmt: str) -> None:
    """Draw ``tl`` as ``fmt`` and write it to ``out``; UserError when it cannot be written."""
    data = timeline_html(tl).encode() if fmt == "html" else timeline_image(tl, fmt)
    try:
        out.write_bytes(data)
    except OSError as e:
        raise UserError(f"cannot write the timeline: {e.strerror or e}", where=str(out)) from None
