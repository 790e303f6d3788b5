"""Tasks for the stale-dispatch race: each clause's implementation reports its own event."""

from __future__ import annotations

from typing import Any

from cosleec.runtime import Task, hedge


class Judge(Task):
    rule = "R"

    def default(self, decision: Any) -> None:
        self.event("Same")

    @hedge(1)
    def a_bigger(self, decision: Any) -> None:
        self.event("ABigger")

    @hedge(2)
    def b_bigger(self, decision: Any) -> None:
        self.event("BBigger")


def install(node: Any) -> None:
    node.bind(Judge())
