"""A Manager node's recording is a rosbag2 MCAP that ROS tools nobody here wrote read, typed.

The demo's day is recorded by the project's recorder in both formats (``ros2``, the default,
and the ``json`` copy), then read back by ``rosbags`` (``AnyReader``, every message decoded
with the types the file itself defines), by ``mcap`` + ``mcap-ros2-support``
(``DecoderFactory``), by Foxglove's ``@mcap/core`` ``McapIndexedReader`` in Node with
``@foxglove/rosmsg2-serialization`` (tests/tools/mcap, installed by ``scripts/setup --dev``),
and by ``cosleec timeline``, which must draw the same run from either file. Then what is not
a recording, or holds a type no record is in, is one clear message.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from cosleec.cli.main import main
from cosleec.demo import run as run_demo
from cosleec.nodes import McapRecorder, read_recording
from cosleec.nodes.bag_messages import TYPES, type_of
from cosleec.nodes.bag_types import SEPARATOR, RecordingError, RosTypes, interface_dir, ros_types
from cosleec.records import RuntimeEvent
from cosleec.views import Timeline

ROOT = Path(__file__).resolve().parents[3]
NODE_READER = ROOT / "tests" / "tools" / "mcap"
NODE_PACKAGES = ("@mcap/core", "@foxglove/rosmsg", "@foxglove/rosmsg2-serialization")


@pytest.fixture(scope="module")
def day(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The demo's day: its audit log, its rosbag2 recording and the JSON copy of the same run."""
    folder = tmp_path_factory.mktemp("day")
    files = {"audit": folder / "day.jsonl", "ros2": folder / "day.mcap", "json": folder / "day-json.mcap"}
    recorders = [McapRecorder(files["ros2"]), McapRecorder(files["json"], fmt="json")]
    assert [r.format for r in recorders] == ["ros2", "json"]

    def both(ev: RuntimeEvent) -> None:
        for r in recorders:
            r.write(ev.kind, ev.time, ev.data)

    try:
        run_demo(audit=str(files["audit"]), on_event=both)
    finally:
        for r in recorders:
            r.close()
    return files


def kinds(path: Path) -> Counter[str]:
    return Counter(rec["kind"] for _, rec in read_recording(path))


def test_both_formats_hold_the_same_records(day: dict[str, Path]) -> None:
    ros2, copy = read_recording(day["ros2"]), read_recording(day["json"])
    assert len(ros2) > 50
    assert ros2 == copy  # nothing is lost in CDR: each message holds its whole record
    assert {"decision", "obligation", "layers", "refused", "context", "event"} <= {r["kind"] for _, r in ros2}


