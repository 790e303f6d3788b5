"""Event-triggered switching (SD10): a declarative transition table over global layers.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from cosleec.cop.layer import Layer
from cosleec.cop.state import swap_globally


@dataclass(frozen=True, kw_only=True)
class Transition:
    """One row of a :class:`Transitions` table: on ``event``, if ``when`` holds, swap these layers."""

    event: str
    activate: tuple[Layer, ...]
    deactivate: tuple[Layer, ...]
    when: Callable[[Any], bool] | None = None


class Transitions:
    """A declarative transition table for event-delimited layers (SD10): use it when modes
    switch on events rather than around a block of code.

    ``on(event, when=..., activate=[...], deactivate=[...])``, applied by ``fire(event)``.

    Each fired event is one atomic swap of the global composition: a concurrent reader sees
    the configuration before or after, never in between (F41).
    """

    def __init__(self) -> None:
        self._table: dict[str, list[Transition]] = {}

    def on(
        self,
        event: str,
        *,
        when: Callable[[Any], bool] | None = None,
        activate: Iterable[Layer] = (),
        deactivate: Iterable[Layer] = (),
    ) -> Transition:
        """Add a row: when ``event`` fires and ``when(context)`` holds (or no guard), activate
        ``activate`` and deactivate ``deactivate`` globally, in one swap with the other rows."""
        t = Transition(event=event, activate=tuple(activate), deactivate=tuple(deactivate), when=when)
        self._table.setdefault(event, []).append(t)
        return t

    def fire(self, event: str, context: Any = None) -> bool:
        """Apply the transitions of ``event`` whose guards hold; True if any applied."""
        on: list[Layer] = []
        off: list[Layer] = []
        for t in self._table.get(event, ()):
            if t.when is None or t.when(context):
                on.extend(t.activate)
                off.extend(t.deactivate)
        if not on and not off:
            return False
        swap_globally(on, off)
        return True
