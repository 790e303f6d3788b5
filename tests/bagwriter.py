"""Bags written the way field recordings are: by rosbags' own writers (rosbag2 MCAP, rosbag2
SQLite 3, ROS 1 .bag) with the standard message types of its type stores. For the tests of
``cosleec conforms RULES BAG --mapping M`` (tests/unit/test_conforms_bags.py, tests/ros)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Nodetype

#: a bag's start, in ns since the epoch (2024-06-10 06:40:00 UTC): field recordings have such stamps
T0 = 1_718_001_600 * 10**9
FORMATS = ("mcap", "sqlite3", "ros1")

#: (seconds from T0, topic, type, fields): one message of a bag
Message = tuple[float, str, str, dict[str, Any]]

_NUMPY = {"float32": np.float32, "float64": np.float64, "uint8": np.uint8, "int32": np.int32}


def store(fmt: str) -> Any:
    return get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.ROS2_JAZZY)


def message(ts: Any, msgtype: str, **given: Any) -> Any:
    """A ``msgtype`` message of type store ``ts``: ``given`` fields, every other one zero or empty."""
    _, fields = ts.fielddefs[msgtype]
    kw: dict[str, Any] = {}
    for name, (nodetype, detail) in fields:
        if name in given:
            kw[name] = given[name]
        elif nodetype == Nodetype.BASE:
            base = detail[0]
            kw[name] = "" if base == "string" else False if base == "bool" else 0.0 if "float" in base else 0
        elif nodetype == Nodetype.NAME:
            kw[name] = message(ts, detail)
        else:  # a sequence of numbers (BatteryState's cell voltages): empty
            kw[name] = np.array([], dtype=_NUMPY.get(detail[0][1][0], np.float64))
    return ts.types[msgtype](**kw)


def write_bag(path: Path, fmt: str, messages: Iterable[Message]) -> Path:
    """A bag of ``messages`` at ``path`` (a directory for rosbag2, ``path.bag`` for ROS 1)."""
    ts = store(fmt)
    messages = sorted(messages, key=lambda m: m[0])
    if fmt == "ros1":
        path = path.with_suffix(".bag")
        with Writer1(path) as w1:
            conns1: dict[str, Any] = {}
            for t, topic, msgtype, given in messages:
                c = conns1.get(topic) or conns1.setdefault(
                    topic, w1.add_connection(topic, msgtype, typestore=ts)
                )
                w1.write(c, T0 + round(t * 1e9), ts.serialize_ros1(message(ts, msgtype, **given), msgtype))
        return path
    plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns: dict[str, Any] = {}
        for t, topic, msgtype, given in messages:
            c = conns.get(topic) or conns.setdefault(topic, w.add_connection(topic, msgtype, typestore=ts))
            w.write(c, T0 + round(t * 1e9), ts.serialize_cdr(message(ts, msgtype, **given), msgtype))
    return path


def write_raw_bag(path: Path, received: Iterable[tuple[int, str, str, bytes]]) -> Path:
    """A rosbag2 MCAP bag of CDR messages as a ROS 2 subscriber received them: (ns, topic, type, bytes)."""
    ts = store("mcap")
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns: dict[str, Any] = {}
        for stamp, topic, msgtype, data in sorted(received, key=lambda m: m[0]):
            c = conns.get(topic) or conns.setdefault(topic, w.add_connection(topic, msgtype, typestore=ts))
            w.write(c, stamp, data)
    return path
