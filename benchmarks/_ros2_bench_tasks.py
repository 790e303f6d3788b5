"""The task node of the latency benchmark: perform Pong as soon as the obligation arrives."""

from typing import Any


def install(node: Any) -> None:
    @node.capability("Pong")
    def pong(ob: Any, decision: Any) -> None:
        node.event("Pong")
