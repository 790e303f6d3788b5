"""``cosleec decide``: what the rules require when EVENT happens in a given context."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Iterable

from cosleec.cli.common import add_clause_options
from cosleec.errors import closest
from cosleec.runtime import ContextError, Manager, MeasureSpec, RuleSet, VirtualClock

CONDITION_WIDTH = 100
"""The text view shortens a longer condition (``--json`` has it whole): Decision.explain."""


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec decide`` and its options."""
    p = sub.add_parser("decide", help="evaluate the rules triggered by an event against given values")
    p.add_argument("rules", metavar="RULES", help="the rule file")
    p.add_argument(
        "--event", required=True, metavar="EVENT", help="the event that happens (declared in RULES)"
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        dest="values",
        help="a measure value: true/false, a number, or a scale literal",
    )
    add_clause_options(p, unknown=False)
    p.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    p.add_argument(
        "--explanations",
        metavar="FILE",
        help="what the robot says to people, rule by rule (YAML); each decision's sentence is printed",
    )
    p.add_argument(
        "--infer-defs", action="store_true", help="infer declarations for files without a def block"
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Decide ``--event`` against the ``--set`` values and print each explanation (or JSON).

    Nothing is dispatched: no task runs. Returns 0 with the decisions; 2 for a malformed
    or unknown ``--set``, an unknown event, or a decision left undetermined for lack of a
    value. Errors in the rule file raise SleecError, which :func:`cosleec.cli.main.main`
    reports with exit 1.
    """
    rules = RuleSet.from_file(args.rules, infer_defs=args.infer_defs)  # SleecError: the CLI shows it, exit 1
    m = Manager(
        rules, semantics=args.semantics, clock=VirtualClock(), dispatch=False, explanations=args.explanations
    )  # ExplanationsError at file:line:col for a sentence the rules do not fit: exit 1
    quiet = logging.getLogger("cosleec.runtime")
    level, quiet.level = quiet.level, logging.ERROR  # whether the rules can conflict is `analyse`'s to say
    try:
        m.start(check=False)  # nothing is dispatched: nothing to implement
    finally:
        quiet.setLevel(level)
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
            hint = f"e.g. --set {name or 'MEASURE'}=true"
            print(f"cosleec decide: --set {item!r}: expected NAME=VALUE\n  hint: {hint}", file=sys.stderr)
            return 2
        if spec is None:
            hint = _hint(name, m.ruleset.measures, "measure")
            if name in m.ruleset.events and not hint.startswith("did you mean"):
                hint = f"{name} is an event: give it with --event {name}"
            print(
                f"cosleec decide: --set {name}: the rules declare no measure {name!r}\n  hint: {hint}",
                file=sys.stderr,
            )
            return 2
        try:
            values[name] = spec.external(spec.parse(text))
        except ContextError as e:
            print(
                f"cosleec decide: --set {name}: {e.message}\n  hint: {_kind_hint(spec, text)}",
                file=sys.stderr,
            )
            return 2
    if args.event not in m.ruleset.events:
        hint = _hint(args.event, m.ruleset.events, "event")
        if args.event in m.ruleset.measures and not hint.startswith("did you mean"):
            hint = f"{args.event} is a measure: give its value with --set {args.event}=VALUE"
        print(
            f"cosleec decide: --event {args.event}: the rules declare no event {args.event!r}\n  hint: {hint}",
            file=sys.stderr,
        )
        return 2
    if values:
        m.update(values)
    decisions = m.event(args.event)
    undetermined = [d for d in decisions if d.clause is None]
    if undetermined:
        names = sorted({n for d in undetermined for n in d.missing})
        print(
            f"cosleec decide: no value for {_some(names)} (needed by "
            f"{_some([d.rule for d in undetermined])}); give it with --set",
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
                    "explanation": d.explanation,  # whole: the text view shortens long conditions
                    "for_people": d.for_people,
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
            print(d.explain(width=CONDITION_WIDTH))
            if args.explanations:
                print(f"  says: {d.for_people}")
        for c in conflicts:
            print(f"conflict: {c['explanation']}")
        for c in cancelled:
            print(f"cancelled: {c['rule']}, by the priority of {c['by']} ({c['priority']})")
    return 0


def _some(names: list[str], most: int = 12) -> str:
    """``a, b, c`` -- at most ``most`` of ``names``, then how many more (a generated rule set
    may need 10,000 values)."""
    more = f", ... ({len(names) - most:,} more)" if len(names) > most else ""
    return ", ".join(names[:most]) + more


def _hint(name: str, declared: Iterable[str], what: str) -> str:
    """Did you mean the closest declared name? Else the names declared (or that there are none)."""
    names = sorted(declared)
    close = closest(name, names)
    if close:
        return f"did you mean {close!r}?"
    if not names:
        return f"the rules declare no {what}"
    return f"the rules declare the {what}s {_some(names)}"


def _kind_hint(spec: MeasureSpec, text: str) -> str:
    """What a value of this measure looks like on the command line."""
    if spec.kind == "boolean":
        return f"{spec.name} is boolean: --set {spec.name}=true or --set {spec.name}=false"
    if spec.kind == "numeric":
        return f"{spec.name} is numeric: a finite number, e.g. --set {spec.name}=3 or --set {spec.name}=0.5"
    close = closest(text.strip(), spec.literals)
    return (f"did you mean {close!r}? " if close else "") + (
        f"{spec.name} is a scale: one of its literals, {', '.join(spec.literals)}"
    )
