"""Tasks for the Manager-down test: R1's every variant asks before acting and reports the answer."""

from __future__ import annotations

from typing import Any

from cosleec.runtime import Task, hedge


class AskFirst(Task):
    rule = "R1"

    def _ask(self) -> None:
        self.event("OpenCurtains" if self.request("OpenCurtains") else "Refuse")

    def default(self, decision: Any) -> None:
        self._ask()

    @hedge(1)
    def one(self, decision: Any) -> None:
        self._ask()

    @hedge(2)
    def two(self, decision: Any) -> None:
        self._ask()


def install(node: Any) -> None:
    node.bind(AskFirst())
