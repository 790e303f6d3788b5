"""``cosleec scaffold``: the Python module a developer fills in to implement a rule set."""

from __future__ import annotations

import argparse
import difflib
import sys
from pathlib import Path

from cosleec.errors import UserError
from cosleec.runtime import SCAFFOLD_STYLES, RuleSet, scaffold


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec scaffold`` and its options."""
    p = sub.add_parser(
        "scaffold",
        help="write the Python module that implements the rules: a default and one method per hedge",
    )
    p.add_argument("rules", metavar="RULES", help="the rule file to implement")
    p.add_argument(
        "--rule",
        action="append",
        metavar="R",
        help="implement only this rule (repeatable; default: every rule)",
    )
    p.add_argument(
        "--style",
        choices=SCAFFOLD_STYLES,
        default="task",
        help="task: a class per rule with a method per clause (the paper's style, default); "
        "capability: a handler per event the rules oblige",
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="FILE.py",
        help="write the module here (refused if the file exists: it may hold your code); default: stdout",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Write the module; exit 0, or 1 for a rule file with errors, an unknown rule, an existing output."""
    rules = RuleSet.from_file(args.rules)
    if args.rule:
        names = [r.name for r in rules.rules]
        for name in args.rule:
            if name not in names:
                close = difflib.get_close_matches(name, names, n=1)
                raise UserError(
                    f"no rule {name!r} in {args.rules}",
                    hint=f"did you mean {close[0]!r}?" if close else f"rules: {', '.join(names)}",
                )
    text = scaffold(rules, only=args.rule, rules_path=args.rules, style=args.style)
    if args.output is None:
        sys.stdout.write(text)
        return 0
    out = Path(args.output)
    if out.exists():
        raise UserError(
            f"{out} exists: scaffold never overwrites a module (it may hold your code)",
            hint="write to a new file, or remove this one first",
        )
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as e:
        raise UserError(f"cannot write {out}: {e.strerror or e}", hint="check the directory exists") from None
    print(
        f"{out}: {len(args.rule) if args.rule else len(rules.rules)} rule(s) to implement ({args.style} style)"
    )
    return 0
