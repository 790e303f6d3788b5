"""Record the decision stream to an MCAP file that Foxglove opens (JSON channels).

Each runtime event kind gets a channel ``/cosleec/<kind>`` with a JSON schema; the message
time is the runtime's clock. Needs the ``mcap`` package (``pip install mcap``).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, BinaryIO

KINDS = ("context", "layers", "decision", "obligation", "refused", "rejected", "task-failed")


class McapRecorder:
    """Writes runtime events to an MCAP file, one JSON channel per event kind.

    The Manager node makes one for ``--record FILE.mcap``, to replay a run in Foxglove
    afterwards. The file is created (or truncated) at once. Writes are not synchronised:
    calls must not overlap.
    """

    def __init__(self, path: str | Path, namespace: str = "/cosleec") -> None:
        from mcap.writer import Writer

        self._fh: BinaryIO = Path(path).open("wb")  # noqa: SIM115 - open for the recorder's lifetime
        self._w = Writer(self._fh)
        self._w.start(profile="", library="cosleec")
        self._channels: dict[str, int] = {}
        self._ns = namespace.rstrip("/")
        self._seq = 0
        self._t0 = time.time_ns()

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

    def write(self, kind: str, t: float, data: dict[str, Any]) -> None:
        """Append one runtime event of ``kind`` that happened at clock time ``t`` (seconds).

        A ``t`` below 1e9 (monotonic or virtual time) is stamped relative to the moment the
        recorder was created; a larger one is taken as Unix time.
        """
        stamp = self._t0 + int(t * 1e9) if t < 1e9 else int(t * 1e9)
        self._seq += 1
        self._w.add_message(
            channel_id=self._channel(kind),
            log_time=stamp,
            publish_time=stamp,
            sequence=self._seq,
            data=json.dumps({"kind": kind, "time": t, **data}, default=str).encode(),
        )

    def close(self) -> None:
        """Finish the MCAP file and close it; a recording never closed lacks its summary and footer."""
        self._w.finish()  # type: ignore[no-untyped-call]
        self._fh.close()


def read_recording(path: str | Path) -> list[tuple[str, dict[str, Any]]]:
    """(topic, message) pairs of a recording, in order."""
    from mcap.reader import make_reader

    out = []
    with Path(path).open("rb") as fh:
        for _schema, channel, message in make_reader(fh).iter_messages():
            out.append((channel.topic, json.loads(message.data)))
    return out
