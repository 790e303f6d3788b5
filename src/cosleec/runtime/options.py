"""The Manager's options, checked once: how it reads its rules, and how it runs them.

``Manager(rules, semantics="nested", untimed=5, ...)`` takes its options as keywords, as a
user types them (strings for the choices, any iterable for the priorities); an
:class:`Options` holds them checked and typed -- the choices as enums, the untimed deadline
as :class:`~cosleec.lang.Untimed` or seconds. Building one (:meth:`Options.build`, or the
class itself) checks every option in the order the Manager always has, and the first wrong
one raises the ConfigurationError, with its hint, that names it and says what it accepts.

Two options are not whole here: the priorities need the rules (``Priorities.build`` checks
their names and closes them), so :attr:`Options.priorities` holds the caller's as given,
checked for shape (:meth:`Options.all_priorities` puts the rule file's first); and
``max_age`` needs the measures (the Context checks it).

:meth:`Options.reading` is how these options read rules that declare given priorities: a
:class:`~cosleec.lang.Reading`, whose ``to_json`` is the audit log's ``options`` record.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

from cosleec.errors import show
from cosleec.lang import HedgeSemantics, PrioritySemantics, Reading, Specification, Unknowns, Untimed, one_of
from cosleec.lang import pairs as priority_pairs
from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock
from cosleec.runtime.errors import ConfigurationError
from cosleec.runtime.explanations import Explanations
from cosleec.runtime.journal import Journal
from cosleec.runtime.model import MAX_WINDOW_S
from cosleec.runtime.priorities import Priorities
from cosleec.runtime.runner import FRAMES_PER_LEVEL, deepest

__all__ = ["GivenPriority", "Options", "UnknownEvents", "explanations_of", "given_priorities"]

GivenPriority = str | tuple[str, str]
"""A priority as a caller gives it: ``"H > L"`` (or a chain ``"A > B > C"``) or ``(H, L)``."""


class UnknownEvents(StrEnum):
    """What :meth:`Manager.event` and :meth:`Manager.request` do with an event no declaration names."""

    RAISE = "raise"  # ContextError naming the event and the closest declared names
    REFUSE = "refuse"  # record it as rejected; request answers False, event does nothing


@dataclass(frozen=True, kw_only=True, slots=True)
class Options:
    """A Manager's options, checked and typed; what each one means.

    ``semantics`` -- how the ``unless`` clauses of a rule combine (``"last-wins"`` or
    ``"nested"``, :class:`~cosleec.lang.HedgeSemantics`; None, the default: the rule file's
    ``semantics_start`` block, else last-wins, as SLEEC; one that contradicts the file's
    block is refused, :func:`~cosleec.lang.clause_semantics_for`); ``clock`` -- a
    :class:`~cosleec.runtime.clock.Clock` (None: monotonic; a VirtualClock for tests);
    ``unknown`` -- how a clause condition over a measure with no value is read
    (``"undetermined"``, the fail-closed default, see :mod:`cosleec.runtime.manager`;
    ``"false"``/``"true"``); ``unknown_events`` -- ``"raise"`` or ``"refuse"``
    (:class:`UnknownEvents`); ``untimed`` -- the deadline of an untimed response
    (``"none"``, ``"immediate"`` or seconds, :class:`~cosleec.lang.Untimed`);
    ``priorities`` -- ``"H > L"`` strings or ``(H, L)`` pairs, added to the rule file's
    ``priority`` block; ``priority_semantics`` -- ``"cancel"`` (the default) or
    ``"conflict-aware"``; ``priority_lead`` -- seconds before the forcing deadline a
    conflict-aware priority cancels the lower rule (0, as SLEEC-TK; give a real robot time
    to act); ``max_age`` -- seconds after which a measure's value is stale; ``audit`` -- a
    JSON Lines audit log (one writer: a second Manager on it is refused); ``journal`` -- a
    SQLite file the state survives a crash in (:mod:`cosleec.runtime.journal`), refused
    (JournalError) when it holds less than was committed; ``reset_journal=True`` -- start
    afresh from such a journal on purpose, once, recording what is lost as a
    ``journal-reset`` audit record (refused when the journal is sound); ``history`` -- how
    many decisions ``Manager.decisions`` keeps; ``max_depth`` -- how deeply implementations
    may trigger rules whose implementations trigger rules (a capability that triggers its
    own rule is stopped there, with a ``task-failed`` record); ``dispatch=False`` decides
    without running implementations (the ROS Manager node, ``cosleec decide``);
    ``explanations`` -- what the robot says to people, rule by rule: the path of an
    explanations file (:mod:`cosleec.runtime.explanations`), an
    :class:`~cosleec.runtime.explanations.Explanations`, or a mapping of the file's shape;
    checked against the rules when the Manager is built (``Decision.for_people``).

    Strings are taken for the choices and any iterable for ``priorities``: building checks
    and converts them. ``clock``, ``audit``, ``journal``, ``max_age``, ``dispatch`` and
    ``explanations`` are kept as given; what they hold is checked where they are opened or applied.
    """

    semantics: HedgeSemantics | None = None
    clock: Clock | None = None
    unknown: Unknowns = Unknowns.UNDETERMINED
    unknown_events: UnknownEvents = UnknownEvents.RAISE
    untimed: Untimed | float = Untimed.NONE
    audit: str | Path | AuditLog | None = None
    journal: str | Path | Journal | None = None
    reset_journal: bool = False
    max_age: Mapping[str, float] | None = None
    history: int = 10_000
    max_depth: int = 16
    dispatch: bool = True
    priorities: tuple[GivenPriority, ...] = ()
    priority_semantics: PrioritySemantics = PrioritySemantics.CANCEL
    priority_lead: float = 0.0
    explanations: str | Path | Explanations | Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        """Check and convert every option, in the Manager's order: ConfigurationError for the
        first wrong one."""
        put = object.__setattr__  # frozen: the one place the fields are set after __init__
        if self.semantics is not None:
            put(self, "semantics", one_of(HedgeSemantics, self.semantics, "semantics"))
        put(self, "unknown", one_of(Unknowns, self.unknown, "unknown"))
        put(self, "unknown_events", one_of(UnknownEvents, self.unknown_events, "unknown_events"))
        put(self, "untimed", _untimed(self.untimed))
        _check_history(self.history)
        _check_max_depth(self.max_depth)
        _check_max_age(self.max_age)
        put(self, "priorities", tuple(given_priorities(self.priorities)))
        # the one check of these two is Priorities.build's (the Manager's and a reload's)
        rule = Priorities.build((), (), self.priority_semantics, self.priority_lead)
        put(self, "priority_semantics", PrioritySemantics(rule.semantics))
        put(self, "priority_lead", rule.lead)
        _check_reset_journal(self.reset_journal, self.journal)

    @classmethod
    def build(cls, **given: Any) -> Options:
        """Options from the Manager's keywords (those not given take their defaults), each checked.

        TypeError, as the Manager's constructor has always raised it, for a keyword that is
        no option; ConfigurationError for the first option with a value it does not accept.
        """
        _known(given)
        return cls(**given)

    def replace(self, **given: Any) -> Options:
        """These options with those ``given`` changed, checked as by :meth:`build`."""
        _known(given)
        return dataclasses.replace(self, **given) if given else self

    def all_priorities(self, spec: Specification) -> list[GivenPriority]:
        """The priorities the Manager builds from: the rule file's pairs, then the caller's."""
        return [*priority_pairs(spec), *self.priorities]

    def reading(
        self, declared: Iterable[tuple[str, str]] = (), semantics: HedgeSemantics | None = None
    ) -> Reading:
        """How these options read rules that declare ``declared`` -- the rule file's pairs and
        the caller's, as ``Priorities.build`` checked them (``Priorities.declared``) -- and
        ``semantics``, the clause semantics those rules are read with when the option leaves
        it to the file: what the Manager's ``options`` record states (:meth:`Reading.to_json`)."""
        return Reading(
            semantics=self.semantics or semantics or HedgeSemantics.LAST_WINS,
            unknown=self.unknown,
            untimed=self.untimed,
            priorities=tuple(declared),
            priority_semantics=self.priority_semantics,
            priority_lead=self.priority_lead,
        )


