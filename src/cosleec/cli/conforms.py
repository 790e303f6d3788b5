"""``cosleec conforms``: does a recorded run (a trace or an audit log) obey the rules?

The run is judged ex post by the reference semantics (:mod:`cosleec.semantics`), not by the
runtime, so a Manager's audit log can be checked against the rules it ran or against a new
version of them (issue 12). Exit codes: 0 the trace conforms up to its last time (what is
still pending is printed), 1 there is a violation (an obligation or prohibition violated, or
an obligation blocked by another rule's prohibition), 2 a usage or input error --
a bad trace line, a rule file with errors, a name the rules do not know.

The trace is read once, whole (a pipe -- ``/dev/stdin``, ``<(...)``, ``-`` -- is judged
whole). When it is a Manager's audit log, every option not given on the command line is the
one the run used (the log's last ``options`` record), and a line says which; names the
rules do not declare (a newer version of them) are dropped from the log's steps, and said,
where a written trace is held to the rules (exit 2). ``--json`` writes strict JSON: a number
that is not finite (a window end past the largest time) is the string ``"inf"``, ``"-inf"``
or ``"nan"``.

With ``--mapping MAPPING.yaml``, TRACE is a field bag of the robot's own topics (a rosbag2
directory, MCAP or SQLite 3, or a ROS 1 ``.bag``), replayed through the Context Listener's
mapping in bag time (:mod:`cosleec.cli.fieldbags`); each verdict names the bag messages
behind it (topic, bag time). A bag that does not cover the whole mapping is judged with
those measures unknown and those events absent, and exits 1: it never passes.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, TypeGuard

from rich.text import Text

from cosleec.cli.common import add_clause_options, add_priority_options, console
from cosleec.cli.fieldbags import BagRun, read_bag
from cosleec.errors import ConfigurationError, UserError, clip
from cosleec.lang import (
    IMMEDIATE_S,
    HedgeSemantics,
    PrioritySemantics,
    SleecError,
    Untimed,
    load,
    parse_untimed,
)
from cosleec.nodes import is_bag
from cosleec.semantics import (
    BLOCKED,
    Conflict,
    Judgement,
    Recording,
    Verdict,
    check_trace,
    conformance,
    fit_trace,
    judge,
    read_recording,
)

USAGE_ERROR = 2
STYLE = {
    "violated": "bold red",
    "blocked": "bold red",
    "cancelled": "yellow",
    "conflict": "magenta",
    "warning": "yellow",
    "gap": "bold red",
}
PRINTED_AT_ONCE = 1000
"""Lines of text output handed to rich together (one call a line is three times slower)."""


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``cosleec conforms`` and its options."""
    p = sub.add_parser(
        "conforms",
        help="check a recorded run (a JSON Lines trace or a Manager's audit log) against the rules",
        description="Judge a recorded run by the reference semantics. Exit 0: conforms up to the trace's "
        "last time; 1: something is violated or blocked; 2: a usage or input error. When TRACE is a "
        "Manager's audit log, an option not given here is the one the run used.",
    )
    p.add_argument("rules", metavar="RULES", help="the rule file")
    p.add_argument(
        "trace",
        metavar="TRACE",
        help='JSON Lines, one object a line: {"t": 0, "set": {"m": true}}, {"t": 0, "event": "E"}, '
        '{"t": 360}; or a Manager\'s audit log; - reads standard input; with --mapping, a bag of the '
        "robot's topics (a rosbag2 directory, MCAP or SQLite 3, or a ROS 1 .bag)",
    )
    p.add_argument(
        "--mapping",
        metavar="MAPPING.yaml",
        help="TRACE is a bag: replay it through this Context Listener mapping (needs the bags extra: "
        "pip install 'cosleec[bags]'); a bag that does not cover the mapping exits 1",
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


def run(args: argparse.Namespace) -> int:
    """Judge the trace and print the verdicts; returns 0, 1 or 2 (see the module docstring).

    Input errors are caught here, not in :func:`cosleec.cli.main.main`, because this
    command's contract makes them exit 2 where ``main`` would exit 1; they are printed the
    same way.
    """
    try:
        given = _given(args)
        spec = load(args.rules, legos_compat=args.legos_compat)
        bag = read_bag(args.trace, args.mapping, spec) if args.mapping else None
        recording = bag.recording if bag else _read(args.trace)
        notes: list[str] = []
        if recording.audit:  # checked against these rules, perhaps a newer version than it ran
            steps, notes = fit_trace(spec, recording.steps)
        else:
            check_trace(spec, recording.steps, path=recording.source)
            steps = recording.steps
        choice = conformance.choose_reading(spec, recording, given)
        choice.notes[:0] = notes
        judgement = judge(spec, steps, choice.reading)
    except UserError as e:
        print(e.render() if isinstance(e, SleecError) else f"cosleec: {e.render()}", file=sys.stderr)
        return USAGE_ERROR
    if args.json:
        doc = _document(args, recording, choice, judgement)
        if bag is not None:
            doc["conforms"] = judgement.conforms and bag.complete
            doc["bag"] = bag.to_json(judgement)
        print(json.dumps(json_safe(doc), indent=2, allow_nan=False))
    else:
        _print(judgement, choice, recording, bag)
    return 0 if judgement.conforms and (bag is None or bag.complete) else 1


def _read(trace: str) -> Recording:
    """The trace or audit log at ``trace``, read once (a pipe cannot be read twice); UserError for
    an empty one (checking nothing must not look like a pass) and for a bag without ``--mapping``."""
    if trace != "-" and is_bag(trace):
        raise UserError(
            "this looks like a bag, and a bag is read through a Context Listener mapping",
            where=trace,
            hint="give the mapping of the robot's topics: cosleec conforms RULES BAG --mapping MAPPING.yaml",
        )
    recording = read_recording(trace)
    if not recording.steps:
        raise UserError(
            "the trace is empty",
            where=recording.source,
            hint='give one step a line, e.g. {"t": 0, "event": "E"}',
        )
    return recording


def _given(args: argparse.Namespace) -> conformance.Given:
    """The options the command line gives (None: not given); UserError for a ``--priority-lead``
    that is no finite number of seconds >= 0 (argparse took any float, as the Manager node's)."""
    lead: float | None = args.priority_lead
    if lead is not None and not (math.isfinite(lead) and lead >= 0):
        raise UserError(
            f"--priority-lead {lead}: not a finite number of seconds >= 0",
            where="--priority-lead",
            hint="give how long before the forcing deadline the lower rule is cancelled, e.g. 5",
        )
    return conformance.Given(
        semantics=None if args.semantics is None else HedgeSemantics(args.semantics),
        priorities=tuple(args.priority),
        priority_semantics=None
        if args.priority_semantics is None
        else PrioritySemantics(args.priority_semantics),
        priority_lead=lead,
        untimed=args.untimed,
    )


def _document(
    args: argparse.Namespace, recording: Recording, choice: conformance.Choice, judgement: Judgement
) -> dict[str, Any]:
    """The ``--json`` document: the files, the options judged under (``untimed`` in seconds,
    null for none), the notes and warnings, then the judgement."""
    reading = choice.reading
    return {
        "rules": str(args.rules),
        "trace": recording.source,
        "options": {
            "semantics": str(reading.semantics),
            "untimed": reading.untimed_seconds,
            "priorities": [list(pair) for pair in sorted(reading.priorities)],
            "priority_semantics": reading.priority_semantics,
            "priority_lead": reading.priority_lead,
            "from_audit": choice.from_audit,
        },
        "notes": choice.notes,
        "warnings": choice.warnings,
        **judgement.to_json(),
    }


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


# ---------------------------------------------------------------------------- human output


def _print(j: Judgement, choice: conformance.Choice, recording: Recording, bag: BagRun | None = None) -> None:
    lines: list[Text] = _bag_head(bag)
    said = _said_options(choice, recording)
    if said:
        line = recording.options.line if recording.options is not None else 0
        lines.append(_line("options", f"from the audit log (line {line}): {', '.join(said)}"))
    for text in choice.warnings:
        lines.append(_line("warning", text))
    for text in choice.notes:
        lines.append(_line("note", text))
    cancelled = [v for v in j.verdicts if v.status == "cancelled"]
    for v in j.breaches:
        at = _s(v.at if v.at is not None else j.end)
        lines += [_line(v.status, f"{_who(v)} at {at} s: {_item(v)} -- {_why(v)}"), *_behind(bag, j, v)]
    for c in j.conflicts:
        lines.append(_line("conflict", _conflict(c)))
    for v in cancelled:
        at = f" at {_s(v.at)} s" if v.at is not None else ""
        by = f" by {v.by}'s priority" if v.by else " by priority"
        lines += [_line("cancelled", f"{_who(v)}{at}: {_item(v)} -- cancelled{by}"), *_behind(bag, j, v)]
    for v in j.pending:
        lines += [_line("pending", f"{_who(v)}: {_item(v)} -- {_open(v)}"), *_behind(bag, j, v)]
    for f in j.firings:
        if f.clause is None and f.missing:
            needs = ", ".join(f.missing)
            lines.append(_line("undecided", f"{f.rule} at {_s(f.time)} s: {f.event} -- no value for {needs}"))
            origin = bag.firing_origin(f) if bag is not None else None
            if origin is not None:
                lines.append(_line("", f"  from {origin.describe()}"))
    for what in j.undetermined:
        lines.append(_line("undecided", clip(what, 300)))
    lines.append(Text(_summary(j, len(cancelled)) + _uncovered(bag)))
    out = console()
    for n in range(0, len(lines), PRINTED_AT_ONCE):  # in batches: a print a line took 3x as long
        out.print(Text("\n").join(lines[n : n + PRINTED_AT_ONCE]))


def _bag_head(bag: BagRun | None) -> list[Text]:
    """The lines on a bag before the verdicts: what it holds, its gaps (fail closed), its rejections."""
    if bag is None:
        return []
    lines = [_line("bag", bag.trace.describe())]
    lines += [_line("gap", gap) for gap in bag.trace.gaps]
    lines += [_line("warning", text) for text in bag.trace.rejections]
    return lines


def _behind(bag: BagRun | None, j: Judgement, v: Verdict) -> list[Text]:
    """The line under a verdict that names the bag messages behind it (none without a bag)."""
    said = bag.behind(j, v) if bag is not None else ""
    return [_line("", f"  from {said}")] if said else []


def _uncovered(bag: BagRun | None) -> str:
    """What the summary adds when the bag does not cover the mapping: it did not pass."""
    if bag is None or bag.complete:
        return ""
    n = len(bag.trace.gaps)
    return f"; NOT judged whole: the bag does not cover the mapping ({_count(n, 'gap')} above)"


def _line(word: str, rest: str) -> Text:
    return Text.assemble((f"{word:<9}", STYLE.get(word, "")), " ", rest)


def _summary(j: Judgement, cancelled: int) -> str:
    """``2 violations (1 blocked), 2 pending, 1 conflict (trace up to 420 s)``: the violations
    counted as ``Manager.stats["violations"]`` counts them (violated and blocked)."""
    violations = len(j.breaches)
    blocked = sum(1 for v in j.verdicts if v.status == BLOCKED)
    parts = [
        _count(violations, "violation") + (f" ({blocked} blocked)" if blocked else ""),
        f"{len(j.pending)} pending",
    ]
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
    if v.status == BLOCKED:
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


def _said_options(choice: conformance.Choice, recording: Recording) -> list[str]:
    """The options taken from the audit log as the options line shows them: ``semantics
    nested``, ``priority Rule21 > Rule3`` (those of the log's priorities in force), ``untimed
    immediate (1 s)``."""
    reading = choice.reading
    out = []
    for key in choice.from_audit:
        if key == "priorities":
            logged = recording.options.priorities if recording.options is not None else ()
            declared = set(reading.priorities)
            shown = [f"priority {h} > {lo}" for h, lo in logged if (h, lo) in declared]
            out.append(", ".join(shown) or "no priority")
        else:
            out.append(f"{key.replace('_', '-')} {_said(getattr(reading, key))}")
    return out


def _said(value: object) -> str:
    """An option's value on the options line: ``nested``, ``60``, ``immediate (1 s)``."""
    if value == Untimed.IMMEDIATE:
        return f"immediate ({_s(IMMEDIATE_S)} s)"
    return _s(value) if isinstance(value, float) else str(value)


def _untimed(text: str) -> Untimed | float:
    """``--untimed``: ``none``, ``immediate`` or a finite, non-negative number of seconds
    (:func:`~cosleec.lang.parse_untimed`; argparse reports anything else, exit 2)."""
    try:
        return parse_untimed(text)
    except ConfigurationError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
