"""The scenario player: one list of steps drives the embedded runtime and a system over ROS.

A step is ``(kind, argument, note)``; what each kind does (set measures, send an event,
advance the clock, ...) is given by whoever plays it, so the same scenario serves the
demo, the embedded tests and the end-to-end ROS tests.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError

Step = tuple[str, Any, str]


def play(
    steps: list[Step],
    actions: dict[str, Callable[[Any], object]],
    now: Callable[[], float],
    on_step: Callable[[float, Step], None] | None = None,
) -> None:
    """Run ``steps`` through ``actions`` (kind -> what to do with the argument)."""
    for step in steps:
        kind, arg, _note = step
        if on_step is not None:
            on_step(now(), step)
        action = actions.get(kind)
        if action is None:
            raise UserError(
                f"unknown scenario step {kind!r}",
                hint=f"the steps this player knows: {', '.join(sorted(actions))}",
            )
        action(arg)


__all__ = ["Step", "play"]
