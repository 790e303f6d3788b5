"""Record the decision stream to an MCAP file that ROS tools read: a rosbag2 recording.

Each runtime event kind gets a channel ``/cosleec/<kind>``; a message is one record
(``{"kind", "time", **data}``: :func:`cosleec.records.as_object`; kinds and fields as
:mod:`cosleec.records` defines them), its time the runtime's clock. Two formats:

- ``ros2`` (the default): what ``ros2 bag record`` writes to MCAP -- profile ``ros2``, CDR
  messages of ``cosleec_interfaces`` types (or ``std_msgs/String``, :mod:`cosleec.nodes.bag_messages`),
  ``ros2msg`` schemas holding the full definitions (:mod:`cosleec.nodes.bag_types`),
  chunks with message indexes, summary, statistics and a ``rosbag2`` metadata record with
  ``ROS_DISTRO``. rosbags, ``ros2 bag``, mcap-ros2-support, Foxglove and PlotJuggler open it.
  Serialised in pure Python (``rosbags``), so the same bytes come from every middleware.
- ``json``: the earlier form, kept for tools that want JSON: ``json`` channels with a stub
  JSON schema, unchunked, no profile.

Needs ``pip install 'cosleec[record]'`` (``mcap``, ``rosbags``).

A recording survives a crash: at most once a second (a background thread, so a quiet second
is flushed too) what was written is handed to the operating system -- in ``ros2`` the chunk
in progress is closed and written with its index. A killed process loses at most the last
second of records and the summary written by :meth:`McapRecorder.close`;
:func:`read_recording` reads such a file up to its last whole record (or chunk).
"""

from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path
from typing import Any, BinaryIO

from cosleec.nodes.bag_messages import encode, type_of
from cosleec.nodes.bag_types import RecordingError, ros_types
from cosleec.records import Kind, as_object

FORMATS = ("ros2", "json")
"""What ``--record-format`` takes: a rosbag2 MCAP (the default) or the JSON copy."""


class McapRecorder:
    """Writes runtime events to an MCAP file, one channel per event kind.

    The Manager node makes one for ``--record FILE.mcap``, to open a run in Foxglove, rosbags
    or ``ros2 bag`` afterwards. ``fmt`` is ``ros2`` (None: the default) or ``json`` (module
    docstring). The file is created (or
    truncated) at once; a ``ros2`` recorder first checks that it can write the types
    (:class:`RecordingError` if not). Thread-safe: the runtime's timer thread and the
    transport's threads may write at the same time. What is written reaches the file within
    ``flush_every`` seconds.
    """

    #: what ``fmt`` takes (:data:`FORMATS`), for the command line's ``--record-format``
    FORMATS = FORMATS

    def __init__(
        self,
        path: str | Path,
        namespace: str = "/cosleec",
        flush_every: float = 1.0,
        fmt: str | None = None,
    ) -> None:
        from mcap.writer import CompressionType, Writer

        self.format = fmt or FORMATS[0]
        if self.format not in FORMATS:
            raise RecordingError(
                f"no recording format {self.format!r}", hint=f"choose one of {', '.join(FORMATS)}"
            )
        self._types = ros_types() if self.format == "ros2" else None  # RecordingError before the file is made
        self._fh: BinaryIO = Path(path).open("wb")  # noqa: SIM115 - open for the recorder's lifetime
        ros2 = self._types is not None
        # ros2: chunks, closed each second (flush); no compression, so every reader opens them
        self._w = Writer(self._fh, use_chunking=ros2, compression=CompressionType.NONE)
        self._w.start(profile="ros2" if ros2 else "", library="cosleec")
        self._fh.flush()  # the header is on disk at once: the file is an MCAP file from the start
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        self._ns = namespace.rstrip("/")
        self._seq = 0
        self._t0 = time.time_ns()
        self._lock = threading.Lock()  # one record at a time, and never during a flush
        self._dirty = False
        self._closed = threading.Event()
        self.flush_every = flush_every
        self._flusher = threading.Thread(target=self._flush_loop, name="cosleec-mcap-flush", daemon=True)
        self._flusher.start()

    def _schema(self, typename: str) -> int:
        """The schema id of ``typename`` (ros2), registered on first use."""
        sid = self._schemas.get(typename)
        if sid is None:
            assert self._types is not None
            sid = self._w.register_schema(
                name=typename, encoding="ros2msg", data=self._types.schema(typename)
            )
            self._schemas[typename] = sid
        return sid

    def _channel(self, kind: str) -> int:
        ch = self._channels.get(kind)
        if ch is None:
            topic = f"{self._ns}/{kind}"
            if self._types is not None:
                ch = self._w.register_channel(
                    topic=topic,
                    message_encoding="cdr",
                    schema_id=self._schema(type_of(kind)),
                    metadata={"offered_qos_profiles": ""},  # as rosbag2: recorded, not subscribed
                )
            else:
                schema = self._w.register_schema(
                    name=f"cosleec.{kind}",
                    encoding="jsonschema",
                    data=json.dumps({"type": "object", "title": f"cosleec {kind}"}).encode(),
                )
                ch = self._w.register_channel(topic=topic, message_encoding="json", schema_id=schema)
            self._channels[kind] = ch
        return ch

    def _payload(self, kind: str, stamp: int, record: dict[str, Any]) -> bytes:
        if self._types is None:
            return json.dumps(record, default=str).encode()
        typename, message = encode(self._types, kind, stamp, record)
        return self._types.serialize(message, typename)

    def write(self, kind: Kind | str, t: float, data: dict[str, Any]) -> None:
        """Append one runtime event of ``kind`` that happened at clock time ``t`` (seconds).

        A ``t`` below 1e9 (monotonic or virtual time) is stamped relative to the moment the
        recorder was created; a larger one is taken as Unix time. Ignored once closed.
        """
        stamp = self._t0 + int(t * 1e9) if t < 1e9 else int(t * 1e9)
        payload = self._payload(str(kind), stamp, as_object(kind, t, data))
        with self._lock:
            if self._closed.is_set():
                return
            self._seq += 1
            self._w.add_message(
                channel_id=self._channel(str(kind)),
                log_time=stamp,
                publish_time=stamp,
                sequence=self._seq,
                data=payload,
            )
            self._dirty = True

    def flush(self) -> None:
        """Hand what was written so far to the operating system (the background thread does it
        every second); in ``ros2`` the chunk in progress is closed and written, indexed."""
        with self._lock:
            if self._dirty and not self._closed.is_set():
                if self._types is not None:
                    self._w.flush()  # type: ignore[no-untyped-call]
                self._fh.flush()
                self._dirty = False

    def _flush_loop(self) -> None:
        while not self._closed.wait(self.flush_every):
            self.flush()

    def close(self) -> None:
        """Finish the MCAP file (metadata, summary and footer) and close it; later writes are ignored."""
        with self._lock:
            if self._closed.is_set():
                return
            self._closed.set()
            if self._types is not None:
                self._w.add_metadata("rosbag2", {"ROS_DISTRO": os.environ.get("ROS_DISTRO") or "jazzy"})
            self._w.finish()  # type: ignore[no-untyped-call]
            self._fh.close()
        self._flusher.join(5)


def read_recording(path: str | Path) -> list[tuple[str, dict[str, Any]]]:
    """(topic, record) pairs of a recording of either format, in the order they were written.

    A recording whose writer was killed (no summary, no footer, maybe a torn last record) is
    read up to its last whole record. :class:`RecordingError` for a file that is not MCAP or
    a channel whose messages hold no runtime record (another program's type).
    """
    from cosleec.nodes.bag_read import read_messages

    return read_messages(Path(path))