def test_rosbags_reads_every_message_typed(day: dict[str, Path]) -> None:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    want = kinds(day["json"])
    # an empty default type store: every type must come from the recording's own schemas
    with AnyReader([day["ros2"]], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert types == {f"/cosleec/{k}": type_of(k) for k in want}
        assert counts == {f"/cosleec/{k}": n for k, n in want.items()}
        decoded: list[tuple[str, Any]] = [
            (c.topic, reader.deserialize(raw, c.msgtype)) for c, _, raw in reader.messages()
        ]
    assert len(decoded) == sum(want.values())
    for topic, msg in decoded:
        record = json.loads(msg.record if hasattr(msg, "record") else msg.data)
        assert topic == f"/cosleec/{record['kind']}"
    decisions = [(m, json.loads(m.record)) for t, m in decoded if t == "/cosleec/decision"]
    assert decisions
    for m, r in decisions:
        assert (m.id, m.rule, m.trigger) == (r["id"], r["rule"], r["event"])
        assert m.clause == (-1 if r["clause"] is None else r["clause"])
        assert m.layer == (r.get("layer") or "")
        assert sorted(v.name for v in m.values) == sorted(r.get("values") or {})
        assert [o.event for o in m.obligations] == [o["event"] for o in r.get("obligations", [])]
    layers = [(m, json.loads(m.record)) for t, m in decoded if t == "/cosleec/layers"]
    assert any(m.switches for m, _ in layers)
    for m, r in layers:
        assert list(m.active) == r["active"]
        assert [(s.rule, s.current) for s in m.switches] == [
            (s["rule"], s["to"] or "") for s in r["switches"]
        ]


def test_mcap_ros2_support_decodes_it_and_the_file_is_indexed(day: dict[str, Path]) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with day["ros2"].open("rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == sum(kinds(day["json"]).values())
        assert summary.chunk_indexes and all(c.message_index_offsets for c in summary.chunk_indexes)
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert [(m.name, m.metadata["ROS_DISTRO"]) for m in reader.iter_metadata()] == [
            ("rosbag2", os.environ.get("ROS_DISTRO") or "jazzy")
        ]
        refused = [
            (m, json.loads(m.record))
            for _, c, _, m in reader.iter_decoded_messages(topics=["/cosleec/refused"])
        ]
    assert refused
    for m, r in refused:
        assert (m.event, list(m.rules), m.reason) == (r["event"], r["by"], r.get("reason", ""))


def test_the_schemas_hold_the_full_definitions_as_rosbag2_writes_them() -> None:
    decision = ros_types().schema("cosleec_interfaces/msg/Decision").decode()
    own, *deps = decision.split(f"\n{SEPARATOR}\n")
    assert own == (interface_dir() / "Decision.msg").read_text()  # the file, comments and all
    heads = [d.split("\n", 1)[0] for d in deps]
    assert heads == [  # depth first, sorted, each once: the names as the fields spell them
        "MSG: cosleec_interfaces/MeasureValue",
        "MSG: cosleec_interfaces/Obligation",
        "MSG: std_msgs/Header",
        "MSG: builtin_interfaces/Time",
    ]
    assert deps[0].split("\n", 1)[1] == (interface_dir() / "MeasureValue.msg").read_text()
    assert "uint8 SCALE=3" in deps[0]
    for typename in {*TYPES.values(), "std_msgs/msg/String"}:  # every type a recording uses parses
        from rosbags.typesys import get_types_from_msg

        assert typename in get_types_from_msg(ros_types().schema(typename).decode(), typename)


def node_reader() -> str:
    """node, when it and the reader's packages are installed; else skip (fail under CI)."""
    node = shutil.which("node")
    missing = [p for p in NODE_PACKAGES if not (NODE_READER / "node_modules" / p / "package.json").is_file()]
    if node is None or missing:
        why = "node is not installed" if node is None else f"npm packages missing: {', '.join(missing)}"
        if os.environ.get("CI"):
            pytest.fail(f"{why} under CI: scripts/setup --dev runs `npm ci` in tests/tools/mcap")
        pytest.skip(f"{why} (bash scripts/setup --dev, or npm ci in tests/tools/mcap)")
    return node


def test_foxglove_s_indexed_reader_finds_and_decodes_every_message(day: dict[str, Path]) -> None:
    node = node_reader()
    done = subprocess.run(
        [node, str(NODE_READER / "read.mjs"), str(day["ros2"])], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    got: dict[str, Any] = json.loads(done.stdout)
    want = kinds(day["json"])
    assert (got["profile"], got["library"]) == ("ros2", "cosleec")
    assert got["chunks"] >= 1
    assert got["statistics"]["messageCount"] == len(got["messages"]) == sum(want.values())
    assert got["metadata"][0]["name"] == "rosbag2"
    assert got["channels"]["/cosleec/decision"] == {
        "encoding": "cdr",
        "schema": "cosleec_interfaces/msg/Decision",
        "schemaEncoding": "ros2msg",
    }
    records = [json.loads(m["message"].get("record") or m["message"]["data"]) for m in got["messages"]]
    assert Counter(r["kind"] for r in records) == want
    for m in got["messages"]:
        if m["topic"] == "/cosleec/decision":
            msg, r = m["message"], json.loads(m["message"]["record"])
            assert (msg["id"], msg["rule"], msg["trigger"]) == (r["id"], r["rule"], r["event"])
            assert [v["name"] for v in msg["values"]] == list(r.get("values") or {})


def test_the_timeline_draws_the_same_from_either_format(
    day: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    audit, ros2, copy = (Timeline.read(day[k]) for k in ("audit", "ros2", "json"))
    for recorded in (ros2, copy):
        assert (recorded.bars, recorded.bands, recorded.links) == (audit.bars, audit.bands, audit.links)
        assert (recorded.series, recorded.markers) == (audit.series, audit.markers)
    pytest.importorskip("plotly")
    pages = []
    for k in ("ros2", "json"):
        out = tmp_path / f"{k}.html"
        assert main(["timeline", str(day[k]), "-o", str(out)]) == 0
        pages.append(out.read_text().replace(day[k].name, "RUN"))
    assert "Traceback" not in capsys.readouterr().err
    assert pages[0] == pages[1]


def test_a_recording_cut_short_reads_up_to_its_last_whole_chunk(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    recorder = McapRecorder(path)
    for i in range(40):
        recorder.write("decision", float(i), {"id": i, "rule": "R1", "event": "E", "clause": 0})
        if i % 10 == 9:
            recorder.flush()  # what the flusher does each second: a chunk, indexed, on disk
    whole = read_recording(path)
    recorder.close()
    assert [r["id"] for _, r in whole] == list(range(40))
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])  # a crash: no summary, a torn chunk
    got = read_recording(cut)
    assert 10 <= len(got) < 40 and len(got) % 10 == 0
    assert got == whole[: len(got)]


# ---------------------------------------------------------------------- mistakes


def foreign(path: Path, encoding: str = "cdr") -> Path:
    """An MCAP file a robot's recorder could have written: a geometry_msgs/Point channel."""
    from mcap.writer import Writer

    types = ros_types()
    with path.open("wb") as fh:
        w = Writer(fh)
        w.start(profile="ros2", library="robot")
        sid = w.register_schema("geometry_msgs/msg/Point", "ros2msg", types.schema("geometry_msgs/msg/Point"))
        ch = w.register_channel("/robot/goal", encoding, sid)
        point = types.make("geometry_msgs/msg/Point", x=1.0, y=2.0, z=0.0)
        w.add_message(ch, 1, types.serialize(point, "geometry_msgs/msg/Point"), 1)
        w.finish()  # type: ignore[no-untyped-call]
    return path


@pytest.mark.parametrize(
    ("make", "says"),
    [
        (lambda p: p.write_bytes(b"PAR1 not an mcap"), "it is not an MCAP file"),
        (
            foreign,
            "channel /robot/goal holds geometry_msgs/msg/Point messages, which carry no cosleec record",
        ),
        (lambda p: foreign(p, "protobuf"), "channel /robot/goal holds protobuf messages"),
    ],
)
def test_what_holds_no_record_is_one_clear_message(
    make: Any, says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "run.mcap"
    make(path)
    with pytest.raises(RecordingError, match=says):
        read_recording(path)
    assert main(["timeline", str(path), "-o", str(tmp_path / "x.html")]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"cosleec: {path}: ") and says in err and "hint:" in err
    assert "Traceback" not in err


def test_an_unknown_type_or_missing_definitions_are_named(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match="no definition of the ROS type robot_msgs/msg/Nope"):
        ros_types().schema("robot_msgs/msg/Nope")
    with pytest.raises(RecordingError, match=r"cannot find the definitions of cosleec_interfaces") as e:
        RosTypes(tmp_path)  # a directory without the .msg files
    assert "--record-format json" in e.value.hint
    with pytest.raises(RecordingError, match="no recording format 'bag'"):
        McapRecorder(tmp_path / "x.mcap", fmt="bag")
    assert not (tmp_path / "x.mcap").exists()  # refused before the file is made
