"""``cosleec conforms``: does a recorded run (a trace or an audit log) obey the rules?

The run is judged ex post by the reference semantics (:mod:`cosleec.semantics`), not by the
runtime, so a Manager's audit log can be checked against the rules it ran or against a new
version of them (issue 12). Exit codes: 0 the trace conforms up to its last time (what is
still pending is printed), 1 something is violated or refused, 2 a usage or input error --
a bad trace line, a rule file with errors, a name the rules do not know.

The trace is read once, whole (a pipe -- ``/dev/stdin``, ``<(...)``, ``-`` -- is judged
whole). When it is a Manager's audit log, every option not given on the command line is the
one the run used (the log's last ``options`` record), and a line says which; names the
rules do not declare (a newer version of them) are dropped from the log's steps, and said,
where a written trace is held to the rules (exit 2). ``--json`` writes strict JSON: a number
that is not finite (a window end past the largest time) is the string ``"inf"``, ``"-inf"``
or ``"nan"``.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, TypeGuard

from rich.text import Text

from cosleec.cli.common import add_clause_options, add_priority_options, console
from cosleec.errors import UserError, clip
from cosleec.lang import HedgeSemantics, SleecError, Specification, cycle, load, pairs, parse_priority
from cosleec.semantics import (
    CANCEL,
    Conflict,
    Judgement,
    Options,
    Recording,
    Verdict,
    check_trace,
    fit_trace,
    judge,
    read_recording,
)

USAGE_ERROR = 2
STYLE = {
    "violated": "bold red",
    "refused": "bold red",
    "cancelled": "yellow",
    "conflict": "magenta",
    "warning": "yellow",
}
IMMEDIATE_S = 1.0
PRINTED_AT_ONCE = 1000
"""Lines of text output handed to rich together (one call a line is three times slower)."""
"""``untimed="immediate"``: the deadline the Manager gives an untimed response (its tolerance)."""


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec conforms`` and its options."""
    p = sub.add_parser(
        "conforms",
        help="check a recorded run (a JSON Lines trace or a Manager's audit log) against the rules",
        description="Judge a recorded run by the reference semantics. Exit 0: conforms up to the trace's "
        "last time; 1: something is violated or refused; 2: a usage or input error. When TRACE is a "
        "Manager's audit log, an option not given here is the one the run used.",
    )
    p.add_argument("rules", metavar="RULES", help="the rule file")
    p.add_argument(
        "trace",
        metavar="TRACE",
        help='JSON Lines, one object a line: {"t": 0, "set": {"m": true}}, {"t": 0, "event": "E"}, '
        '{"t": 360}; or a Manager\'s audit log; - reads standard input',
    )
    add_clause_options(
        p,
        unknown=False,
        semantics_help="how the unless clauses of a rule combine (default: the audit log's, else "
        "last-wins, as SLEEC)",
    )
    add_priority_options(p, lead=True)
    p.add_argument(
        "--untimed",
        type=_untimed,
        default=None,
        metavar="none|immediate|SECONDS",
        help="the deadline of a response written without `within`, as the Manager's option: none "
        f"(they stay pending; the default), immediate ({IMMEDIATE_S:g} s) or seconds",
    )
    p.add_argument("--json", action="store_true", help="print one JSON document instead of text")
    p.add_argument(
        "--legos-compat",
        action="store_true",
        help="read the rules as LEGOS does (cross-scale literals, duplicate names), as `analyse --legos-compat`",
    )
    # None is "not given": an audit log's options fill only what the command line leaves out
    p.set_defaults(run=run, semantics=None, priority_semantics=None, priority_lead=None)


OPTIONS = ("semantics", "priorities", "priority_semantics", "priority_lead", "untimed")
"""The options a Manager's audit log records, by their JSON names, in the order they are shown."""


@dataclass
class _Chosen:
    """The options a trace is judged with, and what the user is told about them."""

    options: Options
    from_audit: list[str] = field(default_factory=list)  # the options taken from the log (OPTIONS)
    said: list[str] = field(default_factory=list)  # those options as the text line shows them
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def run(args: argparse.Namespace) -> int:
    """Judge the trace and print the verdicts; returns 0, 1 or 2 (see the module docstring).

    Input errors are caught here, not in :func:`cosleec.cli.main.main`, because this
    command's contract makes them exit 2 where ``main`` would exit 1; they are printed the
    same way.
    """
    try:
        lead: float | None = args.priority_lead  # float(), as the Manager node's: check it here
        if lead is not None and not (math.isfinite(lead) and lead >= 0):
            raise UserError(
                f"--priority-lead {lead}: not a finite number of seconds >= 0",
                where="--priority-lead",
                hint="give how long before the forcing deadline the lower rule is cancelled, e.g. 5",
            )
        spec = load(args.rules, legos_compat=args.legos_compat)
        recording = read_recording(args.trace)  # once: a pipe cannot be read twice
        if not recording.steps:  # checking nothing must not look like a pass
            raise UserError(
                "the trace is empty",
                where=recording.source,
                hint='give one step a line, e.g. {"t": 0, "event": "E"}',
            )
        notes: list[str] = []
        if recording.audit:  # checked against these rules, perhaps a newer version than it ran
            steps, notes = fit_trace(spec, recording.steps)
        else:
            check_trace(spec, recording.steps, path=recording.source)
            steps = recording.steps
        chosen = _choose(args, spec, recording)
        chosen.notes[:0] = notes
        judgement = judge(spec, steps, chosen.options)
    except UserError as e:
        print(e.render() if isinstance(e, SleecError) else f"cosleec: {e.render()}", file=sys.stderr)
        return USAGE_ERROR
    options = chosen.options
    if args.json:
        doc = {
            "rules": str(args.rules),
            "trace": recording.source,
            "options": {
                "semantics": str(options.semantics),
                "untimed": options.untimed,
                "priorities": [list(pair) for pair in sorted(options.priorities)],
                "priority_semantics": options.priority_semantics,
                "priority_lead": options.lead,
                "from_audit": chosen.from_audit,
            },
            "notes": chosen.notes,
            "warnings": chosen.warnings,
            **judgement.to_json(),
        }
        print(json.dumps(json_safe(doc), indent=2, allow_nan=False))
    else:
        _print(judgement, chosen, recording)
    return 0 if judgement.conforms else 1


