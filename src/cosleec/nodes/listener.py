"""The Context Listener: the robot's own topics -> measure values and trigger events.

A declarative YAML mapping says, per measure or event, which topic and message type to
read, which field (a dotted path), and how to turn it into a value: taken as it is, a
comparison (``above``, ``below``, ``at_least``, ``at_most``, ``equals``, ``not_equals``)
giving a boolean, or ``bands`` giving a scale literal. Events fire on the rising edge of
their condition, so a condition that stays true does not dispatch twice. Nothing in a
mapping is ever evaluated as code::

    measures:
      roomDark:       {topic: /light/lux, type: std_msgs/Float64, below: 10}
      userDistressed: {topic: /emotion/distress, type: std_msgs/Float64,
                       bands: [[0.3, low], [0.7, medium], [high]]}
      heartRate:      {topic: /vitals, type: std_msgs/String, json: true, field: hr}
    events:
      CurtainOpenRequest: {topic: /voice/command, type: std_msgs/String, equals: open curtains}
      UserFallen:         {topic: /fall_detector, type: std_msgs/Bool, equals: true}

All measures read from one incoming message are sent as one atomic context update.

A value is checked before it leaves: a number must be finite and fit a float (NaN, inf
and a 400-digit integer are rejected), a measure taken as it is must be of its measure's
kind (no ``"fast"`` for a numeric measure), and without the rules to say the kind it must
at least be a boolean, a number or a short string. A rejected value is counted and
reported on ``rejected``; the rest of the message still counts.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from cosleec.errors import UserError, show
from cosleec.nodes.base import MessageError, Node
from cosleec.runtime import MeasureSpec

COMPARISONS = {
    "above": lambda x, t: x > t,
    "below": lambda x, t: x < t,
    "at_least": lambda x, t: x >= t,
    "at_most": lambda x, t: x <= t,
    "equals": lambda x, t: x == t,
    "not_equals": lambda x, t: x != t,
}
KEYS = {"topic", "type", "field", "json", "bands", *COMPARISONS}
#: the longest string a measure taken as it is may carry (scale literals are short words)
MAX_TEXT = 1000


class MappingError(UserError, ValueError):
    """A mapping file is wrong; the message names the file and the entry."""


@dataclass(frozen=True, kw_only=True)
class Entry:
    """One checked mapping entry: where a measure or event is read, and how its value is made."""

    name: str
    kind: str  # "measure" | "event"
    topic: str
    type: str
    field: tuple[str, ...]
    json: bool
    comparison: tuple[str, Any] | None
    bands: tuple[tuple[float, str], ...] | None  # (upper bound, literal); last bound is inf
    #: the measure's kind (boolean, numeric, scale) and scale literals, when the rules were given
    measure_kind: str | None = None
    literals: tuple[str, ...] = ()

    def value(self, message: dict[str, Any]) -> Any:
        """The measure value (or event condition) for one message; MessageError if it has none.

        Non-finite or oversized numbers and values of the wrong kind are refused here,
        before they reach the Manager.
        """
        x: Any = message
        if self.json:
            raw = message.get("data")
            if not isinstance(raw, str):
                raise MessageError(f"{self.topic}: expected JSON text in `data`")
            x = json.loads(raw)
        for part in self.field:
            if not isinstance(x, dict) or part not in x:
                raise MessageError(f"{self.topic}: message has no field {'.'.join(self.field)!r}")
            x = x[part]
        if self.comparison is not None:
            op, target = self.comparison
            if isinstance(target, bool) != isinstance(x, bool) or (
                isinstance(target, int | float) and not isinstance(x, int | float)
            ):
                raise MessageError(
                    f"{self.topic}: {'.'.join(self.field)} is {show(x)}, not comparable with {target!r}"
                )
            if isinstance(target, int | float) and not isinstance(target, bool):
                self._number(x)  # NaN compares false with everything: say so instead
            return bool(COMPARISONS[op](x, target))
        if self.bands is not None:
            self._number(x)
            for bound, literal in self.bands:
                if x < bound:
                    return literal
        return self._as_is(x)

    def _number(self, x: Any) -> float:
        """``x`` as a finite float, or MessageError (a boolean, a string, NaN, inf, too large)."""
        what = f"{self.topic}: {'.'.join(self.field) or 'the message'}"
        if isinstance(x, bool) or not isinstance(x, int | float):
            raise MessageError(f"{what} is {show(x)}, not a number")
        if isinstance(x, int) and abs(x) > sys.float_info.max:
            raise MessageError(f"{what} is an integer too large for a float ({x.bit_length()} bits)")
        if not math.isfinite(x):
            raise MessageError(f"{what} is {x!r}, not a finite number")
        return float(x)

    def _as_is(self, x: Any) -> Any:
        """A value taken as it is, if it is of the measure's kind (any plain value without rules)."""
        what = f"{self.topic}: {'.'.join(self.field) or 'the message'}"
        kind = self.measure_kind
        if kind == "boolean" and not isinstance(x, bool):
            raise MessageError(f"{what} is {show(x)}, but {self.name} is boolean")
        if kind == "numeric":
            self._number(x)
        elif kind == "scale" and (not isinstance(x, str) or (self.literals and x not in self.literals)):
            raise MessageError(f"{what} is {show(x)}, not in the scale of {self.name}")
        elif isinstance(x, int | float) and not isinstance(x, bool):
            self._number(x)
        elif isinstance(x, str):
            if len(x) > MAX_TEXT:
                raise MessageError(f"{what} is a string of {len(x)} characters (at most {MAX_TEXT})")
        elif not isinstance(x, bool):
            raise MessageError(f"{what} is {show(x)}, not a boolean, number or string")
        return x


