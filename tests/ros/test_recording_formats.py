"""``cosleec ros2|ros1 manager --record FILE.mcap [--record-format json]`` on a real middleware.

The Manager node runs as its own process (``cosleec.ros.demo.System``: the command line a user
types), a driver sends it context and an event, and the recording it leaves is read by a tool
nobody here wrote: ``rosbags`` for the rosbag2 default (typed, with only the types the file
defines), ``mcap``'s own reader for the JSON copy. The recorder is the same on ROS 1: a rosbag2
MCAP is written in pure Python.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from cosleec.nodes import read_recording
from cosleec.ros.demo import System
from cosleec.ros.driver import Driver


@pytest.mark.parametrize("fmt", ["ros2", "json"])
def test_the_manager_node_records_in_the_format_asked(
    fmt: str, backend: str, graph: dict[str, str], transport: Any, namespace: str, tmp_path: Path
) -> None:
    pytest.importorskip("rosbags")
    path = tmp_path / "run.mcap"
    args = ["--record", str(path)] + (["--record-format", fmt] if fmt != "ros2" else [])
    with System(backend, namespace, env=graph, manager_args=args):
        driver = Driver(transport, namespace)
        driver.ready()
        driver.set({"userUndressed": True, "userDistressed": "low"})
        driver.event("CurtainOpenRequest")
    records = read_recording(path)
    decision = next(r for t, r in records if t == "/cosleec/decision")
    assert (decision["rule"], decision["layer"]) == ("R1", "R1.1")
    from mcap.reader import make_reader

    with path.open("rb") as fh:
        reader = make_reader(fh)
        profile = reader.get_header().profile
        summary = reader.get_summary()
        assert summary is not None
        encodings = {c.message_encoding for c in summary.channels.values()}
    if fmt == "json":
        assert (profile, encodings) == ("", {"json"})
        with path.open("rb") as fh:
            assert all(json.loads(m.data)["kind"] for _, _, m in make_reader(fh).iter_messages())
        return
    assert (profile, encodings) == ("ros2", {"cdr"})
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([path], default_typestore=get_typestore(Stores.EMPTY)) as bag:
        typed: list[Any] = [
            bag.deserialize(raw, c.msgtype)
            for c, _, raw in bag.messages()
            if c.msgtype == "cosleec_interfaces/msg/Decision"
        ]
    assert [(m.rule, m.layer, m.trigger) for m in typed][:1] == [("R1", "R1.1", "CurtainOpenRequest")]
    assert {v.name for v in typed[0].values} >= {"userUndressed", "userDistressed"}
