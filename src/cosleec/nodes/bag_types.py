"""The ROS 2 types of a recording: ``cosleec_interfaces`` read from its ``.msg`` files, their
``ros2msg`` schemas as rosbag2 writes them, and CDR bytes -- in pure Python (``rosbags``).

A recording is written without rclpy, so the Manager node records the same bytes on ROS 2,
on ROS 1 and on the in-process bus. The types come from the interface definitions
(``interfaces/cosleec_interfaces/msg/*.msg``, see :func:`interface_dir`), registered into a
``rosbags`` type store for ROS 2 Jazzy, which knows ``std_msgs`` and ``builtin_interfaces``.

A schema is what rosbag2 stores for a type (``ros2msg``, rosbag2's
``message_definition_encoding`` document in its docs): the type's own definition first, as its ``.msg``
file says it (comments kept), then each type it uses, nested ones included, each after a
line of 80 ``=`` and a line ``MSG: pkg/msg/Type``.
"""

from __future__ import annotations

import os
import re
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from cosleec.errors import UserError

PACKAGE = "cosleec_interfaces"
"""The ROS package of cosleec's message types."""

SEPARATOR = "=" * 80
"""The line between two definitions of a ``ros2msg`` schema."""


class RecordingError(UserError):
    """A recording that cannot be written or read: the types are missing, the file is no MCAP
    file, or a channel holds a type that carries no runtime record."""


def _candidates() -> list[Path]:
    """Where the ``msg`` directory of ``cosleec_interfaces`` may be, most specific first."""
    here = Path(__file__).resolve()
    found = [here.parents[3] / "interfaces" / PACKAGE / "msg"]  # a checkout (src layout)
    shipped = resources.files("cosleec")  # the wheel's copy, for `cosleec ros2 setup`
    found.append(Path(str(shipped / "ros" / "share" / PACKAGE / "msg")))
    for prefix in filter(None, os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)):
        found.append(Path(prefix) / "share" / PACKAGE / "msg")  # an installed ROS 2 package
    return found


def interface_dir() -> Path:
    """The directory of ``cosleec_interfaces``' ``.msg`` files; :class:`RecordingError` if none is found.

    Searched in a checkout (``interfaces/cosleec_interfaces/msg``), in the installed package
    (``cosleec/ros/share/cosleec_interfaces/msg``: package data, not an import), then under each prefix of ``AMENT_PREFIX_PATH`` (``share/cosleec_interfaces/msg``).
    """
    for d in _candidates():
        if (d / "Decision.msg").is_file():
            return d
    raise RecordingError(
        "cannot find the definitions of cosleec_interfaces (msg/*.msg) to record ROS 2 messages",
        where=", ".join(str(d) for d in _candidates()[:2]),
        hint="run from a cosleec checkout or source a ROS 2 workspace where cosleec_interfaces is "
        "built; or record the JSON form: --record-format json",
    )


