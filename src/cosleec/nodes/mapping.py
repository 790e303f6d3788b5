"""The Context Listener's mapping: which robot topic gives which measure value or trigger event.

A declarative YAML mapping says, per measure or event, which topic and message type to
read, which field (a dotted path), and how to turn it into a value: taken as it is, a
comparison (``above``, ``below``, ``at_least``, ``at_most``, ``equals``, ``not_equals``)
giving a boolean, or ``bands`` giving a scale literal. Nothing in a mapping is ever
evaluated as code; ``docs/mapping.md`` describes every key::

    namespace: /cosleec
    measures:
      roomDark:       {topic: /light/lux, type: std_msgs/Float64, below: 10}
      userDistressed: {topic: /emotion/distress, type: std_msgs/Float64,
                       bands: [[0.3, low], [0.7, medium], [high]]}
      heartRate:      {topic: /vitals, type: std_msgs/String, json: true, field: hr}
      batteryLevel:   {topic: /battery, type: sensor_msgs/msg/BatteryState, field: percentage}
    events:
      CurtainOpenRequest: {topic: /voice/command, type: std_msgs/String, equals: open curtains}
      UserFallen:         {topic: /fall_detector, type: std_msgs/Bool, equals: true, qos: reliable}
      CleanRequest:       {topic: /voice/command, type: std_msgs/String, equals: clean, fire: each}

``fire: edge`` (the default) fires an event when its condition becomes true, not again
while it stays true; ``fire: each`` fires on every message for which it holds. An event
with ``every_message: true`` has no condition and fires on every message of its topic; an
event with neither a condition nor that key is an error (a forgotten condition).

``qos`` (a profile ``sensor_data``, ``reliable``, ``latched``, or a table
``{reliability, durability, depth}``; :mod:`cosleec.nodes.qos`) says how a topic is
subscribed. Left out, a measure reads ``sensor_data`` (best effort: it hears best-effort
sensor drivers and reliable publishers alike, and a lost sample is replaced by the next)
and an event reads ``reliable`` (a command must not be lost), except from a
``sensor_msgs`` type, which sensor drivers publish best effort. The entries on one topic
share one subscription, so one QoS: a stated one, else best effort if any entry's default
is, else reliable (:meth:`Mapping.qos_of`).

This module reads and checks a mapping -- all of it before any middleware starts -- and
turns one message into an entry's value (:meth:`Entry.value`); the node that subscribes
and publishes is :class:`cosleec.nodes.listener.ListenerNode`.

A mistake in a mapping is a :class:`MappingError` that names the file, the line and
column, and the entry: ``mapping.yaml:7:3: events.Clean: ...``. A threshold or band bound
must be a finite number (``below: .nan`` would be taken by YAML, and the event never fire),
and band bounds must rise; the error then points at the value itself. A comparison's value
is one boolean, number or text (never null), an ordering compares numbers, and where the
message type says what the field holds (the plain ``std_msgs`` types,
:mod:`cosleec.nodes.mapping_values`) the value is of that kind: a comparison no message
could match is refused here, not found on the robot as every message rejected. The same loader
(:func:`read_yaml`) reads the guard's routes, so a key given twice is an error there too.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from cosleec.errors import UserError, closest, show
from cosleec.nodes.base import MessageError
from cosleec.nodes.mapping_values import field_kind, field_problem, value_problem
from cosleec.nodes.qos import Qos, QosError
from cosleec.runtime import MeasureSpec

#: the key of an event that fires on every message of its topic, without a condition
EVERY_MESSAGE = "every_message"
COMPARISONS = {
    "above": lambda x, t: x > t,
    "below": lambda x, t: x < t,
    "at_least": lambda x, t: x >= t,
    "at_most": lambda x, t: x <= t,
    "equals": lambda x, t: x == t,
    "not_equals": lambda x, t: x != t,
}
KEYS = {"topic", "type", "field", "json", "bands", "qos", "fire", EVERY_MESSAGE, *COMPARISONS}
#: ``guards`` belongs to the guard (:mod:`cosleec.nodes.guard_node`): one file maps a robot
SECTIONS = ("namespace", "measures", "events", "guards")
#: how an event fires: when its condition becomes true (edge), or on every message it holds for
FIRE = ("edge", "each")
#: the longest string a measure taken as it is may carry (scale literals are short words)
MAX_TEXT = 1000


class MappingError(UserError, ValueError):
    """A mapping file is wrong; the message names the file (line and column) and the entry."""


def _suggest(word: object, choices: Iterable[str]) -> str:
    """`` (did you mean 'fire'?)`` when ``word`` is a likely misspelling of one of ``choices``, else ``""``."""
    close = closest(word, choices)
    return f" (did you mean {close!r}?)" if close else ""


def _near_each(words: list[str], choices: Iterable[str]) -> str:
    """`` (did you mean 'mid' for 'meid', 'high' for 'hihg'?)``; one word: as :func:`_suggest`."""
    if len(words) == 1:
        return _suggest(words[0], choices)
    pairs = [(w, c) for w in words for c in (closest(w, choices),) if c]
    return f" (did you mean {', '.join(f'{c!r} for {w!r}' for w, c in pairs)}?)" if pairs else ""


def _undeclared(name: str, kind: str, declared: Iterable[str], other: Iterable[str]) -> str:
    """Why ``name`` is no ``kind`` of the rules, and what to write: the name it likely
    misspells, the section it belongs in (a measure under ``events``), or the names there are."""
    near = _suggest(name, declared)
    if near:
        return near
    other_kind = "event" if kind == "measure" else "measure"
    if name in other:
        article = "an" if other_kind == "event" else "a"
        return f"; it is {article} {other_kind} of the rules: list it under `{other_kind}s`"
    names = sorted(declared)
    if not names:
        return f"; the rules declare no {kind}s"
    shown = ", ".join(names[:12]) + (f", ... ({len(names) - 12} more)" if len(names) > 12 else "")
    return f"; the rules declare the {kind}s {shown}"


def _unknown(given: Iterable[object], allowed: Iterable[str]) -> str:
    """``['fier'] (did you mean 'fire'?); allowed: [...]``: what an unknown-key error lists."""
    names = sorted(str(k) for k in given)  # str: keys may be numbers, booleans, None
    hints = "".join(_suggest(k, allowed) for k in names)
    return f"{names}{hints}; allowed: {sorted(allowed)}"


class _Marked(dict[Any, Any]):
    """A YAML mapping that remembers where each of its keys (``marks``) and values (``value_marks``) was written."""

    marks: dict[Any, yaml.Mark]
    value_marks: dict[Any, yaml.Mark]


class _MarkedList(list[Any]):
    """A YAML sequence that remembers where each of its items was written (``marks``, in order)."""

    marks: list[yaml.Mark]


class _Duplicate(Exception):
    """A key given twice in one YAML mapping (safe_load would keep the last without a word)."""

    def __init__(self, key: Any, mark: yaml.Mark) -> None:
        super().__init__(key)
        self.key, self.mark = key, mark


class _Loader(yaml.SafeLoader):
    """The safe loader, with mappings that keep their keys' positions and refuse a key given twice.

    The positions let a mapping error say ``mapping.yaml:7:3``; a repeated entry or key
    would otherwise silently replace the first, and that entry would never be read.
    """


def _construct_map(loader: _Loader, node: yaml.MappingNode) -> Iterator[_Marked]:
    """:class:`_Loader`'s constructor of every YAML mapping: a :class:`_Marked` dict, or _Duplicate."""
    data = _Marked()
    data.marks, data.value_marks = {}, {}
    yield data  # first, as SafeConstructor does: an anchor may refer to the mapping itself
    seen: set[Any] = set()
    for key_node, _ in node.value:  # before merge keys (<<) are flattened in: an override is fine
        if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
            key = loader.construct_object(key_node)
            if key in seen:
                raise _Duplicate(key, key_node.start_mark)
            seen.add(key)
    data.update(loader.construct_mapping(node))
    # flattened now: a key of the mapping itself comes after a merged one
    for key_node, value_node in node.value:
        with contextlib.suppress(TypeError):  # an unhashable key: construct_mapping refused it already
            key = loader.construct_object(key_node)
            data.marks[key] = key_node.start_mark
            data.value_marks[key] = value_node.start_mark


