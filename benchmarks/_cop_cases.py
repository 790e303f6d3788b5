"""Benchmark subjects: plain functions and their layered twins (defined in a file, so the
compiled dispatch prologue applies, as it does for user code)."""

from __future__ import annotations

from dataclasses import dataclass

from cosleec.cop import Layer, layered

LAYERS = [Layer(f"L{i}") for i in range(10)]


@dataclass(frozen=True, slots=True)
class Obligation:
    event: str
    within_s: float | None
    negated: bool
    rule: str


def plain_min(x: int) -> int:
    return x + 1


@layered
def layered_min(x: int) -> int:
    return x + 1


def plain_rule(event: str) -> Obligation:
    return Obligation("OpenCurtains", 30.0, False, "R1")


@layered
def layered_rule(event: str) -> Obligation:
    return Obligation("OpenCurtains", 30.0, False, "R1")


for _la in LAYERS:

    @layered_min.variant(_la)
    def _pass_min(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed()

    @layered_rule.variant(_la)
    def _pass_rule(event, *, proceed):  # type: ignore[no-untyped-def]
        return proceed()