class RosTypes:
    """A ``rosbags`` type store holding ROS 2 Jazzy's standard types and ``cosleec_interfaces``.

    Made once per process (:func:`ros_types`): reading and registering the types takes a few
    milliseconds. ``make`` builds a message with every field it is not given at its zero
    value; ``serialize`` gives CDR (little-endian), as rosbag2 stores it.
    """

    def __init__(self, msg_dir: Path | None = None) -> None:
        try:
            from rosbags.typesys import Stores, get_types_from_msg, get_typestore
        except ModuleNotFoundError as e:
            raise RecordingError(
                f"recording ROS 2 messages needs the `rosbags` package ({e.name} is missing)",
                hint="pip install 'cosleec[record]', or record the JSON form: --record-format json",
            ) from None
        self.store = get_typestore(Stores.ROS2_JAZZY)
        self.texts: dict[str, str] = {}  # type -> its .msg file as written (comments kept)
        found: dict[str, Any] = {}
        msg_dir = msg_dir or interface_dir()
        if not (msg_dir / "Decision.msg").is_file():
            raise RecordingError(
                "cannot find the definitions of cosleec_interfaces (msg/*.msg) to record ROS 2 messages",
                where=str(msg_dir),
                hint="give the msg directory of interfaces/cosleec_interfaces; or record the JSON form: "
                "--record-format json",
            )
        for f in sorted(msg_dir.glob("*.msg")):
            name = f"{PACKAGE}/msg/{f.stem}"
            self.texts[name] = f.read_text(encoding="utf-8")
            found.update(get_types_from_msg(self.texts[name], name))
        self.store.register(found)

    def schema(self, typename: str) -> bytes:
        """The ``ros2msg`` schema of ``typename``: its definition, then every type it uses.

        As rosbag2 makes it (``LocalMessageDefinitionSource::get_full_text``): each definition
        as its file says it, then, depth first and in sorted order, each type it names that
        was not given yet, after a blank line, the line of ``=`` and ``MSG: `` with the name as
        the field spells it (``std_msgs/Header``; a name without a package is in the
        package of the type that uses it). Foxglove's parser looks types up by that name.
        """
        seen: set[str] = set()

        def walk(name: str) -> str:
            pkg, _, short = name.partition("/")
            text = self._text(f"{pkg}/msg/{short.rsplit('/', 1)[-1]}")
            out = text
            for dep in sorted(_uses(text, pkg)):
                if dep not in seen:
                    seen.add(dep)
                    out += f"\n{SEPARATOR}\nMSG: {dep}\n" + walk(dep)
            return out

        return walk(typename).encode()

    def _text(self, typename: str) -> str:
        """The definition of one type: its ``.msg`` file, else as ``rosbags`` knows it."""
        if typename in self.texts:
            return self.texts[typename]
        if typename not in self.store.types:
            raise RecordingError(
                f"no definition of the ROS type {typename} to write its schema",
                hint="a recording holds only cosleec_interfaces and standard ROS 2 types",
            )
        generated, _ = self.store.generate_msgdef(typename, ros_version=2)
        return generated.split(f"{SEPARATOR}\n")[0]

    def make(self, typename: str, **fields: Any) -> Any:
        """A message of ``typename`` with ``fields``; every other field at its zero value."""
        cls = self.store.types[typename]
        for name, kind in self.store.fielddefs[typename][1]:
            if name not in fields:
                fields[name] = self._zero(kind)
            elif _numbers(kind):  # rosbags holds a sequence of numbers as a numpy array
                fields[name] = _array(fields[name], _numbers(kind))
        return cls(**fields)

    def _zero(self, kind: Any) -> Any:
        """The zero value of one field, from its rosbags field description (node type, detail)."""
        from rosbags.interfaces import Nodetype

        node, detail = kind
        if node == Nodetype.NAME:
            return self.make(detail)
        if node == Nodetype.SEQUENCE:
            return _array([], _numbers(kind)) if _numbers(kind) else []
        if node == Nodetype.ARRAY:  # a fixed size: that many zeros
            inner, size = detail
            zeros = [self._zero(inner) for _ in range(size)]
            return _array(zeros, _numbers(kind)) if _numbers(kind) else zeros
        base = detail[0] if isinstance(detail, tuple) else detail
        if base == "string" or base == "wstring":
            return ""
        if base == "bool":
            return False
        return 0.0 if base.startswith("float") else 0

    def serialize(self, message: Any, typename: str) -> bytes:
        """The CDR bytes of ``message`` (a message of ``typename``)."""
        return bytes(self.store.serialize_cdr(message, typename))


#: a field's type in a ``.msg`` definition, as rosbag2 finds them ("std_msgs/Header" in
#: "std_msgs/Header header"); comments and constants' names do not match
_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_PRIMITIVES = frozenset(
    {
        *("bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16"),
        *("int32", "uint32", "int64", "uint64", "string", "wstring"),
    }
)


def _uses(text: str, package: str) -> set[str]:
    """The message types a definition's fields name, as ``pkg/Type`` (rosbag2's dependencies)."""
    found = set()
    for m in _FIELD_TYPE.finditer(text):
        name = m.group(1)
        if name not in _PRIMITIVES:
            found.add(name if "/" in name else f"{package}/{name}")
    return found


#: ROS names of primitive types numpy names otherwise
_DTYPES = {"byte": "uint8", "char": "uint8", "octet": "uint8", "bool": "bool"}


def _numbers(kind: Any) -> str:
    """The numpy type of a field that is a sequence (or array) of numbers, else ""."""
    from rosbags.interfaces import Nodetype

    node, detail = kind
    if node not in (Nodetype.SEQUENCE, Nodetype.ARRAY):
        return ""
    (inner, inner_detail), _ = detail
    if inner != Nodetype.BASE:
        return ""
    base = inner_detail[0] if isinstance(inner_detail, tuple) else inner_detail
    return "" if base in ("string", "wstring") else str(_DTYPES.get(base, base))


def _array(values: Any, dtype: str) -> Any:
    import numpy as np

    return np.array(list(values), dtype=dtype)


@cache
def ros_types() -> RosTypes:
    """The process's type store (read once, from :func:`interface_dir`)."""
    return RosTypes()