def _construct_seq(loader: _Loader, node: yaml.SequenceNode) -> Iterator[_MarkedList]:
    """:class:`_Loader`'s constructor of every YAML sequence: a :class:`_MarkedList`."""
    data = _MarkedList()
    data.marks = [item.start_mark for item in node.value]
    yield data  # first, as SafeConstructor does: an anchor may refer to the sequence itself
    data.extend(loader.construct_sequence(node))


_Loader.add_constructor("tag:yaml.org,2002:map", _construct_map)
_Loader.add_constructor("tag:yaml.org,2002:seq", _construct_seq)


def read_yaml(text: str, source: str) -> Any:
    """The YAML document ``text`` (empty: ``{}``); MappingError at ``source:line:col`` for a
    syntax error or a key given twice (which plain YAML would silently let win)."""
    try:
        return yaml.load(text, Loader=_Loader) or {}
    except _Duplicate as e:
        where = f"{source}:{e.mark.line + 1}:{e.mark.column + 1}"
        raise MappingError(
            f"{where}: {show(e.key)} is given twice (the second would replace the first)"
        ) from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = f"{source}:{mark.line + 1}:{mark.column + 1}" if mark is not None else source
        what = "; ".join(str(x) for x in (e.context, e.problem) if x)
        raise MappingError(f"{where}: not valid YAML: {what}") from None
    except yaml.YAMLError as e:
        raise MappingError(f"{source}: not valid YAML: {e}") from None


