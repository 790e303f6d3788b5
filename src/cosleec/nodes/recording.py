"""Record the decision stream to an MCAP file that Foxglove opens (JSON channels).

Each runtime event kind gets a channel ``/cosleec/<kind>`` with a JSON schema; a message is
the record as one object without the audit log's header (``{"kind", "time", **data}``:
:func:`cosleec.records.as_object`; kinds and fields as :mod:`cosleec.records` defines them),
its time the runtime's clock. Needs the ``mcap`` package (``pip install mcap``).

A recording survives a crash: records are written unchunked, straight to the file, and
the file is flushed at most once a second (by a background thread, so a quiet second is
flushed too). A killed process loses at most the last second of records, and the
summary and footer written by :meth:`McapRecorder.close`; :func:`read_recording` reads
such a file up to its last whole record.
"""

from __future__ import annotations

import json
import struct
import threading
import time
from pathlib import Path
from typing import Any, BinaryIO

from cosleec.records import Kind, as_object


class McapRecorder:
    """Writes runtime events to an MCAP file, one JSON channel per event kind.

    The Manager node makes one for ``--record FILE.mcap``, to replay a run in Foxglove
    afterwards. The file is created (or truncated) at once. Thread-safe: the runtime's
    timer thread and the transport's threads may write at the same time. What is written
    reaches the file within ``flush_every`` seconds (see the module's note on crashes).
    """

    def __init__(self, path: str | Path, namespace: str = "/cosleec", flush_every: float = 1.0) -> None:
        from mcap.writer import Writer

        self._fh: BinaryIO = Path(path).open("wb")  # noqa: SIM115 - open for the recorder's lifetime
        # unchunked: a chunk reaches the file only when full, so a crash would lose it all
        self._w = Writer(self._fh, use_chunking=False)
        self._w.start(profile="", library="cosleec")
        self._channels: dict[str, int] = {}
        self._ns = namespace.rstrip("/")
        self._seq = 0
        self._t0 = time.time_ns()
        self._lock = threading.Lock()  # one record at a time, and never during a flush
        self._dirty = False
        self._closed = threading.Event()
        self.flush_every = flush_every
        self._flusher = threading.Thread(target=self._flush_loop, name="cosleec-mcap-flush", daemon=True)
        self._flusher.start()

    def _channel(self, kind: str) -> int:
        ch = self._channels.get(kind)
        if ch is None:
            schema = self._w.register_schema(
                name=f"cosleec.{kind}",
                encoding="jsonschema",
                data=json.dumps({"type": "object", "title": f"cosleec {kind}"}).encode(),
            )
            ch = self._w.register_channel(
                topic=f"{self._ns}/{kind}", message_encoding="json", schema_id=schema
            )
            self._channels[kind] = ch
        return ch

    def write(self, kind: Kind | str, t: float, data: dict[str, Any]) -> None:
        """Append one runtime event of ``kind`` that happened at clock time ``t`` (seconds).

        A ``t`` below 1e9 (monotonic or virtual time) is stamped relative to the moment the
        recorder was created; a larger one is taken as Unix time. Ignored once closed.
        """
        stamp = self._t0 + int(t * 1e9) if t < 1e9 else int(t * 1e9)
        payload = json.dumps(as_object(kind, t, data), default=str).encode()
        with self._lock:
            if self._closed.is_set():
                return
            self._seq += 1
            self._w.add_message(
                channel_id=self._channel(kind),
                log_time=stamp,
                publish_time=stamp,
                sequence=self._seq,
                data=payload,
            )
            self._dirty = True

    def flush(self) -> None:
        """Hand what was written so far to the operating system (the background thread does it every second)."""
        with self._lock:
            if self._dirty and not self._closed.is_set():
                self._fh.flush()
                self._dirty = False

    def _flush_loop(self) -> None:
        while not self._closed.wait(self.flush_every):
            self.flush()

    def close(self) -> None:
        """Finish the MCAP file (summary and footer) and close it; later writes are ignored."""
        with self._lock:
            if self._closed.is_set():
                return
            self._closed.set()
            self._w.finish()  # type: ignore[no-untyped-call]
            self._fh.close()
        self._flusher.join(5)


def read_recording(path: str | Path) -> list[tuple[str, dict[str, Any]]]:
    """(topic, message) pairs of a recording, in the order they were written.

    A recording whose writer was killed (no summary, no footer, maybe a torn last record)
    is read up to its last whole record.
    """
    from mcap.exceptions import McapError
    from mcap.records import Channel, DataEnd, Message
    from mcap.stream_reader import StreamReader

    out = []
    topics: dict[int, str] = {}
    with Path(path).open("rb") as fh:
        try:
            for record in StreamReader(fh).records:
                if isinstance(record, Channel):
                    topics[record.id] = record.topic
                elif isinstance(record, Message):
                    out.append((topics[record.channel_id], json.loads(record.data)))
                elif isinstance(record, DataEnd):
                    break  # the summary repeats channels; no message follows
        except (McapError, struct.error, EOFError):  # the end of a recording cut short
            pass
    return out