def json_safe(x: Any) -> Any:
    """``x`` with every float that is not finite as the string ``"inf"``, ``"-inf"`` or ``"nan"``
    (strict JSON has no such numbers; ``json.dumps(..., allow_nan=False)`` accepts the result)."""
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else "inf" if x > 0 else "-inf"
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    return x


def _choose(args: argparse.Namespace, spec: Specification, recording: Recording) -> _Chosen:
    """The options: those given on the command line, else the audit log's, else the defaults."""
    given: dict[str, Any] = {
        "semantics": args.semantics,
        "priority_semantics": args.priority_semantics,
        "priority_lead": args.priority_lead,
        "untimed": args.untimed,
    }
    log = recording.options
    chosen = _Chosen(Options())
    said: dict[str, str] = {}
    if log is None:
        priorities = _priorities_of(spec, args.priority)
    else:
        logged = {
            "semantics": log.semantics,
            "priority_semantics": log.priority_semantics,
            "priority_lead": log.priority_lead,
            "untimed": log.untimed,
        }
        for key, value in logged.items():
            if given[key] is None:
                given[key] = value
                said[key] = f"{key.replace('_', '-')} {_said(value)}"
        if args.priority:
            priorities = _priorities_of(spec, args.priority)
        else:
            where = f"{recording.source}:{log.line}"
            priorities = _priorities_of(spec, [], logged=log.priorities, where=where, notes=chosen.notes)
            shown = [f"priority {h} > {lo}" for h, lo in log.priorities if (h, lo) in priorities]
            said["priorities"] = ", ".join(shown) or "no priority"
    chosen.from_audit = [key for key in OPTIONS if key in said]
    chosen.said = [said[key] for key in chosen.from_audit]
    chosen.options = Options(
        semantics=HedgeSemantics(given["semantics"] or HedgeSemantics.LAST_WINS),
        untimed=_untimed_seconds("none" if given["untimed"] is None else given["untimed"]),
        priorities=frozenset(priorities),
        priority_semantics=given["priority_semantics"] or CANCEL,
        lead=0.0 if given["priority_lead"] is None else float(given["priority_lead"]),
    )
    if recording.audit and log is None:
        chosen.notes.append(
            "the audit log records no options (a Manager from before they were recorded): "
            "options not given here are the defaults"
        )
    if log is not None and recording.options_differ and chosen.from_audit:
        chosen.warnings.append(
            f"the log has runs with different options: those of the last (line {log.line}) are used"
        )
    if log is not None and log.unknown not in (None, "undetermined"):
        chosen.warnings.append(
            f"the run read a condition over a measure with no value as {log.unknown} (unknown={log.unknown}); "
            "the reference semantics leaves such a firing undetermined, so verdicts may differ"
        )
    other = {s: n for s, n in recording.decision_semantics.items() if s != str(chosen.options.semantics)}
    if other:
        made = ", ".join(f"{clip(s, 40)} ({_count(n, 'decision')})" for s, n in sorted(other.items()))
        how = " (given on the command line)" if args.semantics is not None else ""
        chosen.warnings.append(
            f"the log's decisions were made with semantics {made}; "
            f"judged with {chosen.options.semantics}{how}"
        )
    return chosen


