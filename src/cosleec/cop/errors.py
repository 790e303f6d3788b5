"""Errors of the COP runtime: constraints reject explicitly, they never heal silently (SD11).

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations


class COPError(Exception):
    """Base class of every error cosleec.cop raises."""


class DefinitionError(COPError):
    """A layered function, partial or group is defined inconsistently (SD12)."""


class ActivationError(COPError):
    """An activation or deactivation is not allowed (unbalanced, re-entered, vetoed)."""


class ExclusionError(ActivationError):
    """A second member of an exclusive group was activated in strict mode (SD6, SD11)."""


class HedgeEvaluationError(COPError):
    """A hedge predicate raised: the dispatch is aborted, no partial runs (SD14)."""

    def __init__(self, group: str, member: str, cause: BaseException) -> None:
        super().__init__(
            f"predicate of {member!r} in group {group!r} failed: {type(cause).__name__}: {cause}"
        )
        self.group = group
        self.member = member
