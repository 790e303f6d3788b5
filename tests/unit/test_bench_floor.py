"""The benchmarks' floor (benchmarks/_floor.py) keeps the records the Manager keeps.

``dispatch_path`` and ``scalability_grid`` measure the runtime against this floor, "the same
records kept as fast as CPython allows". If the runtime's records change and the floor does
not, the figure measures something else; so the floor's decisions, obligations, layer
switches and counts are held here to the Manager's own, on grid rule sets and random
updates and triggers (time, ids and context versions aside: the floor keeps its own).
"""

from __future__ import annotations

import dataclasses
import random
import sys
from typing import Any

import pytest

from cosleec.runtime import Manager, VirtualClock
from tests.conftest import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
from _floor import Floor
from _rulesets import grid_rules

OWN = ("id", "decision_id", "instance", "seq", "context_version")  # numbered by each on its own


def record(d: Any) -> dict[str, Any]:
    out = {k: v for k, v in d.to_json().items() if k not in OWN}
    out["values"], out["conditions"] = d.values, d.conditions
    return out


def tracked(t: Any) -> dict[str, Any]:
    return {f.name: getattr(t, f.name) for f in dataclasses.fields(t) if f.name not in OWN}


@pytest.mark.parametrize("rules, clauses, seed", [(6, 3, 0), (10, 5, 1), (3, 20, 2)])
def test_the_floor_decides_and_keeps_what_the_manager_does(rules: int, clauses: int, seed: int) -> None:
    rng = random.Random(seed)
    clock = VirtualClock()
    m = Manager.from_text(grid_rules(rules, clauses), clock=clock, history=64)
    calls: list[tuple[str, str, str | None]] = []
    caps = {e: (lambda ob, d, e=e: calls.append((e, d.rule, d.layer))) for e in ("Act", "Alt")}
    for e, cap in caps.items():
        m.capability(e)(cap)
    m.start()
    names = [f"c{i}_{j}" for i in range(rules) for j in range(clauses)]
    m.update(dict.fromkeys(names, False))
    mine = Floor(m, caps, own_context=True)
    for _ in range(300):
        if rng.random() < 0.5:
            i = rng.randrange(rules)
            flip = {f"c{i}_{j}": rng.random() < 0.3 for j in range(clauses)}
            assert [tuple(s) for s in m.update(flip)] == mine.update(flip)
        else:
            event = f"E{rng.randrange(rules)}"
            before = len(calls)
            (decision,) = m.event(event)
            mine.trigger(event)
            assert record(mine.decisions[-1]) == record(decision)
            assert calls[before] == calls[before + 1]  # the same capability, rule and layer
            if rng.random() < 0.5:
                clock.advance(rng.choice([0.5, 2.0, 30.0]))  # deadlines pass (the floor judges them)
    assert [tracked(t) for t in mine.active.values()] == [tracked(t) for t in m.outstanding()]
    assert {k: mine.stats[k] for k in ("events", "decisions", "violations")} == {
        k: m.stats[k] for k in ("events", "decisions", "violations")
    }
    m.close()
