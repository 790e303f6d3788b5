"""A Manager's parts refer to each other without a reference cycle: a Manager dropped is freed
at once (its rules, records and files with it), not when the cyclic collector runs -- late,
and as a pause in someone's step (the p99 of scalability_grid saw it)."""

from __future__ import annotations

import gc
import weakref
from collections import deque
from collections.abc import Iterator
from pathlib import Path

import pytest

from cosleec import Manager, VirtualClock

RULES = "def_start event E event F def_end rule_start R1 when E then F within 5 seconds rule_end"


@pytest.fixture
def no_collector() -> Iterator[None]:
    gc.collect()
    gc.disable()
    try:
        yield
    finally:
        gc.enable()


@pytest.mark.parametrize("durable", ["none", "audit", "journal"])
def test_a_closed_manager_dropped_is_freed_without_the_cyclic_collector(
    tmp_path: Path, durable: str, no_collector: None
) -> None:
    kw: dict[str, object] = {}
    if durable in ("audit", "journal"):
        kw["audit"] = tmp_path / "a.jsonl"
    if durable == "journal":
        kw["journal"] = tmp_path / "state.db"
    m = Manager.from_text(RULES, clock=VirtualClock(), **kw)
    heard: deque[object] = deque(maxlen=10)
    m.subscribe(heard.append)
    m.capability("F")(lambda ob, d: None)
    m.start(timer=True)
    m.event("E")
    m.close()
    parts = [weakref.ref(x) for x in (m, m.core, m.core.steps, m.core.tracker, m.core.decider)]
    del m
    assert [r() is None for r in parts] == [True] * len(parts)


def test_a_hook_of_a_part_that_is_gone_says_so() -> None:
    from cosleec.runtime.steps import weakly

    class Part:
        def hook(self) -> int:
            return 1

    p = Part()
    call = weakly(p.hook)
    assert call() == 1
    del p
    with pytest.raises(ReferenceError, match=r"Part\.hook"):
        call()
