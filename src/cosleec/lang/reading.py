"""How rules are read: the options a run's verdicts depend on, as one value (issue 29).

The same rules can be read in several ways, each a documented choice: how the ``unless``
clauses of a rule combine (:class:`HedgeSemantics`), how a condition over a measure with no
value is read (:class:`Unknowns`), the deadline of a response written without ``within``
(:class:`Untimed`, or seconds), and which rule gives way when two clash (the declared
priorities, with :class:`PrioritySemantics` and its lead). A :class:`Reading` holds them
together, each under the one name the Manager's keyword, the command line's option and the
audit log use for it:

- the runtime reads its rules so (the Manager's options, ``cosleec.runtime.options.Options``);
- the reference semantics judges a trace so (``cosleec.semantics.judge``);
- ``cosleec conforms`` and ``cosleec analyse`` build one from the command line
  (:func:`parse_untimed` reads ``--untimed``, :func:`parse_priority` a ``--priority``);
- a Manager states its own in the audit log's ``options`` record, whose data is exactly
  :meth:`Reading.to_json`; :meth:`Reading.from_json` reads one back.

A Reading checks itself when built: a value of the wrong kind is a ConfigurationError that
names the option and lists its choices (:func:`one_of`), never a reading that means
something else later.

May import: errors, and the lang modules hedges and priorities.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Self, TypeGuard, TypeVar

from cosleec.errors import ConfigurationError, clip, show
from cosleec.lang.hedges import HedgeSemantics, Unknowns
from cosleec.lang.priorities import Pair, PrioritySemantics

__all__ = ["IMMEDIATE_S", "Reading", "Untimed", "one_of", "parse_untimed"]

E = TypeVar("E", bound=StrEnum)


class Untimed(StrEnum):
    """The deadline of a response written without ``within``, when it is not a number of seconds.

    ``untimed`` is one of these or a finite number of seconds >= 0 (``Untimed | float``).
    """

    NONE = "none"  # no deadline: it stays pending (the analysis: it must happen some time)
    IMMEDIATE = "immediate"  # within IMMEDIATE_S seconds of its trigger


IMMEDIATE_S = 1.0
"""``untimed="immediate"``: the seconds an untimed response has (the Manager's tolerance)."""

_UNTIMED_WORDS = tuple(u.value for u in Untimed)


def one_of(kind: type[E], value: object, name: str) -> E:
    """``value`` -- a member of the option enum ``kind`` or its string -- as that member.

    Use it wherever an option arrives as text (a keyword argument, a configuration file): a
    wrong value is a ConfigurationError naming the option and listing the choices, e.g.
    ``semantics must be one of 'last-wins', 'nested', not 'nestd'``.
    """
    if isinstance(value, str):
        try:
            return kind(value)
        except ValueError:
            pass
    choices = ", ".join(repr(str(k)) for k in kind)
    raise ConfigurationError(f"{name} must be one of {choices}, not {show(value)}")


def parse_untimed(text: str) -> Untimed | float:
    """The ``untimed`` option as typed on a command line: ``none``, ``immediate`` or seconds.

    The counterpart of :func:`parse_priority` for ``--untimed``. ConfigurationError (a
    ValueError) for anything but a finite, non-negative number of seconds or the two words.
    """
    if text in _UNTIMED_WORDS:
        return Untimed(text)
    try:
        value = float(text)
    except ValueError:
        raise ConfigurationError(
            f"{clip(text, 40)!r} is not none, immediate or a number of seconds"
        ) from None
    if not math.isfinite(value) or value < 0:
        raise ConfigurationError(f"{clip(text, 40)!r} is not a finite, non-negative number of seconds")
    return value


@dataclass(frozen=True, kw_only=True, slots=True)
class Reading:
    """How rules are read: every option a verdict on them depends on.

    ``semantics``: how the ``unless`` clauses of a rule combine; ``unknown``: how a clause
    condition over a measure with no value is read (None: not said -- an ``options`` record
    from a Manager that did not record it); ``untimed``: the deadline of a response written
    without ``within`` (:class:`Untimed`, or seconds); ``priorities``: the declared
    ``(higher, lower)`` pairs (the rule file's and those given besides), kept sorted and
    each once, as a set; ``priority_semantics``: how a priority resolves a clash;
    ``priority_lead``: seconds before the forcing deadline a conflict-aware priority
    cancels the lower rule (0: at the deadline, as SLEEC-TK).

    Strings are taken for the enums (``Reading(semantics="nested")``); a value that is not
    one of the choices raises ConfigurationError.
    """

    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
    unknown: Unknowns | None = Unknowns.UNDETERMINED
    untimed: Untimed | float = Untimed.NONE
    priorities: tuple[Pair, ...] = ()
    priority_semantics: PrioritySemantics = PrioritySemantics.CANCEL
    priority_lead: float = 0.0

    def __post_init__(self) -> None:
        """Each option as its type (an enum member, a float, sorted pairs), or ConfigurationError."""
        put = object.__setattr__  # frozen: the one place the fields are set after __init__
        put(self, "semantics", one_of(HedgeSemantics, self.semantics, "semantics"))
        if self.unknown is not None:
            put(self, "unknown", one_of(Unknowns, self.unknown, "unknown"))
        put(self, "untimed", _untimed(self.untimed))
        put(self, "priorities", _pairs(self.priorities))
        put(
            self,
            "priority_semantics",
            one_of(PrioritySemantics, self.priority_semantics, "priority_semantics"),
        )
        if not _is_seconds(self.priority_lead):
            raise ConfigurationError(
                f"priority_lead must be a number of seconds >= 0, not {show(self.priority_lead)}"
            )
        put(self, "priority_lead", float(self.priority_lead))

    @property
    def untimed_seconds(self) -> float | None:
        """The deadline of an untimed response, in seconds after its trigger: None for
        ``none`` (no deadline), :data:`IMMEDIATE_S` for ``immediate``."""
        if self.untimed == Untimed.NONE:
            return None
        if self.untimed == Untimed.IMMEDIATE:
            return IMMEDIATE_S
        return float(self.untimed)

    def to_json(self) -> dict[str, Any]:
        """The data of the audit log's ``options`` record: exactly what a Manager writes
        (``unknown`` left out when not said; pairs as sorted ``[higher, lower]`` lists)."""
        out: dict[str, Any] = {"semantics": str(self.semantics)}
        if self.unknown is not None:
            out["unknown"] = str(self.unknown)
        out["untimed"] = str(self.untimed) if isinstance(self.untimed, Untimed) else self.untimed
        out["priorities"] = [[h, lo] for h, lo in self.priorities]
        out["priority_semantics"] = str(self.priority_semantics)
        out["priority_lead"] = self.priority_lead
        return out

    @classmethod
    def from_json(cls, record: Mapping[str, Any]) -> Self:
        """The reading an ``options`` record states (other keys, such as ``seq``, are ignored).

        ValueError naming the first field that is missing or wrong, in the order
        semantics, priorities, priority_semantics, priority_lead, untimed, unknown; a
        missing ``unknown`` is not said (None).
        """
        _check_record(record)
        unknown = record.get("unknown")
        return cls(
            semantics=record["semantics"],
            unknown=unknown,
            untimed=record["untimed"],
            priorities=tuple((h, lo) for h, lo in record["priorities"]),
            priority_semantics=record["priority_semantics"],
            priority_lead=record["priority_lead"],
        )


def _check_record(record: Mapping[str, Any]) -> None:
    """ValueError unless ``record`` holds an ``options`` record's fields, each well formed."""

    def bad(key: str, want: str) -> ValueError:
        got = f"not {show(record[key], 60)}" if key in record else "missing"
        return ValueError(f"the options record's {key!r} is {want}: {got}")

    if record.get("semantics") not in _values(HedgeSemantics):
        raise bad("semantics", _either(HedgeSemantics))
    given = record.get("priorities")
    if not isinstance(given, list) or not all(
        isinstance(p, list) and len(p) == 2 and all(isinstance(x, str) and x for x in p) for p in given
    ):
        raise bad("priorities", 'a list of ["higher", "lower"] rule name pairs')
    if record.get("priority_semantics") not in _values(PrioritySemantics):
        raise bad("priority_semantics", _either(PrioritySemantics))
    if not _is_seconds(record.get("priority_lead")):
        raise bad("priority_lead", "a number of seconds >= 0")
    untimed = record.get("untimed")
    if untimed not in _UNTIMED_WORDS and not _is_seconds(untimed):
        raise bad("untimed", '"none", "immediate" or a number of seconds >= 0')
    if "unknown" in record and record["unknown"] not in _values(Unknowns):
        raise bad("unknown", _either(Unknowns))


def _values(kind: type[StrEnum]) -> list[str]:
    """The strings an option enum's members are (a list: a record's value may be unhashable)."""
    return [k.value for k in kind]


def _either(kind: type[StrEnum]) -> str:
    """``last-wins or nested``: an option enum's choices, for a message."""
    return " or ".join(_values(kind))


def _untimed(value: object) -> Untimed | float:
    """The ``untimed`` option as its type, or ConfigurationError."""
    if isinstance(value, str) and value in _UNTIMED_WORDS:
        return Untimed(value)
    if _is_seconds(value):
        return float(value)
    raise ConfigurationError(
        f"untimed must be 'none', 'immediate' or a finite number of seconds >= 0, not {show(value)}"
    )


def _pairs(priorities: Iterable[object]) -> tuple[Pair, ...]:
    """Declared priorities as sorted ``(higher, lower)`` pairs, each once, or ConfigurationError."""
    given: list[object]
    try:
        given = list(priorities)
    except TypeError:
        given = [priorities]  # not a collection: shown as the wrong pair below
    out: set[Pair] = set()
    for p in given:
        if not (isinstance(p, tuple | list) and len(p) == 2 and all(isinstance(n, str) and n for n in p)):
            raise ConfigurationError(f"priorities must be (higher, lower) pairs of rule names, not {show(p)}")
        out.add((p[0], p[1]))
    return tuple(sorted(out))


def _is_seconds(x: object) -> TypeGuard[int | float]:
    """Is ``x`` a finite number of seconds >= 0 (not a boolean; an int too large for a float is
    not finite)?"""
    if isinstance(x, bool) or not isinstance(x, int | float):
        return False
    try:
        return math.isfinite(x) and x >= 0
    except OverflowError:
        return False
