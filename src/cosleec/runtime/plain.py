"""Plain words: names, values and durations as a person reads them, not as the rules write them.

The runtime's sentences for people (:attr:`Decision.for_people
<cosleec.runtime.decision.Decision.for_people>`, :attr:`Permission.for_people
<cosleec.runtime.permission.Permission.for_people>`) and its reasons for developers both
say how long something lasts, never a reading of the Manager's clock (``3739.94 s`` means
nothing to a patient, and little to an operator who did not start the clock): use
:func:`spoken` for people ("9 minutes") and :func:`duration` for developers ("9 min 20 s").
A rule's names are written for a parser (``RefuseRequest``, ``requesterIsPatient``):
:func:`words` spells them as words ("refuse request", "requester is patient").
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Mapping

from cosleec.runtime.values import Value

__all__ = ["duration", "listed", "mentioned", "spoken", "value_words", "words"]

# an acronym before a capitalised word (HTTPServer: HTTP), a capitalised or lower-case
# word, an acronym, a number
_PART = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|[0-9]+(?:\.[0-9]+)?")


@functools.lru_cache(maxsize=4096)
def words(name: str) -> str:
    """``name`` as words: camelCase and snake_case split, lower case but for acronyms
    (``ExplainWhy`` -> ``explain why``, ``batteryLow`` -> ``battery low``,
    ``sendSMSAlert`` -> ``send SMS alert``); a name with nothing to split stays as it is."""
    parts = _PART.findall(name)
    if not parts:
        return name
    return " ".join(p if len(p) > 1 and p.isupper() else p.lower() for p in parts)


def value_words(value: Value | None) -> str:
    """A measure's value for people: ``yes``/``no`` for a boolean, a number as written, a
    scale literal as words, ``unknown`` when the measure has no value."""
    if value is None:
        return "unknown"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int):
        return str(value)
    return words(str(value))


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def mentioned(text: str, values: Mapping[str, Value | None]) -> list[tuple[str, Value | None]]:
    """The measures of ``values`` that condition ``text`` names, with their values, in the
    order of ``values``: what an explanation says a condition read."""
    names = _names(text)  # one pass over each text, once
    return [
        (n, x)
        for n, x in values.items()
        if n in names or (not _plain(n) and re.search(rf"\b{re.escape(n)}\b", text))
    ]


@functools.lru_cache(maxsize=4096)
def _names(text: str) -> frozenset[str]:
    """The names condition ``text`` holds (a rule's conditions recur: read once each)."""
    return frozenset(_NAME.findall(text))


@functools.lru_cache(maxsize=4096)
def _plain(name: str) -> bool:
    """Whether ``name`` is one word of a condition's text (else it is searched for whole)."""
    return _NAME.fullmatch(name) is not None


def listed(parts: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``: a list in a sentence."""
    if len(parts) <= 1:
        return "".join(parts)
    return f"{', '.join(parts[:-1])} and {parts[-1]}"


_UNITS = (("d", 86400.0), ("h", 3600.0), ("min", 60.0))


def duration(seconds: float) -> str:
    """How long, for developers: ``0.25 s``, ``40 s``, ``9 min 20 s``, ``2 h 5 min``,
    ``3 d 4 h`` (the two largest units, whole seconds past a minute; never negative;
    ``no end`` for infinity)."""
    if not math.isfinite(seconds):
        return _endless(seconds, "no end")
    s = max(0.0, seconds)
    if s < 60:
        return f"{round(s, 2):g} s"
    left = round(s)
    parts = []
    for unit, size in _UNITS:
        n = int(left // size)
        if n:
            parts.append(f"{n} {unit}")
            left -= int(n * size)
    if left:
        parts.append(f"{left} s")
    return " ".join(parts[:2])  # the two largest units say it (3 d 4 h, not 3 d 4 h 5 min 6 s)


def spoken(seconds: float) -> str:
    """How long, for people, rounded as one would say it: ``a moment`` (under a second),
    ``40 seconds``, ``9 minutes``, ``1 hour 5 minutes``, ``2 days 3 hours``."""
    if not math.isfinite(seconds):
        return _endless(seconds, "ever")
    s = max(0.0, seconds)
    if s < 1:
        return "a moment"
    if s < 60:
        return _count(math.ceil(s), "second")
    minutes = max(1, round(s / 60))
    if minutes < 60:
        return _count(minutes, "minute")
    if minutes < 24 * 60:
        h, m = divmod(minutes, 60)
        return _count(h, "hour") + (f" {_count(m, 'minute')}" if m else "")
    d, h = divmod(round(s / 3600), 24)
    return _count(d, "day") + (f" {_count(h, 'hour')}" if h else "")


def _endless(seconds: float, infinite: str) -> str:
    """A duration that is no number of seconds: ``infinite`` (no end), or unknown (NaN)."""
    return "an unknown time" if math.isnan(seconds) else infinite


def _count(n: int, unit: str) -> str:
    return f"{n} {unit}" if n == 1 else f"{n} {unit}s"