def explanations_of(given: str | Path | Explanations | Mapping[str, Any] | None) -> Explanations | None:
    """The ``explanations`` option read (a file loaded, a mapping taken), not yet checked
    against the rules; ConfigurationError for anything else."""
    if given is None or isinstance(given, Explanations):
        return given
    if isinstance(given, str | Path):
        return Explanations.load(given)
    if isinstance(given, Mapping):
        return Explanations.of(given)
    raise ConfigurationError(
        f"explanations must be the path of an explanations file, an Explanations or a mapping, not {show(given)}",
        hint='Manager(rules, explanations="rules.explanations.yaml")',
    )


def given_priorities(priorities: Iterable[GivenPriority] | None) -> list[GivenPriority]:
    """The ``priorities`` option as a list (a single string is one priority; None is none), or
    ConfigurationError when it is no collection. What each one says is checked against the
    rules by ``Priorities.build``; :meth:`Manager.reload` takes its ``priorities`` so too.
    """
    given = () if priorities is None else [priorities] if isinstance(priorities, str) else priorities
    try:
        return list(given)
    except TypeError:
        raise ConfigurationError(
            f"priorities must be a list of 'H > L' strings or (H, L) pairs, not {show(priorities)}"
        ) from None


_NAMES = frozenset(f.name for f in dataclasses.fields(Options))


