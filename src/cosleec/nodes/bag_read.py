"""Read a Manager node's recording back: its records, from either format, in the order written.

``json`` channels hold a record per message; ``cdr`` channels (a ``ros2`` recording) are
decoded with the types their own ``ros2msg`` schemas define -- not this version's -- so a
recording made by another cosleec version reads too, and the record comes from the
message's ``record`` or ``data`` field (:mod:`cosleec.nodes.bag_messages`). The file is
read as a stream, so a recording cut short by a crash reads up to its last whole record
(``json``) or chunk (``ros2``).
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

from cosleec.nodes.bag_messages import record_of
from cosleec.nodes.bag_types import RecordingError

MAGIC = b"\x89MCAP0\r\n"
"""The first bytes of every MCAP file."""

_NOT_OURS = (
    "cosleec timeline reads a Manager node's --record FILE.mcap; a robot's own bag is judged with a mapping"
)


class _Decoders:
    """One CDR decoder per schema of the file, made from the schema's own definitions."""

    def __init__(self) -> None:
        self.schemas: dict[int, Any] = {}
        self._stores: dict[int, Any] = {}

    def decode(self, channel: Any, data: bytes) -> dict[str, Any] | None:
        """The record of one CDR message on ``channel``; RecordingError if its type cannot be read."""
        schema = self.schemas.get(channel.schema_id)
        if schema is None or schema.encoding != "ros2msg":
            raise RecordingError(
                f"channel {channel.topic} has no ros2msg schema: its messages cannot be decoded",
                hint=_NOT_OURS,
            )
        store = self._stores.get(schema.id)
        if store is None:
            store = self._stores[schema.id] = _store(
                schema.name, schema.data.decode("utf-8", "replace"), channel.topic
            )
        try:
            message = store.deserialize_cdr(data, schema.name)
        except Exception as e:  # a torn or foreign message: say which
            raise RecordingError(
                f"a message on {channel.topic} is not a valid {schema.name}: {type(e).__name__}: {e}",
                hint=_NOT_OURS,
            ) from None
        return record_of(message)


def _store(name: str, text: str, topic: str) -> Any:
    """A ``rosbags`` type store that knows ``name`` from its ``ros2msg`` schema ``text``."""
    try:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
        from rosbags.typesys.base import TypesysError
    except ModuleNotFoundError as e:
        raise RecordingError(
            f"reading a ROS 2 recording needs the `rosbags` package ({e.name} is missing)",
            hint="pip install 'cosleec[record]'",
        ) from None
    store = get_typestore(Stores.EMPTY)
    try:
        store.register(get_types_from_msg(text, name))
    except (TypesysError, ValueError, KeyError) as e:
        raise RecordingError(f"the schema of {topic} ({name}) cannot be read: {e}", hint=_NOT_OURS) from None
    if name not in store.types:
        raise RecordingError(f"the schema of {topic} does not define its type {name}", hint=_NOT_OURS)
    return store


def read_messages(path: Path) -> list[tuple[str, dict[str, Any]]]:
    """(topic, record) pairs of the recording at ``path`` (:func:`cosleec.nodes.read_recording`)."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, DataEnd, Message, Schema
    from mcap.stream_reader import StreamReader

    out: list[tuple[str, dict[str, Any]]] = []
    channels: dict[int, Any] = {}
    decoders = _Decoders()
    with path.open("rb") as fh:
        head = fh.read(len(MAGIC))
        if len(head) < len(MAGIC) and MAGIC.startswith(head):
            return out  # a recording just created: its writer has not written its header yet
        if head != MAGIC:
            raise RecordingError(
                "the recording holds no runtime record: it is not an MCAP file "
                "(it does not start with MCAP's magic bytes)",
                where=str(path),
                hint="give the file of a Manager node's --record FILE.mcap",
            )
        fh.seek(0)
        try:
            for record in StreamReader(fh).records:
                if isinstance(record, Schema):
                    decoders.schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Message):
                    _add(out, channels[record.channel_id], record.data, decoders)
                elif isinstance(record, DataEnd):
                    break  # the summary repeats schemas and channels; no message follows
        except (McapError, struct.error, EOFError):  # the end of a recording cut short
            pass
    return out


def _add(out: list[tuple[str, dict[str, Any]]], channel: Any, data: bytes, decoders: _Decoders) -> None:
    """Append the record of one message on ``channel``; RecordingError for a message that holds none."""
    if channel.message_encoding == "json":
        try:
            parsed = json.loads(data)
        except ValueError:
            return  # a torn last message of a JSON recording: skipped as before
        if isinstance(parsed, dict):
            out.append((channel.topic, parsed))
        return
    if channel.message_encoding != "cdr":
        raise RecordingError(
            f"channel {channel.topic} holds {channel.message_encoding or 'unencoded'} messages, "
            "which a Manager node never records",
            hint=_NOT_OURS,
        )
    rec = decoders.decode(channel, data)
    if rec is None:
        schema = decoders.schemas.get(channel.schema_id)
        raise RecordingError(
            f"channel {channel.topic} holds {schema.name if schema else 'a type'} messages, which carry "
            "no cosleec record (no `record` or `data` field holding one)",
            hint=_NOT_OURS,
        )
    out.append((channel.topic, rec))
