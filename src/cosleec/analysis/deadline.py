"""The time a whole ``cosleec analyse`` run may take (``--deadline``), as opposed to
``--timeout``, which bounds one solver question.

A run asks many questions -- several per rule, per check -- and builds an encoding for
each, so a per-question limit alone leaves the run unbounded (issue 28: one rule with 5,000
``unless`` clauses ran for minutes under ``--timeout 5``). A :class:`Deadline` is made
once per run and shared by every file, check and encoding: each solver question gets at
most the time that is left, and building an encoding looks at the clock as it goes, so the
run ends within a moment of the deadline. What the deadline cuts short raises
:class:`OutOfTime`, which :func:`cosleec.analysis.run.analyse_spec` turns into a partial
report that names what was not decided. Reading and checking a file (:mod:`cosleec.lang`)
is not interrupted.
"""

from __future__ import annotations

import time
from dataclasses import dataclass


class OutOfTime(Exception):
    """The run's deadline passed: the question being asked, or built, is not decided."""


@dataclass(frozen=True)
class Deadline:
    """When the run must end, on the monotonic clock; make one with :meth:`after`."""

    at: float

    @classmethod
    def after(cls, seconds: float) -> Deadline:
        """The deadline ``seconds`` from now."""
        return cls(time.monotonic() + seconds)

    def left(self) -> float:
        """Seconds until the deadline (negative once it has passed)."""
        return self.at - time.monotonic()

    def passed(self) -> bool:
        """Whether the deadline has passed."""
        return time.monotonic() >= self.at

    def check(self) -> None:
        """Raise :class:`OutOfTime` once the deadline has passed."""
        if self.passed():
            raise OutOfTime


def question_ms(timeout_ms: int, deadline: Deadline | None) -> int:
    """The milliseconds one solver question may take: ``timeout_ms`` (0: no limit), or what
    is left of ``deadline`` if that is less (at least 1: z3 reads 0 as no limit)."""
    if deadline is None:
        return timeout_ms
    left = max(1, int(deadline.left() * 1000))
    return left if timeout_ms == 0 else min(timeout_ms, left)