def _known(given: Mapping[str, Any]) -> None:
    """TypeError for the first keyword that is no option, worded as Python words it for the
    Manager's constructor (which took every option as a keyword of its own)."""
    for name in given:
        if name not in _NAMES:
            raise TypeError(f"Manager.__init__() got an unexpected keyword argument {name!r}")


def _untimed(value: object) -> Untimed | float:
    """The ``untimed`` option checked: ``"none"``, ``"immediate"`` or a finite number of seconds
    from 0 to MAX_WINDOW_S (the longest window the runtime tracks)."""
    if isinstance(value, str) and value in ("none", "immediate"):
        return Untimed(value)
    if isinstance(value, int | float) and not isinstance(value, bool) and 0 <= value <= MAX_WINDOW_S:
        return float(value)
    raise ConfigurationError(
        f"untimed must be 'none', 'immediate' or a number of seconds from 0 to {MAX_WINDOW_S:g}, "
        f"not {show(value)}"
    )


def _check_history(history: object) -> None:
    """ConfigurationError unless ``history`` -- how many decisions the Manager keeps -- is a whole
    number of at least 1."""
    if isinstance(history, bool) or not isinstance(history, int) or history < 1:
        raise ConfigurationError(f"history must be a whole number of at least 1, not {show(history)}")


def _check_max_age(max_age: object) -> None:
    """ConfigurationError unless ``max_age`` is None or maps measures to seconds (the Context
    checks the measures and the seconds, once it has the rules)."""
    if max_age is not None and not isinstance(max_age, Mapping):
        raise ConfigurationError(
            f"max_age maps each measure to the seconds its value stays fresh, not {show(max_age)}",
            hint="give one number per measure: max_age={'distance': 5.0}",
        )


def _check_max_depth(max_depth: object) -> None:
    """ConfigurationError unless ``max_depth`` is a whole number of levels the interpreter's
    stack holds (``deepest()``)."""
    most = deepest()
    if isinstance(max_depth, bool) or not isinstance(max_depth, int) or not 1 <= max_depth <= most:
        raise ConfigurationError(
            f"max_depth must be a whole number from 1 to {most}, not {show(max_depth)}",
            hint=f"each level of implementations that trigger rules takes about {FRAMES_PER_LEVEL} of "
            f"Python's {sys.getrecursionlimit()} stack frames (sys.getrecursionlimit()); 16 is the default",
        )


def _check_reset_journal(reset_journal: object, journal: object) -> None:
    """ConfigurationError unless ``reset_journal`` is a boolean, and True only with a journal to reset."""
    if not isinstance(reset_journal, bool) or (reset_journal and not journal):
        raise ConfigurationError(
            f"reset_journal must be True or False, and True only with a journal, not {show(reset_journal)}"
        )
