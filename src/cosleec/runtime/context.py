"""The runtime context: typed measure values, validated, with optional staleness.

An update is all-or-nothing: one bad value rejects the whole update with a reason and the
state is unchanged. A measure never set, or older than its ``max_age``, is *unknown*.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection, Mapping
from typing import Any

from cosleec.errors import closest, show
from cosleec.runtime.errors import ContextError
from cosleec.runtime.values import MeasureSpec, Value

_UNSET: Any = object()


class Context:
    """Current measure values (stored form: scale values as positions).

    ``max_age`` maps a measure to the seconds after which its value is stale (unknown).
    Not thread-safe: the Manager serialises access.
    """

    def __init__(
        self, measures: Mapping[str, MeasureSpec], max_age: Mapping[str, float] | None = None
    ) -> None:
        self.measures = dict(measures)
        ages = dict(max_age or {})
        unknown = sorted(str(n) for n in set(ages) - set(self.measures))
        if unknown:
            raise ContextError(f"max_age names no measure: {', '.join(unknown)}")
        for name, age in ages.items():  # a NaN would never expire: staleness would never fail closed
            if isinstance(age, bool) or not isinstance(age, int | float) or not 0 < age < float("inf"):
                raise ContextError(
                    f"max_age of {name} must be a positive, finite number of seconds, not {age!r}"
                )
        self.values: dict[str, Any] = {}
        self.stamps: dict[str, float] = {}
        self.version = 0
        self._aged = sorted(ages.items())
        self.aging = bool(self._aged)  # can any value go stale? (no: a step need not look)
        # for the hot path: a boolean value of a boolean measure is stored as it is, and only
        # a scale value looks different to users (its literal) than stored (its position)
        self._booleans = frozenset(n for n, m in self.measures.items() if m.kind == "boolean")
        self._scales = {n: m.literals for n, m in self.measures.items() if m.kind == "scale"}

    def validate(self, updates: Mapping[str, object]) -> dict[str, Any]:
        """The stored form of every update, or ContextError naming the first bad one."""
        if self._only_booleans(updates):  # the common update: stored as it is, checked in C
            return dict(updates)
        out: dict[str, Any] = {}
        measures, booleans = self.measures, self._booleans
        for name, value in updates.items():
            if (value is True or value is False) and type(name) is str and name in booleans:
                out[name] = value  # the common case, with no call
                continue
            spec = measures.get(name) if isinstance(name, str) else None
            if spec is None and not isinstance(name, str):
                raise ContextError(f"a measure is named by a string, not {type(name).__name__}")
            if spec is None:
                raise ContextError(f"unknown measure {show(name)}", hint=self._suggest(name))
            out[name] = spec.coerce(value)
        return out

    def _suggest(self, name: str) -> str:
        """The hint for an unknown measure: the declared one it most likely misspells, else
        where measures are declared."""
        close = closest(name, self.measures)
        if close is not None:
            return f"did you mean {close}?"
        return "declare it in the rules' def block (measure NAME : boolean), or check its spelling"

    def _only_booleans(self, updates: Mapping[str, object]) -> bool:
        """Is every key of ``updates`` the name of a boolean measure (a ``str``: a key that only
        compares equal to a name is no name) and every value a ``bool``?"""
        size = len(updates)
        return (
            [*map(type, updates)].count(str) == size
            and self._booleans.issuperset(updates)
            and [*map(type, updates.values())].count(bool) == size
        )

    def apply(self, stored: Mapping[str, Any], now: float) -> set[str]:
        """Apply validated values; return the measures whose value changed (or became known)."""
        changed = set()
        values, stamps = self.values, self.stamps
        for name, v in stored.items():  # (a plain loop: faster here than comprehensions and bulk updates)
            old = values.get(name, _UNSET)
            if old is _UNSET or old != v or type(old) is not type(v):
                changed.add(name)
            values[name] = v
            stamps[name] = now
        if changed:
            self.version += 1
        return changed

    def apply_booleans(self, updates: Mapping[str, object], now: float) -> bool | None:
        """:meth:`validate` and :meth:`apply` at once, for the hot path's common update: only
        boolean values of boolean measures (stored as they are, so the update changes
        something exactly when it is not all stored already). Did any value change (or become
        known)? Then the rules that read the update's measures are to be judged again -- those
        whose values did not change come to the same choice. None, having changed nothing,
        for any other update (:meth:`validate` says what is wrong with it, or stores it)."""
        if not self._only_booleans(updates):
            return None
        values, stamps = self.values, self.stamps
        changed = not updates.items() <= values.items()  # (bools: equal is identical)
        if changed:
            values.update(updates)
            self.version += 1
        for name in updates:
            stamps[name] = now
        return changed

    def expire(self, now: float) -> set[str]:
        """Forget values older than their measure's max_age: they become unknown."""
        gone = set()
        for name, max_age in self._aged:  # only measures that can go stale are looked at
            if name in self.values and now - self.stamps[name] > max_age:
                del self.values[name]
                gone.add(name)
        if gone:
            self.version += 1
        return gone

    def next_expiry(self) -> float | None:
        """When the next known value reaches its ``max_age`` (clock time, seconds); None if none can.

        The Manager's timer thread sleeps until then; the value goes stale just after it.
        """
        times = [self.stamps[n] + age for n, age in self._aged if n in self.values]
        return min(times) if times else None

    def record_of(self, stored: Mapping[str, Any], changed: Collection[str]) -> Callable[[], dict[str, Any]]:
        """The ``context`` record of values :meth:`apply` just stored (``stored``, of which
        ``changed`` changed), as a function that makes it: ``{"values": ..., "version": ...}``,
        the changed values as users see them, by name. It keeps ``stored`` and ``changed``,
        which nobody changes once applied, and the version now, so it makes the same record
        whenever it is called (``Step.emit_later``)."""
        return functools.partial(_context_record, stored, changed, self.version, self._scales)

    def external(self, names: Any = None) -> dict[str, Value | None]:
        """Values as users see them; ``None`` for unknown."""
        keys = self.measures if names is None else names
        if not isinstance(keys, dict | list | tuple):  # read twice below: a one-shot iterable once
            keys = list(keys)
        values = self.values
        return _shown(dict(zip(keys, map(values.get, keys))), self._scales)


def _shown(values: dict[str, Any], scales: Mapping[str, tuple[str, ...]]) -> dict[str, Value | None]:
    """``values`` (stored form, by name) as users see them: a scale's position as its literal.
    Changed in place, and returned."""
    if scales:
        for n, v in values.items():
            if v is not None and n in scales:
                values[n] = scales[n][int(v)]
    return values


def _context_record(
    stored: Mapping[str, Any], changed: Collection[str], version: int, scales: Mapping[str, tuple[str, ...]]
) -> dict[str, Any]:
    """What :meth:`Context.record_of` makes: as :meth:`Context.external` shows the changed
    values just after they were stored."""
    return {"values": _shown({n: stored[n] for n in sorted(changed)}, scales), "version": version}
