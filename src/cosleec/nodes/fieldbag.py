"""Field bags through the Context Listener: a recording of the robot's own topics, replayed.

Robots are tested in the field with ``ros2 bag record`` (or ROS 1's ``rosbag record``)
running. :func:`replay` reads such a bag -- a rosbag2 directory (MCAP or SQLite 3) or a
ROS 1 ``.bag`` -- with ``rosbags`` (pure Python: no ROS needed; ``pip install
'cosleec[bags]'``) and feeds its messages, in bag time, to a real
:class:`~cosleec.nodes.listener.ListenerNode` built on the given
:class:`~cosleec.nodes.mapping.Mapping`. The listener's own code makes the measure updates
and events -- edges, ``fire: each``, the checks on every value, the rejection of a message
an entry cannot read -- so a bag is judged on exactly what the deployed listener would have
told the Manager. QoS plays no part: the bag holds what the recorder heard.

The result, a :class:`BagTrace`, is a list of :class:`BagStep` (time in seconds from the
bag's start, values set, an event) each with the :class:`Origin` of the message behind it
(topic, bag time). ``cosleec conforms RULES BAG --mapping M`` judges it by the reference
semantics; any other reader of a trace (``cosleec timeline``) can take it the same way.

A bag the mapping does not fully cover fails closed: a topic of the mapping missing from
the bag, recorded with another type, or a field the mapping reads that the bag's type has
not, is a *gap* (:attr:`BagTrace.gaps`, one sentence each). Its measures stay unknown and
its events never happen -- the rules' unknown policy decides what that means, as with the
deployed listener -- and :attr:`BagTrace.complete` is False, which ``conforms`` never
reports as a pass. Messages the listener rejects are counted (:attr:`BagTrace.rejections`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, fields, is_dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from cosleec.errors import UserError, clip
from cosleec.nodes.listener import ListenerNode
from cosleec.nodes.mapping import Entry, Mapping
from cosleec.nodes.qos import Qos

__all__ = ["BagError", "BagStep", "BagTrace", "Origin", "is_bag", "replay"]

#: the listener's rejections are reported in :attr:`BagTrace.rejections`, not logged again
_quiet = logging.getLogger("cosleec.nodes.fieldbag.listener")
_quiet.addHandler(logging.NullHandler())
_quiet.propagate = False

#: what a rosbag2 directory holds (its metadata.yaml and storage files) and a ROS 1 bag's suffix
BAG_SUFFIXES = (".bag", ".mcap", ".db3")
#: how many kinds of rejection are reported one by one
MAX_REJECTIONS = 20


class BagError(UserError):
    """A bag that cannot be read: not a bag, a bag rosbags cannot open, or rosbags missing."""


@dataclass(frozen=True, slots=True)
class Origin:
    """The bag message behind a step: its ``topic``, its bag time ``stamp`` (nanoseconds since
    the epoch, as the recorder logged it) and ``offset`` (seconds from the bag's start)."""

    topic: str
    stamp: int
    offset: float

    def bag_time(self) -> str:
        """``1718000012.500000000``: the stamp as seconds.nanoseconds, exactly."""
        return f"{self.stamp // 10**9}.{self.stamp % 10**9:09d}"

    def describe(self) -> str:
        """``/fall_detector at 12.5 s (bag time 1718000012.500000000)``."""
        return f"{self.topic} at {_s(self.offset)} s (bag time {self.bag_time()})"

    def to_json(self) -> dict[str, Any]:
        """``{"topic", "stamp_ns", "t"}`` for ``--json``."""
        return {"topic": self.topic, "stamp_ns": self.stamp, "t": self.offset}


@dataclass(frozen=True, slots=True)
class BagStep:
    """What the listener made of one bag message: ``values`` set, or one ``event``, at ``t``
    (seconds from the bag's start). ``origin`` None: the step that marks the bag's end."""

    t: float
    values: dict[str, Any] = field(default_factory=dict)
    event: str | None = None
    origin: Origin | None = None


@dataclass
class BagTrace:
    """A bag replayed through a mapping: the steps, and what the bag did not give the mapping.

    ``start``: the bag's start (ns since the epoch; ``t`` 0); ``end``: its last time, in
    seconds from the start; ``read``: the messages fed to the listener; ``gaps``: what of
    the mapping the bag does not cover (fail closed); ``rejections``: messages the
    listener refused, by topic and reason, with the count and the first one's time.
    """

    source: str
    start: int
    end: float
    steps: list[BagStep] = field(default_factory=list)
    read: int = 0
    gaps: list[str] = field(default_factory=list)
    rejections: list[str] = field(default_factory=list)
    topics: dict[str, int] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        """True when every entry of the mapping found its topic, type and field in the bag."""
        return not self.gaps

    def describe(self) -> str:
        """``run1 (rosbag2): 120 messages on 3 mapped topics, 60 s from 2024-06-10 06:40:12 UTC``."""
        when = datetime.fromtimestamp(self.start / 1e9, UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
        topics = len([t for t, n in self.topics.items() if n])
        return (
            f"{self.source}: {self.read} message{'' if self.read == 1 else 's'} on {topics} mapped "
            f"topic{'' if topics == 1 else 's'}, {_s(self.end)} s from {when} "
            f"(bag time {self.start // 10**9}.{self.start % 10**9:09d}); times are seconds from its start"
        )


def is_bag(path: str | Path) -> bool:
    """Does ``path`` look like a bag (a rosbag2 directory, a ``.bag``, ``.mcap`` or ``.db3``)?

    For ``cosleec conforms``, which must tell a user who gave a bag without ``--mapping``
    what is missing instead of failing to read it as JSON Lines.
    """
    p = Path(path)
    return (p / "metadata.yaml").is_file() or p.suffix in BAG_SUFFIXES


def replay(path: str | Path, mapping: Mapping) -> BagTrace:
    """The trace the Context Listener, built on ``mapping``, makes of the bag at ``path``.

    Every message on a topic of the mapping, in bag time, goes to a real
    :class:`ListenerNode` (the deployed one's code, QoS aside); what it publishes becomes
    the steps, each naming its message. A last step marks the bag's end. BagError when the
    bag cannot be read; a bag that leaves part of the mapping uncovered is no error but a
    :attr:`BagTrace.gaps` entry (fail closed).
    """
    with _open(Path(path)) as reader:
        start = int(reader.start_time)
        end_ns = max(int(reader.end_time) - 1, start)  # rosbags' end is just after the last message
        out = BagTrace(source=str(path), start=start, end=(end_ns - start) / 1e9)
        feeds = _feeds(reader, mapping, out)
        replayer = _Replayer(mapping, out)
        connections = [c for conns in feeds.values() for c in conns]
        for connection, stamp, raw in reader.messages(connections=connections) if connections else ():
            origin = Origin(connection.topic, int(stamp), (int(stamp) - start) / 1e9)
            try:
                message = _fields(reader.deserialize(raw, connection.msgtype))
            except Exception as e:  # a message rosbags cannot decode: the listener never hears it
                replayer.refused(origin, f"cannot be decoded: {clip(str(e), 120)}")
                continue
            out.topics[origin.topic] = out.topics.get(origin.topic, 0) + 1
            out.read += 1
            replayer.feed(origin, message)
        out.rejections = replayer.rejections()
    for topic in feeds:  # a topic the bag declares but never carried: nothing was heard there
        if not out.topics.get(topic):
            out.gaps.append(f"topic {topic} has no message in the bag: {_names(_reading(mapping, topic))}")
    out.steps.append(BagStep(t=out.end))
    return out


# ---------------------------------------------------------------------------- feeding the listener


class _Capture:
    """The :class:`~cosleec.nodes.transport.Transport` a replayed listener runs on: it keeps
    the typed handlers the node subscribes, and the records the node publishes, in order."""

    def __init__(self) -> None:
        self.handlers: dict[str, Any] = {}
        self.published: list[tuple[str, dict[str, Any]]] = []

    def publish(self, topic: str, message: dict[str, Any] | str) -> None:
        """Keep what the node sends (it sends records, never text)."""
        if isinstance(message, dict):
            self.published.append((topic.rsplit("/", 1)[-1], message))

    def subscribe(self, topic: str, handler: Any) -> None:
        """The listener subscribes no cosleec topic; nothing to keep."""

    def subscribe_typed(self, topic: str, type_name: str, handler: Any, qos: Qos | None = None) -> None:
        """Keep the handler of ``topic``: the replay calls it with each message (QoS is moot)."""
        self.handlers[topic] = handler

    def advertise(self, topic: str, latched: bool = False) -> None:
        """Nothing to declare: what is published is kept."""

    def close(self) -> None:
        """Nothing to release."""


class _Replayer:
    """A :class:`ListenerNode` on a :class:`_Capture`, fed one bag message at a time: after each,
    what the node published becomes steps of ``out`` with the message's origin."""

    def __init__(self, mapping: Mapping, out: BagTrace) -> None:
        self.capture = _Capture()
        self.node = ListenerNode(self.capture, mapping)
        self.node.status_each = False  # no status record after each rejection: nobody listens
        self.node.limiter.logger = _quiet  # rejections are reported as notes, not logged
        self.out = out
        self.refusals: dict[tuple[str, str], tuple[int, Origin]] = {}

    def feed(self, origin: Origin, message: dict[str, Any]) -> None:
        """Give ``message`` to the listener's handler of its topic; keep what the handler published."""
        self.capture.handlers[origin.topic](message)
        for kind, record in self.capture.published:
            if kind == "context":
                self.out.steps.append(BagStep(origin.offset, values=dict(record["values"]), origin=origin))
            elif kind == "events":
                self.out.steps.append(BagStep(origin.offset, event=str(record["event"]), origin=origin))
            elif kind == "rejected":
                self.refused(origin, str(record.get("reason", "")))
        self.capture.published.clear()

    def refused(self, origin: Origin, reason: str) -> None:
        """Count a message the listener refused (or that could not be decoded), by topic and reason."""
        key = (origin.topic, reason)
        n, first = self.refusals.get(key, (0, origin))
        self.refusals[key] = (n + 1, first)

    def rejections(self) -> list[str]:
        """One sentence per topic and reason: how many messages, and when the first was."""
        out = [
            f"{n} message{'' if n == 1 else 's'} on {topic} rejected by the listener, the first "
            f"at {_s(first.offset)} s: {reason}"
            for (topic, reason), (n, first) in self.refusals.items()
        ]
        if len(out) > MAX_REJECTIONS:
            out = [*out[:MAX_REJECTIONS], f"... and {len(out) - MAX_REJECTIONS} more kinds of rejection"]
        return out


# ---------------------------------------------------------------------------- the bag


def _open(path: Path) -> Any:
    """An unopened rosbags ``AnyReader`` on the bag at ``path`` (a ``.mcap`` or ``.db3`` inside
    a rosbag2 directory stands for the directory); BagError for anything it cannot be."""
    try:
        from rosbags.highlevel import AnyReader, AnyReaderError
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise BagError(
            "reading a bag needs the rosbags package", hint="pip install 'cosleec[bags]'"
        ) from None
    if not path.exists():
        raise BagError("no such bag", where=str(path))
    if path.is_file() and path.suffix != ".bag" and (path.parent / "metadata.yaml").exists():
        path = path.parent
    if path.is_file() and path.suffix != ".bag":
        raise BagError(
            "not a bag rosbags reads: a rosbag2 bag is a directory with a metadata.yaml, a ROS 1 bag "
            "a .bag file",
            where=str(path),
            hint="give the bag's directory; `ros2 bag reindex DIR` writes a lost metadata.yaml",
        )
    store = Stores.ROS1_NOETIC if path.suffix == ".bag" else Stores.ROS2_JAZZY
    try:  # the bag's own definitions first (rosbags' rule); the standard types where it has none
        reader = AnyReader([path], default_typestore=get_typestore(store))
        reader.open()
    except (AnyReaderError, OSError, ValueError, KeyError) as e:
        raise BagError(f"rosbags cannot read the bag: {clip(str(e), 300)}", where=str(path)) from None
    return _Opened(reader)


class _Opened:
    """An open ``AnyReader``, closed when the ``with`` block ends."""

    def __init__(self, reader: Any) -> None:
        self.reader = reader

    def __enter__(self) -> Any:
        return self.reader

    def __exit__(self, *exc: object) -> None:
        self.reader.close()


def _feeds(reader: Any, mapping: Mapping, out: BagTrace) -> dict[str, list[Any]]:
    """topic -> the bag's connections the listener is fed from: those of the mapping's topics
    whose type is the mapping's. A mapping topic with no such connection, and an entry whose
    field the type has not, is a gap of ``out`` (its measure stays unknown, its event never
    happens)."""
    by_topic: dict[str, list[Any]] = {}
    for c in reader.connections:
        by_topic.setdefault(c.topic, []).append(c)
    feeds: dict[str, list[Any]] = {}
    for topic, type_name in mapping.topics().items():
        entries = _reading(mapping, topic)
        names = _names(entries)
        there = by_topic.get(topic, [])
        typed = [c for c in there if _same_type(c.msgtype, type_name)]
        out.topics[topic] = 0
        if not there:
            out.gaps.append(f"topic {topic} is not in the bag: {names}")
        elif not typed:
            found = ", ".join(sorted({c.msgtype for c in there}))
            out.gaps.append(f"topic {topic} is {found} in the bag, the mapping reads {type_name}: {names}")
        else:
            feeds[topic] = typed
            for e in entries:
                problem = _field_problem(reader.typestore, typed[0].msgtype, e)
                if problem:
                    out.gaps.append(f"{e.label} ({e.where or mapping.source}): {problem}: {_names([e])}")
    return feeds


def _reading(mapping: Mapping, topic: str) -> list[Entry]:
    """The entries of ``mapping`` that read ``topic``."""
    return [e for e in mapping.entries if e.topic == topic]


def _names(entries: list[Entry]) -> str:
    """What a gap means: ``measure roomDark stays unknown, event UserFallen never happens``."""
    return ", ".join(
        f"measure {e.name} stays unknown" if e.kind == "measure" else f"event {e.name} never happens"
        for e in entries
    )


def _same_type(bag_type: str, mapped: str) -> bool:
    """``std_msgs/msg/Bool`` (a bag's name) is the mapping's ``std_msgs/Bool`` or ``std_msgs/msg/Bool``."""
    return bag_type.replace("/msg/", "/") == mapped.replace("/msg/", "/")


def _field_problem(typestore: Any, msgtype: str, entry: Entry) -> str:
    """Why the bag's ``msgtype`` has not the field ``entry`` reads ("" when it has).

    Walks the type's definition, not a message: a field missing from the type is missing
    from every message. A JSON entry reads ``data``, a string; the path inside the JSON is
    the messages' business (the listener rejects a message that lacks it).
    """
    path = ("data",) if entry.json else entry.field
    current = msgtype
    for i, part in enumerate(path):
        defs = typestore.fielddefs.get(current)
        if defs is None:
            return f"{'.'.join(path[:i])} of {msgtype} is no message, it has no field {part!r}"
        kinds = dict(defs[1])
        if part not in kinds:
            shown = ", ".join(kinds) or "none"
            return f"{current} has no field {part!r} (its fields: {clip(shown, 200)})"
        nodetype, detail = kinds[part]
        current = detail if getattr(nodetype, "name", "") == "NAME" else ""
        if entry.json and detail != ("string", 0):
            return f"a JSON entry reads the text in `data`, but {msgtype}'s data is no string"
    return ""


def _fields(msg: Any) -> Any:
    """A decoded rosbags message as the listener gets a live one: nested dicts of its fields,
    arrays of messages as lists of dicts, arrays of numbers as lists (:func:`cosleec.ros.messages.to_dict`'s shape)."""
    if is_dataclass(msg) and not isinstance(msg, type):
        return {f.name: _fields(getattr(msg, f.name)) for f in fields(msg) if not f.name.startswith("__")}
    if isinstance(msg, list | tuple):
        return [_fields(x) for x in msg]
    tolist = getattr(msg, "tolist", None)  # numpy arrays (and numpy scalars): plain Python values
    return tolist() if callable(tolist) else msg


def _s(x: float) -> str:
    """Seconds for a note: ``12``, ``12.5``, ``0.001``."""
    if not math.isfinite(x):
        return str(x)
    return str(int(x)) if x == int(x) else f"{x:.3f}".rstrip("0").rstrip(".")