def _at(source: str, where: Any, key: Any, otherwise: str | None = None) -> str:
    """``source:line:col`` of ``key`` in the loaded YAML mapping ``where``; ``otherwise`` (or
    ``source``) when the position is unknown (a mapping not read by :class:`_Loader`)."""
    mark = where.marks.get(key) if isinstance(where, _Marked) else None
    if mark is None:
        return otherwise or source
    return f"{source}:{mark.line + 1}:{mark.column + 1}"


def _value_at(source: str, where: Any, key: Any, otherwise: str) -> str:
    """``source:line:col`` of the value of ``key`` in the loaded YAML mapping ``where``; else ``otherwise``."""
    mark = where.value_marks.get(key) if isinstance(where, _Marked) else None
    return otherwise if mark is None else f"{source}:{mark.line + 1}:{mark.column + 1}"


def _item_at(source: str, items: Any, i: int, otherwise: str) -> str:
    """``source:line:col`` of item ``i`` of the loaded YAML sequence ``items``; else ``otherwise``."""
    marks = items.marks if isinstance(items, _MarkedList) else []
    return otherwise if i >= len(marks) else f"{source}:{marks[i].line + 1}:{marks[i].column + 1}"


def _not_finite(value: Any) -> str | None:
    """How a number no finite float can be is shown (``NaN``, ``-infinity``, ``an integer of 401
    digits``); None for a finite one, and for what is no number (a boolean, a string)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    if isinstance(value, int):
        return f"an integer of {len(str(abs(value)))} digits" if abs(value) > sys.float_info.max else None
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "infinity" if value > 0 else "-infinity"
    return None


#: why a threshold must be finite, said with every refusal of one
FIXED = (
    "a finite reading compared with it always gives the same answer, so the condition could never "
    "change (an event would never fire, or fire on every reading)"
)


def default_qos(kind: str, type_name: str) -> Qos:
    """The QoS an entry reads with when the mapping gives none, and why.

    A measure is a state that its publisher sends again and again: best effort
    (``sensor_data``) hears best-effort sensor drivers and reliable publishers alike, and a
    lost sample is replaced by the next. An event is often a one-off command that must not
    be lost: ``reliable``. But a ``sensor_msgs`` type comes from a sensor driver, which
    publishes best effort, and a reliable subscription would never hear it:
    ``sensor_data`` for those events too.
    """
    if kind == "measure" or type_name.split("/", 1)[0] == "sensor_msgs":
        return Qos.SENSOR_DATA
    return Qos.RELIABLE


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
    #: the QoS the mapping states for this entry; None: :func:`default_qos`
    qos: Qos | None = None
    #: an event's firing: "edge" (when its condition becomes true) or "each" (every message it holds for)
    fire: str = "edge"
    #: where the entry is written (``mapping.yaml:7:3``), for messages
    where: str = ""
    #: an event that fires on every message of its topic (``every_message: true``): no condition
    every_message: bool = False

    @property
    def label(self) -> str:
        """``events.Clean``: how messages name the entry."""
        return f"{self.kind}s.{self.name}"

    @property
    def default_qos(self) -> Qos:
        """The QoS this entry reads with when the mapping states none (:func:`default_qos`)."""
        return default_qos(self.kind, self.type)

    def value(self, message: dict[str, Any]) -> Any:
        """The measure value (or event condition) for one message; MessageError if it has none.

        Non-finite or oversized numbers and values of the wrong kind are refused here,
        before they reach the Manager. An ``every_message`` event holds for any message.
        """
        if self.every_message:
            return True
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
        """Check mapping ``text`` as :meth:`load` does; ``source`` names it in messages.

        Everything is checked here, before any middleware starts: the entries, and that the
        entries sharing a topic agree on its type and QoS (:meth:`topics`, :meth:`qos_of`).
        """
        doc = read_yaml(text, source)
        if not isinstance(doc, dict):
            raise MappingError(f"{source}: expected a mapping with `measures` and/or `events`")
        unknown = set(doc) - set(SECTIONS)
        if unknown:
            first = min(unknown, key=lambda k: str(k))
            raise MappingError(f"{_at(source, doc, first)}: unknown section(s) {_unknown(unknown, SECTIONS)}")
        namespace = doc.get("namespace")
        if namespace is not None and (not isinstance(namespace, str) or not namespace):
            raise MappingError(
                f"{_at(source, doc, 'namespace')}: `namespace` must be a topic prefix such as /cosleec, "
                f"not {show(namespace)}"
            )
        m = cls(namespace=namespace, source=source)
        for kind in ("measures", "events"):
            section = doc.get(kind) or {}
            if not isinstance(section, dict):
                raise MappingError(f"{_at(source, doc, kind)}: `{kind}` must map names to entries")
            for name, spec in section.items():
                at = _at(source, section, name)
                m.entries.append(_entry(source, at, kind[:-1], str(name), spec, measures, events))
        for t in m.topics():  # a conflict on a topic is found now, not when the node subscribes
            m.qos_of(t)
        return m

    def topics(self) -> dict[str, str]:
        """topic -> message type; MappingError if one topic is given two types."""
        out: dict[str, str] = {}
        first: dict[str, Entry] = {}
        for e in self.entries:
            if out.setdefault(e.topic, e.type) != e.type:
                f = first[e.topic]
                raise MappingError(
                    f"{e.where or self.source}: {e.label}: topic {e.topic} is given two types: "
                    f"{out[e.topic]} (by {f.label}) and {e.type}"
                )
            first.setdefault(e.topic, e)
        return out

    def qos_of(self, topic: str) -> Qos:
        """The QoS of the one subscription that serves every entry on ``topic``.

        A QoS stated by an entry is the topic's (entries that state different ones are a
        MappingError naming both). Else best effort (``sensor_data``) if any entry on the
        topic reads best effort by default -- a measure, or a ``sensor_msgs`` type -- and
        ``reliable`` only if all are events that default to it. Not "the stronger wins":
        a reliable subscription never hears a best-effort publisher, so it would make the
        measure deaf to the sensor it was meant for, while best effort hears any publisher
        and on a topic that carries a state (a measure) the next sample replaces a lost
        one. State ``qos: reliable`` on one entry to have a reliable subscription anyway.
        MappingError if no entry reads ``topic``.
        """
        entries = [e for e in self.entries if e.topic == topic]
        if not entries:
            raise MappingError(f"{self.source}: no entry reads topic {topic}")
        stated = [e for e in entries if e.qos is not None]
        if stated:
            a = stated[0]
            assert a.qos is not None
            for b in stated[1:]:
                if b.qos != a.qos:
                    assert b.qos is not None
                    raise MappingError(
                        f"{b.where or self.source}: {b.label}: qos {b.qos.describe()} differs from "
                        f"{a.label}'s {a.qos.describe()} ({a.where or self.source}); the entries on "
                        f"topic {topic} share one subscription: give them the same qos, or give it on one"
                    )
            return a.qos
        if any(e.default_qos == Qos.SENSOR_DATA for e in entries):
            return Qos.SENSOR_DATA
        return Qos.RELIABLE


def _qos(at: str, kind: str, type_name: str, raw: Any) -> Qos:
    """The QoS an entry states (``raw``); a table's missing keys are the entry's default's.

    ``at`` (``mapping.yaml:9:5: events.Clean``) starts the MappingError, which wraps a QosError.
    """
    if isinstance(raw, dict) and not all(isinstance(k, str) for k in raw):
        raise MappingError(
            f"{at}: qos keys are reliability, durability and depth, not {sorted(map(str, raw))}"
        )
    try:
        return Qos.parse(raw, default_qos(kind, type_name))
    except QosError as e:
        near = _suggest(raw, Qos.PROFILES) if isinstance(raw, str) else ""
        raise MappingError(f"{at}: qos: {e}{near}") from None


def _bands(source: str, at: str, where: str, raw: Any) -> tuple[tuple[float, str], ...]:
    """The checked ``bands`` of the entry ``where`` (written at ``at``): finite bounds that rise.

    A band a finite reading can never fall in -- a bound that is NaN, infinite, too large
    for a float, or not above the bound before it -- is a MappingError at that bound.
    """
    if not isinstance(raw, list) or not raw:
        raise MappingError(f"{where}: `bands` is a list of [upper bound, literal], the last just [literal]")
    out: list[tuple[float, str]] = []
    for i, band in enumerate(raw):
        tail = i == len(raw) - 1 and isinstance(band, list) and len(band) == 1  # [literal]
        if not tail and not (isinstance(band, list) and len(band) == 2 and isinstance(band[0], int | float)):
            raise MappingError(f"{where}: band {i + 1} must be [upper bound, literal] (the last: [literal])")
        bound, literal = (math.inf, band[0]) if tail else (band[0], band[1])
        label = f"{_item_at(source, band, 0, at)}: {where.split(': ')[-1]}"
        if not isinstance(literal, str):
            raise MappingError(
                f"{_item_at(source, band, 0 if tail else 1, at)}: {where.split(': ')[-1]}: band {i + 1}'s literal must be a word of the scale, not {show(literal)}",
                hint="give the scale literal the band stands for, such as [0.3, low]",
            )
        shown = None if tail else _not_finite(bound)
        if shown is not None:
            raise MappingError(
                f"{label}: band {i + 1}'s bound must be a finite number, not {shown}: every finite reading "
                "falls on the same side of it, so a band would never (or always) be given; give a number, "
                "and give the last band no bound: [literal]"
            )
        if out and float(bound) <= out[-1][0]:
            before = raw[i - 1][0]
            raise MappingError(
                f"{label}: band {i + 1}'s bound {bound!r} must be above band {i}'s {before!r}: bands are "
                f"tried in order, so {literal!r} could never be given; list the bounds rising"
            )
        out.append((float(bound), literal))
    if out[-1][0] != math.inf:
        out.append((math.inf, out[-1][1]))
    return tuple(out)


@dataclass(frozen=True)
class _Written:
    """Where one entry is written, to start its errors: ``mapping.yaml:7:3: events.Clean``.

    ``at`` is the position of the entry's name; an error about one key (or its value)
    points at that key instead, when the loader kept its position.
    """

    source: str
    at: str
    kind: str  # "measure" | "event"
    name: str
    spec: Any

    @property
    def label(self) -> str:
        """``events.Clean``: how messages name the entry."""
        return f"{self.kind}s.{self.name}"

    @property
    def where(self) -> str:
        """``mapping.yaml:7:3: events.Clean``: the entry, at its name."""
        return f"{self.at}: {self.label}"

    def key(self, key: Any) -> str:
        """The entry, at its ``key`` (at its name when that position is unknown)."""
        return f"{_at(self.source, self.spec, key, self.at)}: {self.label}"

    def value(self, key: Any) -> str:
        """The entry, at the value of its ``key`` (at its name when that position is unknown)."""
        return f"{_value_at(self.source, self.spec, key, self.at)}: {self.label}"


def _check_keys(w: _Written) -> None:
    """The entry is a table of known keys, with a ``topic`` and a ``type`` (strings)."""
    spec = w.spec
    if not isinstance(spec, dict):
        raise MappingError(f"{w.where}: expected an entry with at least `topic` and `type`")
    extra = set(spec) - KEYS
    if extra:
        first = min(extra, key=lambda k: str(k))
        raise MappingError(f"{w.key(first)}: unknown key(s) {_unknown(extra, KEYS)}")
    for key in ("topic", "type"):
        if not isinstance(spec.get(key), str) or not spec[key]:
            raise MappingError(f"{w.where}: `{key}` is required and must be a string")


def _comparison(w: _Written) -> tuple[str, Any] | None:
    """The entry's one comparison (``("below", 10)``), if it gives one; a number in it must be finite.

    At most one comparison or ``bands``: two would say two ways to make one value.
    """
    comps = [k for k in COMPARISONS if k in w.spec]
    if len(comps) + ("bands" in w.spec) > 1:
        raise MappingError(f"{w.where}: give at most one of {sorted(COMPARISONS)} or `bands`")
    if not comps:
        return None
    op = comps[0]
    shown = _not_finite(w.spec[op])
    if shown is not None:  # `below: .nan` would be taken, and the condition never hold
        raise MappingError(
            f"{w.value(op)}: `{op}` must be a finite number, not {shown}: {FIXED}; "
            f"give a number such as `{op}: 10`"
        )
    problem = value_problem(op, w.spec[op], None, str(w.spec["type"]))  # null, a list, a word to order
    if problem is not None:
        raise MappingError(f"{w.value(op)}: {problem[0]}", hint=problem[1])
    return op, w.spec[op]


def _every(w: _Written) -> bool:
    """Whether the entry is an event that fires on every message of its topic (``every_message: true``).

    Said, never implied: an event without a condition is a forgotten condition unless it
    says so. Such an event has no condition and reads no field, so a key that makes a
    value (a comparison, ``bands``, ``field``, ``json``) or says when it fires (``fire``)
    is refused beside it: it would be ignored.
    """
    if EVERY_MESSAGE not in w.spec:
        return False
    at, every = w.key(EVERY_MESSAGE), w.spec[EVERY_MESSAGE]
    if w.kind != "event":
        raise MappingError(
            f"{at}: `{EVERY_MESSAGE}` is for events; a measure's value is sent with every message already",
            hint=f"leave out `{EVERY_MESSAGE}`",
        )
    if not isinstance(every, bool):
        raise MappingError(
            f"{at}: `{EVERY_MESSAGE}` is true or false, not {show(every)}",
            hint=f"write `{EVERY_MESSAGE}: true`",
        )
    clash = [k for k in (*COMPARISONS, "bands", "field", "json", "fire") if k in w.spec]
    if every and clash:
        raise MappingError(
            f"{w.key(clash[0])}: an `{EVERY_MESSAGE}` event fires on every message without a condition, "
            f"so `{clash[0]}` would be ignored",
            hint=f"leave out `{clash[0]}`; or, to fire on every message for which a condition holds, leave "
            f"out `{EVERY_MESSAGE}` and give the condition with `fire: each`",
        )
    return every


def _fire(w: _Written) -> str:
    """How the event fires: ``edge`` (the default) or ``each``; ``fire`` on a measure is an error."""
    fire = w.spec.get("fire", "edge")
    if "fire" in w.spec:
        fire_at = w.key("fire")
        if w.kind != "event":
            raise MappingError(
                f"{fire_at}: `fire` is for events; a measure's value is sent with every message"
            )
        if fire not in FIRE:
            raise MappingError(
                f"{fire_at}: `fire` is edge (when the condition becomes true; the default) or each "
                f"(every message for which it holds), not {show(fire)}{_suggest(fire, FIRE)}"
            )
    return str(fire)


def _field(w: _Written) -> tuple[str, ...]:
    """The dotted path of the field read: ``data`` of a plain message, the root of a JSON payload."""
    if "json" in w.spec and not isinstance(w.spec["json"], bool):
        raise MappingError(f"{w.where}: `json` must be true or false, not {w.spec['json']!r}")
    default_field = "" if w.spec.get("json") else "data"
    return tuple(p for p in str(w.spec.get("field", default_field)).split(".") if p)


def _check_event(
    w: _Written, e: Entry, measures: Iterable[str] | None, events: frozenset[str] | None
) -> None:
    """An event entry names an event of the rules (when they are given), and has a condition."""
    if events is not None and w.name not in events:
        raise MappingError(
            f"{w.where}: the rules declare no event {w.name!r}"
            f"{_undeclared(w.name, 'event', events, measures or ())}"
        )
    if e.comparison is None and not e.every_message:
        raise MappingError(
            f"{w.where}: an event needs a condition (e.g. `equals: true`)",
            hint=f"give a comparison (`equals: true`, `above: 0.5`); to fire on every message of the "
            f"topic, say so: `{EVERY_MESSAGE}: true`",
        )


def _check_measure(
    w: _Written, e: Entry, measures: dict[str, MeasureSpec], events: frozenset[str] | None
) -> None:
    """A measure entry names a measure of the rules and makes a value of its kind.

    ``bands`` give literals of the measure's scale (only a scale measure has them), and a
    comparison gives a boolean (so not for a numeric measure).
    """
    ms = measures.get(w.name)
    if ms is None:
        raise MappingError(
            f"{w.where}: the rules declare no measure {w.name!r}"
            f"{_undeclared(w.name, 'measure', measures, events or ())}"
        )
    if ms.kind == "scale":
        if e.bands is not None:
            bad = [lit for _, lit in e.bands if lit not in ms.literals]
            if bad:
                raise MappingError(
                    f"{w.where}: {bad} not in the scale of {w.name} ({', '.join(ms.literals)})"
                    + _near_each(bad, ms.literals)
                )
    elif e.bands is not None:
        raise MappingError(f"{w.where}: `bands` give scale literals, but {w.name} is {ms.kind}")
    if ms.kind != "boolean" and e.comparison is not None:
        raise MappingError(
            f"{w.where}: a comparison gives a boolean, but {w.name} is {ms.kind}",
            hint="leave out the comparison to take the value as it is"
            + (", or give `bands` to turn a number into a literal" if ms.kind == "scale" else ""),
        )
    _check_as_is(w, e, ms)


#: per measure kind: the kind of field it can be taken from as it is, and how to make it from another
AS_IS = {
    "boolean": ("boolean", "give a comparison that makes the boolean (`below: 0.2`, `equals: open`)"),
    "numeric": (
        "number",
        "read a number: a number type (std_msgs/Float64), or JSON text (`json: true`, `field`)",
    ),
    "scale": (
        "text",
        "give `bands` ([[0.3, low], [high]]) to turn a number into a literal, or read the literal as text",
    ),
}


def _check_as_is(w: _Written, e: Entry, ms: MeasureSpec) -> None:
    """A measure taken as it is (no comparison, no bands) reads a field of its kind, where the
    message type says the field's kind: else every message would be rejected on the robot."""
    held = field_kind(e.type, e.field, e.json)
    if e.comparison is not None or e.bands is not None or held is None:
        return
    needed, fix = AS_IS[ms.kind]
    if held != needed:
        raise MappingError(
            f"{w.where}: {e.type}'s data is a {held}, but {w.name} is {ms.kind}: taken as it is, "
            "every message would be rejected",
            hint=fix,
        )


