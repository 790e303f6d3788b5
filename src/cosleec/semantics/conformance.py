"""Which reading a recorded run is judged under (``cosleec conforms``).

A run is judged ex post by the reference semantics, under one :class:`~cosleec.lang.Reading`.
Each of its options comes from the first of three places that has it: what the user gives
(:class:`Given`), the run's own audit log (its last ``options`` record, so a run is judged as
it ran), the defaults. The priorities are the rule file's, with the user's or else the
log's -- a logged pair over a rule these rules no longer have (they are a newer version) is
left out, and said. :func:`choose_reading` decides, and says what the user should be told:
which options came from the log, and when the verdicts may not be those of the run (its
log holds runs with other options, it read unknown values otherwise, its decisions were
made with other clause semantics).

The messages name the options as ``cosleec conforms`` takes them (``--priority``).
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TypeVar

from cosleec.errors import UserError, clip
from cosleec.lang import (
    HedgeSemantics,
    PrioritySemantics,
    Reading,
    Specification,
    Unknowns,
    Untimed,
    clause_semantics_for,
    cycle,
    pairs,
    parse_priority,
)
from cosleec.semantics.trace import Recording

OPTIONS = ("semantics", "priorities", "priority_semantics", "priority_lead", "untimed")
"""The options a Manager's audit log records, by their JSON names, in the order they are shown."""

Pair = tuple[str, str]
T = TypeVar("T")

_DEFAULT = Reading()  # the options nobody gave: SLEEC-TK's reading


@dataclass(frozen=True)
class Given:
    """The options a user gives for judging a run; None (no priority: empty) is not given --
    the audit log's then, else the default. ``priorities`` are ``"H > L"`` texts as typed."""

    semantics: HedgeSemantics | None = None
    priorities: tuple[str, ...] = ()
    priority_semantics: PrioritySemantics | None = None
    priority_lead: float | None = None
    untimed: Untimed | float | None = None


@dataclass
class Choice:
    """The reading a run is judged under, and what the user is told about it.

    ``from_audit``: the options taken from the audit log (of :data:`OPTIONS`, in that
    order); ``notes`` and ``warnings``: lines to show, in order.
    """

    reading: Reading
    from_audit: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)


def choose_reading(spec: Specification, recording: Recording, given: Given) -> Choice:
    """The reading ``recording`` is judged under against ``spec``: ``given``'s options, else the
    audit log's, else the defaults (for the clause semantics: the file's semantics block).

    UserError for a given priority that names no rule of ``spec``, for priorities that
    go round in a circle (a rule above itself), and for given clause semantics that
    contradict the file's semantics block.
    """
    log = recording.options
    notes: list[str] = []
    if log is None or given.priorities:
        priorities = judged_priorities(spec, given.priorities)
    else:
        where = f"{recording.source}:{log.line}"
        priorities = judged_priorities(spec, [], logged=log.priorities, where=where, notes=notes)
    fallback = _DEFAULT if log is None else log
    if given.semantics is not None:  # ConfigurationError when it contradicts the file's block
        clause_semantics_for(spec, given.semantics, option="--semantics")
    # not given: what the run used (its options record), else what the file declares
    written = fallback.semantics if log is not None else clause_semantics_for(spec)
    reading = Reading(
        semantics=_or(given.semantics, written),
        untimed=_or(given.untimed, fallback.untimed),
        priorities=tuple(priorities),
        priority_semantics=_or(given.priority_semantics, fallback.priority_semantics),
        priority_lead=_or(given.priority_lead, fallback.priority_lead),
    )
    choice = Choice(reading, [] if log is None else _from_log(given), notes)
    if recording.audit and log is None:
        choice.notes.append(
            "the audit log records no options (a Manager from before they were recorded): "
            "options not given here are the defaults"
        )
    choice.warnings += _cautions(recording, choice, semantics_given=given.semantics is not None)
    return choice


def judged_priorities(
    spec: Specification,
    given: Sequence[str],
    *,
    logged: Sequence[Pair] = (),
    where: str = "--priority",
    notes: list[str] | None = None,
) -> list[Pair]:
    """The file's priorities, those ``given`` (``"H > L"`` texts) and those an audit log's
    options record (``logged``, found at ``where``); UserError for an unknown rule name given,
    a rule over itself, or a cycle (``A > B`` and ``B > A``).

    A logged pair naming a rule these rules do not have (they are a newer version) is left
    out, with a line in ``notes``.
    """
    rules = [r.name for r in spec.rules]
    out = list(pairs(spec))
    for text in given:
        out += _given_pairs(spec, rules, text)
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
    _refuse_cycle(out, where, hint)
    return out


def _from_log(given: Given) -> list[str]:
    """The options (of :data:`OPTIONS`, in that order) an audit log's record supplies: those not
    ``given`` (the priorities: when none is given)."""
    return [key for key in OPTIONS if _missing(given, key)]


def _missing(given: Given, key: str) -> bool:
    """Is option ``key`` not given (no priority given, for the priorities)?"""
    return not given.priorities if key == "priorities" else getattr(given, key) is None


def _or(given: T | None, fallback: T) -> T:
    """An option as given, else ``fallback`` (the audit log's, else the default)."""
    return fallback if given is None else given


def _given_pairs(spec: Specification, rules: list[str], text: str) -> list[Pair]:
    """The pairs a given ``"H > L"`` text declares; UserError for a malformed one or a name
    that is no rule of ``spec`` (with the closest name, or the rules)."""
    try:
        found = parse_priority(text)
    except UserError as e:
        e.where = e.where or f"--priority {clip(text, 80)!r}"
        raise
    for pair in found:
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
    return found


def _refuse_cycle(priorities: list[Pair], where: str, hint: str) -> None:
    """UserError when ``priorities`` go round: a rule above itself, or a longer circle."""
    circle = cycle(priorities)
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


def _cautions(recording: Recording, choice: Choice, *, semantics_given: bool) -> list[str]:
    """Why the verdicts may not be those of the run the log records, one line each."""
    log = recording.options
    out = []
    if log is not None and recording.options_differ and choice.from_audit:
        out.append(f"the log has runs with different options: those of the last (line {log.line}) are used")
    if log is not None and log.unknown not in (None, Unknowns.UNDETERMINED):
        out.append(
            f"the run read a condition over a measure with no value as {log.unknown} "
            f"(unknown={log.unknown}); the reference semantics leaves such a firing undetermined, "
            "so verdicts may differ"
        )
    semantics = choice.reading.semantics
    other = {s: n for s, n in recording.decision_semantics.items() if s != str(semantics)}
    if other:
        made = ", ".join(
            f"{clip(s, 40)} ({n} decision{'' if n == 1 else 's'})" for s, n in sorted(other.items())
        )
        how = " (given on the command line)" if semantics_given else ""
        out.append(f"the log's decisions were made with semantics {made}; judged with {semantics}{how}")
    return out
