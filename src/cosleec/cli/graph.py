"""``cosleec graph``: the rule set as a picture (Graphviz SVG/PNG/DOT, Mermaid)."""

from __future__ import annotations

import argparse
import difflib
import sys
from pathlib import Path

from cosleec.errors import UserError
from cosleec.runtime import RuleSet
from cosleec.views import FORMATS, analysed_conflicts, build, check_drawable, render, to_dot, to_mermaid


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec graph`` and its options."""
    p = sub.add_parser(
        "graph",
        help="draw the rules as COP sees them: a cluster per rule with its layers, shared events and "
        "measures, priorities and possible conflicts",
    )
    p.add_argument("rules", metavar="RULES", help="the rule file to draw")
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="write here; the format follows the extension: .svg, .png (Graphviz), .dot, .mmd (Mermaid). "
        "Default: DOT text on stdout",
    )
    p.add_argument(
        "--rule",
        action="append",
        metavar="R",
        help="draw only this rule (repeatable), with the events and measures it touches",
    )
    p.add_argument(
        "--analyse",
        action="store_true",
        help="draw as red edges the conflicts `cosleec analyse` finds (z3: proved, or up to its bound) "
        "instead of the quick pairwise check",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Draw; exit 0, or 1 for a rule file with errors, an unknown rule, an unknown format, a
    missing Graphviz or a file that cannot be written."""
    fmt = "dot"
    out: Path | None = None
    if args.output is not None:
        out = Path(args.output)
        fmt = out.suffix.lower().lstrip(".")
        if fmt not in FORMATS:
            raise UserError(
                f"cannot tell what to draw {out} as: {out.suffix or 'no extension'}",
                hint=f"end the file name with one of {', '.join('.' + f for f in FORMATS)}",
            )
    rules = RuleSet.from_file(args.rules)
    names = [r.name for r in rules.rules]
    for name in args.rule or ():
        if name not in names:
            close = difflib.get_close_matches(name, names, n=1)
            raise UserError(
                f"no rule {name!r} in {args.rules}",
                hint=f"did you mean {close[0]!r}?" if close else f"rules: {', '.join(names)}",
            )
    check_drawable(rules, args.rule or ())  # before the analysis: a picture too large is said at once
    conflicts = analysed_conflicts(args.rules) if args.analyse else None
    graph = build(rules, args.rule or (), conflicts, fmt=fmt)
    if fmt == "mmd":
        data = to_mermaid(graph).encode()
    else:
        dot = to_dot(graph, args.rules)
        data = dot.encode() if fmt == "dot" else render(dot, fmt)
    if out is None:
        sys.stdout.write(data.decode())
        return 0
    try:
        out.write_bytes(data)
    except OSError as e:
        raise UserError(f"cannot write {out}: {e.strerror or e}", hint="check the directory exists") from None
    print(f"{out}: {len(graph.clusters)} rule(s) drawn ({fmt})")
    return 0
