"""A job: a decision on its way to its implementation (now, or once what it requires is allowed)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from cosleec.cop import Snapshot
from cosleec.runtime.decision import Decision
from cosleec.runtime.implementations import Implementations
from cosleec.runtime.model import CompiledRule
from cosleec.runtime.obligations import Tracked


@dataclass(eq=False, slots=True)
class Job:
    """A decision to hand to its implementation once the step is over (or once allowed).

    ``composition`` is the rule's COP composition at the trigger (None: an ``otherwise``
    fallback); ``items`` what the decision put in force; ``record`` its decision record,
    annotated within the step when the dispatch differs from the decision;
    ``implementations`` those bound when it was decided (a reload since binds the new
    rules' own: a decision runs as it was decided, under the rule it was decided by).

    Each action (an obligation of ``items`` that requires an event) runs on its own: when
    some are forbidden for now, the others run and these wait. ``sent`` holds the ids of
    the actions already handed to the implementation; a *part* -- the job a dispatch runs
    -- shares it with the decision's job, and its ``items`` are the actions it runs (and
    the decision's prohibitions).
    """

    rule: CompiledRule
    decision: Decision
    composition: Snapshot | None
    items: list[Tracked]
    record: dict[str, Any] | None = None
    implementations: Implementations | None = None
    sent: set[int] = field(default_factory=set)

    @property
    def fallback(self) -> bool:
        """Is it an ``otherwise`` decision (no trigger, no composition)?"""
        return self.composition is None