def _check_field(w: _Written, e: Entry) -> None:
    """The entry reads a field its message type has, and compares it with a value of its kind
    (:mod:`cosleec.nodes.mapping_values`: known for the plain ``std_msgs`` types)."""
    if e.every_message:
        return
    problem = field_problem(e.type, e.field, e.json)
    if problem is not None:
        raise MappingError(f"{w.key('json' if e.json else 'field')}: {problem[0]}", hint=problem[1])
    held = field_kind(e.type, e.field, e.json)
    if e.comparison is not None:
        op, value = e.comparison
        problem = value_problem(op, value, held, e.type)
        if problem is not None:
            raise MappingError(f"{w.value(op)}: {problem[0]}", hint=problem[1])
    if e.bands is not None and held not in (None, "number"):
        raise MappingError(
            f"{w.key('bands')}: `bands` sort numbers, but {e.type}'s data is a {held}",
            hint="read a number type (std_msgs/Float64); a text that is a literal is taken as it is",
        )


def _entry(
    source: str,
    at: str,
    kind: str,
    name: str,
    spec: Any,
    measures: dict[str, MeasureSpec] | None,
    events: frozenset[str] | None,
) -> Entry:
    """One checked entry ``name`` of section ``kind``s, written at ``at`` (``mapping.yaml:7:3``).

    Checked in the order its mistakes are reported: the keys, the value it makes
    (comparison or bands), ``every_message``, ``fire``, ``json`` and ``qos``, the field and
    the comparison's value against the message type (where it is known); then, with the
    rules, that it names one of their measures or events and makes a value of its kind.
    """
    w = _Written(source, at, kind, name, spec)
    _check_keys(w)
    comparison = _comparison(w)
    bands = _bands(source, at, w.where, spec["bands"]) if "bands" in spec else None
    every = _every(w)
    fire = "each" if every else _fire(w)
    field_path = () if every else _field(w)  # it reads no field: a message without one still fires it
    e = Entry(
        name=name,
        kind=kind,
        topic=spec["topic"],
        type=spec["type"],
        field=field_path,
        json=bool(spec.get("json")),
        comparison=comparison,
        bands=bands,
        qos=_qos(w.key("qos"), kind, spec["type"], spec["qos"]) if "qos" in spec else None,
        fire=fire,
        where=at,
        every_message=every,
    )
    _check_field(w, e)
    if kind == "measure" and measures is not None and name in measures:
        spec_of = measures[name]
        e = replace(e, measure_kind=spec_of.kind, literals=tuple(spec_of.literals))
    if kind == "event":
        _check_event(w, e, measures, events)
    elif measures is not None:
        _check_measure(w, e, measures, events)
    return e