def _priorities_of(
    spec: Specification,
    given: Sequence[str],
    *,
    logged: Sequence[tuple[str, str]] = (),
    where: str = "--priority",
    notes: list[str] | None = None,
) -> list[tuple[str, str]]:
    """The file's priorities, those given with ``--priority`` and those an audit log's options
    record (``logged``, found at ``where``); UserError for an unknown rule name on the command
    line, a rule over itself, or a cycle (``A > B`` and ``B > A``).

    A logged pair naming a rule these rules do not have (they are a newer version) is left
    out, with a line in ``notes``.
    """
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
    known = [(h, lo) for h, lo in logged if h in rules and lo in rules]
    gone = [f"{h} > {lo}" for h, lo in logged if (h, lo) not in known]
    if gone and notes is not None:
        notes.append(
            f"priorities of the log over rules not in these rules, ignored: {clip(', '.join(gone), 300)}"
        )
    out += [pair for pair in known if pair not in out]
    hint = (
        "these are the audit log's priorities with the rule file's: choose others with --priority"
        if logged
        else ""
    )
    circle = cycle(out)
    if circle and len(circle) == 2:
        raise UserError(
            f"rule {clip(circle[0], 80)!r} is declared above itself",
            where=where,
            hint=hint or "a priority orders two different rules",
        )
    if circle:
        raise UserError(
            f"the priorities go round in a circle: {clip(' > '.join(circle), 200)}",
            where=where,
            hint=hint or "a rule cannot prevail over a rule that prevails over it; drop one of them",
        )
    return out


# ---------------------------------------------------------------------------- human output


def _print(j: Judgement, chosen: _Chosen, recording: Recording) -> None:
    lines: list[Text] = []
    if chosen.said:
        line = recording.options.line if recording.options is not None else 0
        lines.append(_line("options", f"from the audit log (line {line}): {', '.join(chosen.said)}"))
    for text in chosen.warnings:
        lines.append(_line("warning", text))
    for text in chosen.notes:
        lines.append(_line("note", text))
    cancelled = [v for v in j.verdicts if v.status == "cancelled"]
    for v in j.breaches:
        lines.append(
            _line(
                v.status, f"{_who(v)} at {_s(v.at if v.at is not None else j.end)} s: {_item(v)} -- {_why(v)}"
            )
        )
    for c in j.conflicts:
        lines.append(_line("conflict", _conflict(c)))
    for v in cancelled:
        at = f" at {_s(v.at)} s" if v.at is not None else ""
        by = f" by {v.by}'s priority" if v.by else " by priority"
        lines.append(_line("cancelled", f"{_who(v)}{at}: {_item(v)} -- cancelled{by}"))
    for v in j.pending:
        lines.append(_line("pending", f"{_who(v)}: {_item(v)} -- {_open(v)}"))
    for f in j.firings:
        if f.clause is None and f.missing:
            needs = ", ".join(f.missing)
            lines.append(_line("undecided", f"{f.rule} at {_s(f.time)} s: {f.event} -- no value for {needs}"))
    for what in j.undetermined:
        lines.append(_line("undecided", clip(what, 300)))
    lines.append(Text(_summary(j, len(cancelled))))
    out = console()
    for n in range(0, len(lines), PRINTED_AT_ONCE):  # in batches: a print a line took 3x as long
        out.print(Text("\n").join(lines[n : n + PRINTED_AT_ONCE]))


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
    """``not CallSupport in [0, 600]``: the item with its absolute window (``[0, never]`` when its
    end lies past the largest time)."""
    lo, hi = v.window
    window = f"[{_s(lo)}, {_s(hi)}]" if hi is not None else f"from {_s(lo)} s on"
    return f"{'not ' if v.negated else ''}{v.event} in {window}"


def _ends(hi: float | None) -> TypeGuard[float]:
    """Does a window with this end ever close?"""
    return hi is not None and hi != math.inf


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
    return f"no {v.event} by {_s(hi)} s{note}" if _ends(hi) else f"no {v.event}{note}"


def _open(v: Verdict) -> str:
    """What a pending verdict still allows after the trace ends."""
    hi = v.window[1]
    if v.negated:
        return "respected so far" + (f"; forbidden until {_s(hi)} s" if _ends(hi) else "")
    return "not yet" + (f"; due by {_s(hi)} s" if _ends(hi) else "; no deadline")


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
    """Seconds as the user wrote them: ``360``, ``0.5``; ``17873.099`` for a monotonic clock's time;
    ``1e+308`` for a huge one; ``never`` for an infinite one (a window end past the largest time)."""
    if math.isnan(x):
        return "undefined"
    if math.isinf(x):
        return "never" if x > 0 else "-inf"
    if abs(x) >= 1e15:
        return f"{x:.6g}"
    return str(int(x)) if x == int(x) else f"{x:.3f}".rstrip("0").rstrip(".")


def _said(value: object) -> str:
    """An option's value on the options line: ``nested``, ``60``, ``immediate (1 s)``."""
    if value == "immediate":
        return f"immediate ({_s(IMMEDIATE_S)} s)"
    return _s(value) if isinstance(value, float) else str(value)


def _untimed(text: str) -> str | float:
    """``--untimed``: ``none``, ``immediate`` or a finite, non-negative number of seconds (argparse
    reports anything else, exit 2)."""
    if text in ("none", "immediate"):
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{clip(text, 40)!r} is not none, immediate or a number of seconds"
        ) from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(
            f"{clip(text, 40)!r} is not a finite, non-negative number of seconds"
        )
    return value


def _untimed_seconds(value: str | float) -> float | None:
    """The reference's ``Options.untimed`` for the Manager's option: none -> None, immediate -> 1 s."""
    if value == "none":
        return None
    if value == "immediate":
        return IMMEDIATE_S
    return float(value)