@dataclass
class Mapping:
    """A checked Context Listener mapping: its entries and the namespace it asks for.

    Build it with :meth:`load` or :meth:`parse`, giving the rule set's measures and events:
    a mapping that names something the rules do not declare, or gives a value of the
    wrong kind, then fails at start-up instead of in front of the robot.
    """

    entries: list[Entry] = field(default_factory=list)
    namespace: str | None = None
    source: str = "<mapping>"

    @classmethod
    def load(
        cls,
        path: str | Path,
        measures: dict[str, MeasureSpec] | None = None,
        events: frozenset[str] | None = None,
    ) -> Mapping:
        """Read and check the mapping file at ``path``; MappingError names the file and entry at fault.

        ``measures`` and ``events`` (from the :class:`~cosleec.runtime.RuleSet`) turn on the
        checks against the rules; None skips them.
        """
        try:
            text = Path(path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise MappingError(f"{path}: cannot read the mapping: {e}") from None
        return cls.parse(text, str(path), measures, events)

    @classmethod
    def parse(
        cls,
        text: str,
        source: str = "<mapping>",
        measures: dict[str, MeasureSpec] | None = None,
        events: frozenset[str] | None = None,
    ) -> Mapping:
        """Check mapping ``text`` as :meth:`load` does; ``source`` names it in messages."""
        try:
            doc = yaml.safe_load(text) or {}
        except yaml.YAMLError as e:
            raise MappingError(f"{source}: not valid YAML: {e}") from None
        if not isinstance(doc, dict):
            raise MappingError(f"{source}: expected a mapping with `measures` and/or `events`")
        unknown = set(doc) - {"measures", "events", "namespace"}
        if unknown:
            raise MappingError(f"{source}: unknown section(s) {sorted(unknown)}")
        m = cls(namespace=doc.get("namespace"), source=source)
        for kind in ("measures", "events"):
            section = doc.get(kind) or {}
            if not isinstance(section, dict):
                raise MappingError(f"{source}: `{kind}` must map names to entries")
            for name, spec in section.items():
                m.entries.append(_entry(source, kind[:-1], str(name), spec, measures, events))
        return m

    def topics(self) -> dict[str, str]:
        """topic -> message type; MappingError if one topic is given two types."""
        out: dict[str, str] = {}
        for e in self.entries:
            if out.setdefault(e.topic, e.type) != e.type:
                raise MappingError(
                    f"{self.source}: topic {e.topic} is given two types: {out[e.topic]} and {e.type}"
                )
        return out


def _entry(
    source: str,
    kind: str,
    name: str,
    spec: Any,
    measures: dict[str, MeasureSpec] | None,
    events: frozenset[str] | None,
) -> Entry:
    where = f"{source}: {kind}s.{name}"
    if not isinstance(spec, dict):
        raise MappingError(f"{where}: expected an entry with at least `topic` and `type`")
    extra = set(spec) - KEYS
    if extra:
        raise MappingError(f"{where}: unknown key(s) {sorted(extra)}; allowed: {sorted(KEYS)}")
    for key in ("topic", "type"):
        if not isinstance(spec.get(key), str) or not spec[key]:
            raise MappingError(f"{where}: `{key}` is required and must be a string")
    comps = [k for k in COMPARISONS if k in spec]
    if len(comps) + ("bands" in spec) > 1:
        raise MappingError(f"{where}: give at most one of {sorted(COMPARISONS)} or `bands`")
    comparison = (comps[0], spec[comps[0]]) if comps else None
    bands = None
    if "bands" in spec:
        raw = spec["bands"]
        if not isinstance(raw, list) or not raw:
            raise MappingError(
                f"{where}: `bands` is a list of [upper bound, literal], the last just [literal]"
            )
        out: list[tuple[float, str]] = []
        for i, band in enumerate(raw):
            last = i == len(raw) - 1
            if last and isinstance(band, list) and len(band) == 1:
                out.append((math.inf, str(band[0])))
            elif isinstance(band, list) and len(band) == 2 and isinstance(band[0], int | float):
                out.append((float(band[0]), str(band[1])))
            else:
                raise MappingError(
                    f"{where}: band {i + 1} must be [upper bound, literal] (the last: [literal])"
                )
        if out[-1][0] != math.inf:
            out.append((math.inf, out[-1][1]))
        bands = tuple(out)
    # a plain message's value is its `data`; a JSON payload is read from its root
    default_field = "" if spec.get("json") else "data"
    field_path = tuple(p for p in str(spec.get("field", default_field)).split(".") if p)
    e = Entry(
        name=name,
        kind=kind,
        topic=spec["topic"],
        type=spec["type"],
        field=field_path,
        json=bool(spec.get("json")),
        comparison=comparison,
        bands=bands,
    )
    if kind == "measure" and measures is not None and name in measures:
        spec_of = measures[name]
        e = replace(e, measure_kind=spec_of.kind, literals=tuple(spec_of.literals))
    if kind == "event":
        if events is not None and name not in events:
            raise MappingError(f"{where}: the rules declare no event {name!r}")
        if comparison is None:
            raise MappingError(f"{where}: an event needs a condition (e.g. `equals: true`)")
    elif measures is not None:
        ms = measures.get(name)
        if ms is None:
            raise MappingError(f"{where}: the rules declare no measure {name!r}")
        if ms.kind == "scale":
            if bands is not None:
                bad = [lit for _, lit in bands if lit not in ms.literals]
                if bad:
                    raise MappingError(
                        f"{where}: {bad} not in the scale of {name} ({', '.join(ms.literals)})"
                    )
        elif bands is not None:
            raise MappingError(f"{where}: `bands` give scale literals, but {name} is {ms.kind}")
        if ms.kind == "numeric" and comparison is not None:
            raise MappingError(f"{where}: a comparison gives a boolean, but {name} is numeric")
    return e


class ListenerNode(Node):
    """Subscribes to the mapped robot topics; publishes ``context`` updates and ``events``.

    Run one per robot, next to the Manager node. The mapping's ``namespace``, when set,
    wins over ``namespace``. A message a mapping entry cannot read is rejected for that
    entry; the other entries of the message still count. Whatever a message holds, the
    node rejects it and goes on: no error leaves a typed topic's callback.
    """

    name = "listener"

    def __init__(self, transport: Any, mapping: Mapping, *, namespace: str = "/cosleec") -> None:
        super().__init__(transport, mapping.namespace or namespace)
        self.mapping = mapping
        self.edges: dict[str, bool] = {}
        for t in ("context", "events"):
            self.advertise(t)
        by_topic: dict[str, list[Entry]] = {}
        for e in mapping.entries:
            by_topic.setdefault(e.topic, []).append(e)
        for t, type_name in mapping.topics().items():
            entries = by_topic[t]
            transport.subscribe_typed(
                t, type_name, lambda msg, entries=entries, t=t: self._message(t, entries, msg)
            )

    def _message(self, where: str, entries: list[Entry], message: dict[str, Any]) -> None:
        self._count("received")
        try:
            self._read(where, entries, message)
        except Exception as err:  # never into the transport: its thread must go on delivering
            self.reject_error(where, err, message)

    def _read(self, where: str, entries: list[Entry], message: dict[str, Any]) -> None:
        values: dict[str, Any] = {}
        fired: list[str] = []
        for e in entries:
            try:
                v = e.value(message)
            except Exception as err:  # this entry cannot read it; the others may
                self.reject_error(where, err, message)
                continue
            if e.kind == "measure":
                values[e.name] = v
            else:
                before = self.edges.get(e.name, False)
                self.edges[e.name] = bool(v)
                if v and not before:
                    fired.append(e.name)
        if values:
            self.publish("context", {"values": values})
        for name in fired:
            self.publish("events", {"event": name})
