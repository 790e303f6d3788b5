"""Implementations.capability_under: one required event's capability, as capabilities_under runs it.

The plans run a decision that requires one plain event through ``capability_under``; the
general path runs every decision through ``capabilities_under`` (``dispatch``). For each
kind of capability -- one that returns, one that raises, none registered -- and a layer
activation that fails, the two must give the same outcomes, count the same failures, log
the same way and run the capability with the same layers active.
"""

from __future__ import annotations

import logging
from typing import Any

import pytest

from cosleec.cop import active_layers
from cosleec.lang import HedgeSemantics
from cosleec.runtime.decision import Decision
from cosleec.runtime.implementations import Implementations, Ran
from cosleec.runtime.model import Obligation

from .build import ruleset

RULES = "R1 when E then Rec within 5 seconds unless {a} then Help within 2 seconds"


def run(
    kind: str, one: bool, caplog: pytest.LogCaptureFixture
) -> tuple[list[Ran], int, list[str], list[str]]:
    rs = ruleset(RULES)
    impl = Implementations(rs)
    rule = rs.rules[0]
    ob = Obligation(event="Help", within_s=2.0, rule="R1")
    d = Decision.made(
        id=1,
        time=0.0,
        event="E",
        rule="R1",
        clause=1,
        layer="R1.1",
        semantics=HedgeSemantics.LAST_WINS,
        values={},
        conditions=(),
        obligations=(ob,),
    )
    inside: list[str] = []
    if kind != "none":

        @impl.capability("Help")
        def help_(o: Obligation, dd: Decision) -> None:
            inside.extend(la.name for la in active_layers())
            if kind == "raises":
                raise ValueError("no gripper")

    layers: tuple[Any, ...] = rule.compositions[1].layers if kind != "bad-layer" else ("R1.1",)
    caplog.clear()
    with caplog.at_level(logging.ERROR, logger="cosleec.runtime"):
        ran = impl.capability_under(layers, rule, d, ob) if one else impl.capabilities_under(layers, rule, d)
    return ran, impl.failures, inside, [r.getMessage() for r in caplog.records]


@pytest.mark.parametrize("kind", ["returns", "raises", "none", "bad-layer"])
def test_one_capability_runs_as_the_general_dispatch_runs_it(
    kind: str, caplog: pytest.LogCaptureFixture
) -> None:
    one = run(kind, True, caplog)
    every = run(kind, False, caplog)
    assert one == every
    ran, failures, inside, logged = one
    assert failures == (kind in ("raises", "bad-layer")) and len(ran) == 1
    if kind == "returns":
        assert ran == [Ran("capability", "Help")] and inside == ["R1.1"] and logged == []
    if kind == "raises":
        assert ran[0].error == "ValueError: no gripper" and "capability Help failed" in logged[0]
    if kind == "none":
        assert ran == [Ran("task", None)]
    if kind == "bad-layer":
        assert ran[0].what == "task" and "expected Layer" in (ran[0].error or "")
