"""Benchmark subjects: plain functions and their layered twins, on each dispatcher.

``DISPATCHERS`` maps a dispatcher name to its B-min and B-rule layered functions; every
one has a pass-through ``around`` partial on each of ``LAYERS``. ``RULES`` imitates the
SLEEC runtime: 60 rules, each a layered function with one variant per clause layer (an
exclusive group of two), dispatched under ``run_with(Snapshot(all active clause layers))``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from cosleec.cop import Layer, LayerGroup, layered

LAYERS = [Layer(f"L{i}") for i in range(10)]


@dataclass(frozen=True, slots=True)
class Obligation:
    event: str
    within_s: float | None
    negated: bool
    rule: str


def plain_min(x: int) -> int:
    return x + 1


def plain_rule(event: str) -> Obligation:
    return Obligation("OpenCurtains", 30.0, False, "R1")


def _twins(fast: bool) -> tuple[Any, Any]:
    @layered(fast=fast)
    def layered_min(x: int) -> int:
        return x + 1

    @layered(fast=fast)
    def layered_rule(event: str) -> Obligation:
        return Obligation("OpenCurtains", 30.0, False, "R1")

    for la in LAYERS:

        @layered_min.variant(la)
        def _pass_min(x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed()

        @layered_rule.variant(la)
        def _pass_rule(event, *, proceed):  # type: ignore[no-untyped-def]
            return proceed()

    return layered_min, layered_rule


DISPATCHERS = {"reference": _twins(False), "fast": _twins(True)}


def _rule(i: int, fast: bool) -> tuple[Any, list[Layer]]:
    clauses = [Layer(f"R{i}.{c}") for c in (1, 2)]
    LayerGroup(f"R{i}", clauses)

    @layered(fast=fast, method=False)
    def handle(event: str) -> Obligation:
        return Obligation("OpenCurtains", 30.0, False, f"R{i}")

    for la in clauses:

        @handle.variant(la)
        def _clause(event, *, proceed):  # type: ignore[no-untyped-def]
            return Obligation("RefuseRequest", 30.0, False, f"R{i}")

    return handle, clauses


RULES = {name: [_rule(i, name == "fast") for i in range(60)] for name in DISPATCHERS}
