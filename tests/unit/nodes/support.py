"""Helpers of the node tests: read what nodes publish on a bus, as their handlers see it."""

from __future__ import annotations

import json
from typing import Any

from cosleec.nodes import LocalBus


def unnumbered(message: dict[str, Any]) -> dict[str, Any]:
    """A message without the sender's numbering (``_from``, ``_n``), as handlers see it."""
    return {k: v for k, v in message.items() if k not in ("_from", "_n")}


def collect(bus: LocalBus, topic: str) -> list[dict[str, Any]]:
    """Every message published on ``topic`` from now on, unnumbered (a live list)."""
    out: list[dict[str, Any]] = []
    bus.transport().subscribe(topic, lambda p: out.append(unnumbered(json.loads(p))))
    return out
