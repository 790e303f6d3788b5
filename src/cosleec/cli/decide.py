"""``cosleec decide``: what the rules require when EVENT happens in a given context."""

from __future__ import annotations

import argparse
import json
import sys

from cosleec.cli.common import add_clause_options
from cosleec.runtime import ContextError, Manager, RuleSet, VirtualClock


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec decide`` and its options."""
    p = sub.add_parser("decide", help="evaluate the rules triggered by an event against given values")
    p.add_argument("rules", metavar="RULES")
    p.add_argument("--event", required=True, metavar="EVENT")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        dest="values",
        help="a measure value: true/false, a number, or a scale literal",
    )
    add_clause_options(p, unknown=False)
    p.add_argument("--json", action="store_true")
    p.add_argument("--infer-defs", action="store_true")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Decide ``--event`` against the ``--set`` values and print each explanation (or JSON).

    Nothing is dispatched: no task runs. Returns 0 with the decisions; 2 for a malformed
    or unknown ``--set``, an unknown event, or a decision left undetermined for lack of a
    value. Errors in the rule file raise SleecError, which :func:`cosleec.cli.main.main`
    reports with exit 1.
    """
    rules = RuleSet.from_file(args.rules, infer_defs=args.infer_defs)  # SleecError: the CLI shows it, exit 1
    m = Manager(rules, semantics=args.semantics, clock=VirtualClock(), dispatch=False)
    conflicts: list[dict[str, object]] = []
    cancelled: list[dict[str, object]] = []
    m.subscribe(lambda ev: conflicts.append(ev.data) if ev.kind == "conflict" else None)
    m.subscribe(lambda ev: cancelled.append(ev.data) if ev.kind == "cancelled" else None)
    values = {}
    for item in args.values:
        name, sep, text = item.partition("=")
        name = name.strip()
        spec = m.ruleset.measures.get(name)
        if not sep:
            print(f"cosleec decide: --set {item!r}: expected NAME=VALUE", file=sys.stderr)
            return 2
        if spec is None:
            print(f"cosleec decide: --set {name}: no measure named {name!r}", file=sys.stderr)
            return 2
        try:
            values[name] = spec.external(spec.parse(text))
        except ContextError as e:
            print(f"cosleec decide: --set {name}: {e}", file=sys.stderr)
            return 2
    if args.event not in m.ruleset.events:
        print(f"cosleec decide: --event {args.event}: no event named {args.event!r}", file=sys.stderr)
        return 2
    if values:
        m.update(values)
    decisions = m.event(args.event)
    undetermined = [d for d in decisions if d.clause is None]
    if undetermined:
        names = sorted({n for d in undetermined for n in d.missing})
        print(
            f"cosleec decide: no value for {', '.join(names)} (needed by "
            f"{', '.join(d.rule for d in undetermined)}); give it with --set",
            file=sys.stderr,
        )
        return 2
    if args.json:
        doc = {
            "event": args.event,
            "decisions": [
                {
                    "rule": d.rule,
                    "clause": d.clause,
                    "layer": d.layer,
                    "obligations": [o.to_json() for o in d.obligations],
                }
                for d in decisions
            ],
            "conflicts": conflicts,
            "cancelled": cancelled,
        }
        print(json.dumps(doc, indent=2))
    else:
        if not decisions:
            print(f"{args.event}: no rule applies")
        for d in decisions:
            print(d.explanation)
        for c in conflicts:
            print(f"conflict: {c['explanation']}")
        for c in cancelled:
            print(f"cancelled: {c['rule']}, by the priority of {c['by']} ({c['priority']})")
    return 0
