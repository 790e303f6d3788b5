"""The record observers hear: :class:`RuntimeEvent`, one per state change, in order."""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from cosleec.records.kinds import Kind


@dataclass(frozen=True)
class RuntimeEvent:
    """What observers (terminal display, ROS publishers, the audit log, tests) are told, in order.

    ``kind`` says what happened (:class:`Kind`; it equals its string, ``ev.kind ==
    "decision"``); ``data`` carries the fields of that kind (:data:`cosleec.records.FIELDS`;
    a decision's ``time`` is its own, which the audit log makes the record's time).
    ``seq`` numbers the records of one Manager (continued across restarts with a journal,
    or from the audit log it appends to); 0 when nothing records.

    A record the runtime makes on its hot path may be :meth:`deferred`: its ``data`` is
    made when first read (by an observer, the audit log, a node), not when the step makes
    it, so that a decision nobody reads costs no record.
    """

    kind: Kind
    time: float
    data: dict[str, Any] = field(default_factory=dict)
    seq: int = 0

    @classmethod
    def made(cls, kind: Kind, time: float, data: dict[str, Any], seq: int) -> RuntimeEvent:
        """The same as the constructor with every field given, for the Manager's hot path
        (a frozen dataclass sets each field through ``object.__setattr__``; a decision with
        observers makes several records). ``kind`` is taken as given: no conversion."""
        ev = object.__new__(cls)
        d = ev.__dict__  # (four stores: cheaper than an update from keywords)
        d["kind"] = kind
        d["time"] = time
        d["data"] = data
        d["seq"] = seq
        return ev

    @classmethod
    def deferred(cls, kind: Kind, time: float, make: Callable[[], dict[str, Any]], seq: int) -> RuntimeEvent:
        """A record whose ``data`` is ``make()``, called once, when ``data`` is first read (from
        any thread; ``make`` must give the same record whenever it is called, so it may only
        read what no longer changes). Equal to :meth:`made` with that data."""
        ev = object.__new__(cls)
        d = ev.__dict__
        d["kind"] = kind
        d["time"] = time
        d["seq"] = seq
        d["_make"] = make
        return ev

    def __getattr__(self, name: str) -> Any:
        """(Only for a :meth:`deferred` record's ``data`` not made yet: every other
        attribute is found without this.)"""
        d = self.__dict__
        if name != "data" or ("_make" not in d and "data" not in d):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        with _MAKING:  # one thread makes it; a second one waits and reads it
            if "data" not in d:
                d["data"] = d["_make"]()
                del d["_make"]
        return d["data"]


_MAKING = threading.RLock()  # (re-entrant: a record's maker may read another deferred record)
