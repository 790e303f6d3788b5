"""``cosleec conforms``: does a recorded run (a trace or an audit log) obey the rules?

The run is judged ex post by the reference semantics (:mod:`cosleec.semantics`), not by the
runtime, so a Manager's audit log can be checked against the rules it ran or against a new
version of them (issue 12). Exit codes: 0 the trace conforms up to its last time (what is
still pending is printed), 1 something is violated or refused, 2 a usage or input error --
a bad trace line, a rule file with errors, a name the rules do not know.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import sys
from collections.abc import Sequence

from rich.text import Text

from cosleec.cli.common import add_clause_options, add_priority_options, console
from cosleec.errors import UserError, clip
from cosleec.lang import HedgeSemantics, SleecError, Specification, cycle, load, pairs, parse_priority
from cosleec.semantics import (
    Conflict,
    Judgement,
    Options,
    Verdict,
    check_trace,
    judge,
    read,
)

USAGE_ERROR = 2
STYLE = {"violated": "bold red", "refused": "bold red", "cancelled": "yellow", "conflict": "magenta"}


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec conforms`` and its options."""
    p = sub.add_parser(
        "conforms",
        help="check a recorded run (a JSON Lines trace or a Manager's audit log) against the rules",
        description="Judge a recorded run by the reference semantics. Exit 0: conforms up to the trace's "
        "last time; 1: something is violated or refused; 2: a usage or input error.",
    )
    p.add_argument("rules", metavar="RULES", help="the rule file")
    p.add_argument(
        "trace",
        metavar="TRACE",
        help='JSON Lines, one object a line: {"t": 0, "set": {"m": true}}, {"t": 0, "event": "E"}, '
        '{"t": 360}; or a Manager\'s audit log',
    )
    add_clause_options(p, unknown=False)
    add_priority_options(p)
    p.add_argument(
        "--untimed",
        type=_seconds,
        default=None,
        metavar="SECONDS",
        help="a deadline for responses written without `within` (default: none, they stay pending)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Judge the trace and print the verdicts; returns 0, 1 or 2 (see the module docstring).

    Input errors are caught here, not in :func:`cosleec.cli.main.main`, because this
    command's contract makes them exit 2 where ``main`` would exit 1; they are printed the
    same way.
    """
    try:
        spec = load(args.rules)
        steps = read(args.trace)
        if not steps:  # checking nothing must not look like a pass
            raise UserError(
                "the trace is empty",
                where=str(args.trace),
                hint='give one step a line, e.g. {"t": 0, "event": "E"}',
            )
        check_trace(spec, steps, path=args.trace)
        options = Options(
            semantics=HedgeSemantics(args.semantics),
            untimed=args.untimed,
            priorities=frozenset(_priorities_of(spec, args.priority)),
            priority_semantics=args.priority_semantics,
        )
        judgement = judge(spec, steps, options)
    except UserError as e:
        print(e.render() if isinstance(e, SleecError) else f"cosleec: {e.render()}", file=sys.stderr)
        return USAGE_ERROR
    if args.json:
        doc = {
            "rules": str(args.rules),
            "trace": str(args.trace),
            "options": {
                "semantics": str(options.semantics),
                "untimed": options.untimed,
                "priorities": [list(pair) for pair in sorted(options.priorities)],
                "priority_semantics": options.priority_semantics,
            },
            **judgement.to_json(),
        }
        print(json.dumps(doc, indent=2))
    else:
        _print(judgement)
    return 0 if judgement.conforms else 1


def _priorities_of(spec: Specification, given: Sequence[str]) -> list[tuple[str, str]]:
    """The file's priorities and those given with ``--priority``; UserError for an unknown
    rule name, a rule over itself, or a cycle (``A > B`` and ``B > A``)."""
    rules = [r.name for r in spec.rules]
    out = list(pairs(spec))
    for text in given:
        try:
            given_pairs = parse_priority(text)
        except UserError as e:
            e.where = e.where or f"--priority {clip(text, 80)!r}"
            raise
        for pair in given_pairs:
            for name in pair:
                if name not in rules:
                    close = difflib.get_close_matches(name, rules, n=1) if len(name) < 200 else []
                    raise UserError(
                        f"no rule named {clip(name, 80)!r} in {spec.path}",
                        where=f"--priority {clip(text, 80)!r}",
                        hint=f"did you mean {close[0]!r}?"
                        if close
                        else f"the rules are {clip(', '.join(rules), 200)}",
                    )
        out += given_pairs
    circle = cycle(out)
    if circle and len(circle) == 2:
        raise UserError(
            f"rule {clip(circle[0], 80)!r} is declared above itself",
            where="--priority",
            hint="a priority orders two different rules",
        )
    if circle:
        raise UserError(
            f"the priorities go round in a circle: {clip(' > '.join(circle), 200)}",
            where="--priority",
            hint="a rule cannot prevail over a rule that prevails over it; drop one of them",
        )
    return out


# ---------------------------------------------------------------------------- human output


def _print(j: Judgement) -> None:
    out = console()
    cancelled = [v for v in j.verdicts if v.status == "cancelled"]
    for v in j.breaches:
        out.print(
            _line(
                v.status, f"{_who(v)} at {_s(v.at if v.at is not None else j.end)} s: {_item(v)} -- {_why(v)}"
            )
        )
    for c in j.conflicts:
        out.print(_line("conflict", _conflict(c)))
    for v in cancelled:
        at = f" at {_s(v.at)} s" if v.at is not None else ""
        by = f" by {v.by}'s priority" if v.by else " by priority"
        out.print(_line("cancelled", f"{_who(v)}{at}: {_item(v)} -- cancelled{by}"))
    for v in j.pending:
        out.print(_line("pending", f"{_who(v)}: {_item(v)} -- {_open(v)}"))
    for f in j.firings:
        if f.clause is None and f.missing:
            needs = ", ".join(f.missing)
            out.print(_line("undecided", f"{f.rule} at {_s(f.time)} s: {f.event} -- no value for {needs}"))
    for what in j.undetermined:
        out.print(_line("undecided", clip(what, 300)))
    out.print(Text(_summary(j, len(cancelled))))


def _line(word: str, rest: str) -> Text:
    return Text.assemble((f"{word:<9}", STYLE.get(word, "")), " ", rest)


def _summary(j: Judgement, cancelled: int) -> str:
    """``1 violation, 0 refused, 2 pending, 1 conflict (trace up to 420 s)``."""
    violated = sum(1 for v in j.verdicts if v.status == "violated")
    refused = sum(1 for v in j.verdicts if v.status == "refused")
    parts = [_count(violated, "violation"), f"{refused} refused", f"{len(j.pending)} pending"]
    parts.append(_count(len(j.conflicts), "conflict"))
    if cancelled:
        parts.append(f"{cancelled} cancelled")
    return f"{', '.join(parts)} (trace up to {_s(j.end)} s)"


def _who(v: Verdict) -> str:
    """``Rule3 (default)``, ``R1 (clause 2)``, ``R1 (default, otherwise)``."""
    clause = "default" if v.clause == 0 else f"clause {v.clause}"
    return f"{v.rule} ({clause}{', otherwise' if v.depth else ''})"


def _item(v: Verdict) -> str:
    """``not CallSupport in [0, 600]``: the item with its absolute window."""
    lo, hi = v.window
    window = f"[{_s(lo)}, {_s(hi)}]" if hi is not None else f"from {_s(lo)} s on"
    return f"{'not ' if v.negated else ''}{v.event} in {window}"


def _why(v: Verdict) -> str:
    """One line on what breached ``v``."""
    if v.status == "refused":
        forbids = (
            clip(v.note, 200)
            if v.note
            else f"{v.by or 'another rule'} forbids {v.event} over the whole window"
        )
        return f"{forbids}, and no priority settles the conflict"
    note = f" ({clip(v.note, 200)})" if v.note else ""
    if v.negated:
        return f"{v.by or v.event} happened at {_s(v.at) if v.at is not None else '?'} s{note}"
    hi = v.window[1]
    return f"no {v.event} by {_s(hi)} s{note}" if hi is not None else f"no {v.event}{note}"


def _open(v: Verdict) -> str:
    """What a pending verdict still allows after the trace ends."""
    hi = v.window[1]
    if v.negated:
        return "respected so far" + (f"; forbidden until {_s(hi)} s" if hi is not None else "")
    return "not yet" + (f"; due by {_s(hi)} s" if hi is not None else "; no deadline")


def _conflict(c: Conflict) -> str:
    owes, forbids = c.rules
    clauses = ["default" if n == 0 else f"clause {n}" for n in c.clauses]
    winner = f", {c.winner} prevails" if c.winner else ""
    return (
        f"at {_s(c.time)} s: {owes} ({clauses[0]}) owes {c.event}, {forbids} ({clauses[1]}) forbids it"
        f" -- {c.resolution}{winner}"
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _s(x: float) -> str:
    """Seconds as the user wrote them: ``360``, ``0.5``; ``17873.099`` for a monotonic clock's time."""
    if not math.isfinite(x):
        return str(x)
    return str(int(x)) if x == int(x) and abs(x) < 1e15 else f"{x:.3f}".rstrip("0").rstrip(".")


def _seconds(text: str) -> float:
    """``--untimed``: a finite, non-negative number of seconds (argparse reports anything else, exit 2)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{clip(text, 40)!r} is not a number of seconds") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(
            f"{clip(text, 40)!r} is not a finite, non-negative number of seconds"
        )
    return value
