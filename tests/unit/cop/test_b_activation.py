"""Checklist B: activation scope (tests that dispatch run on both dispatchers)."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import pytest

from cosleec.cop import (
    ActivationError,
    Layer,
    activate,
    activate_globally,
    active_layers,
    bind,
    deactivate,
    deactivate_globally,
    layered_generator,
    run_with,
    snapshot,
)

L1, L2, L3 = Layer("L1"), Layer("L2"), Layer("L3")
Layered = Callable[..., Any]


def names() -> list[str]:
    return [la.name for la in active_layers()]


@pytest.fixture
def trace(layered: Layered) -> Any:
    @layered
    def trace() -> str:
        return "base"

    for layer in (L1, L2, L3):

        def make(layer: Layer) -> None:
            @trace.variant(layer)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return f"{layer.name}({proceed()})"

        make(layer)
    return trace


def test_b12_nested_blocks_compose_and_restore_exactly(trace: Any) -> None:
    with activate(L1):
        with activate(L2):
            assert names() == ["L2", "L1"]
            assert trace() == "L2(L1(base))"
        assert names() == ["L1"]
    assert names() == []


def test_b13_reactivation_inside_deactivation_moves_the_layer_outermost() -> None:
    with activate(L1, L2, L3):
        assert names() == ["L3", "L2", "L1"]
        with deactivate(L2):
            assert names() == ["L3", "L1"]
            with activate(L2):
                assert names() == ["L2", "L3", "L1"]  # activation order l1, l3, l2


def test_b14_a_layer_active_through_several_routes_runs_once(trace: Any) -> None:
    activate_globally(L1)
    with activate(L1), activate(L1):
        assert trace() == "L1(base)"
    deactivate_globally(L1)


def test_b15_reactivation_keeps_the_position() -> None:
    with activate(L1, L2), activate(L1):
        assert names() == ["L2", "L1"]


def test_b16_exceptions_restore_the_composition_and_do_not_disturb_proceed(layered: Layered) -> None:
    with pytest.raises(RuntimeError), activate(L1):
        raise RuntimeError
    assert names() == []
    activate_globally(L2)
    with pytest.raises(RuntimeError), deactivate(L2):
        raise RuntimeError
    assert names() == ["L2"]
    deactivate_globally(L2)

    @layered
    def h() -> str:
        return "h"

    @h.variant(L1)
    def _h(*, proceed):  # type: ignore[no-untyped-def]
        raise ValueError("in h's partial")

    @layered
    def k() -> str:
        return "k-base"

    @k.variant(L1)
    def _k(*, proceed):  # type: ignore[no-untyped-def]
        with contextlib.suppress(ValueError):
            h()
        return proceed()

    with activate(L1):
        assert k() == "k-base"  # contextpy3 runs h's base here


def test_b17_an_activation_object_cannot_be_entered_twice_at_once() -> None:
    act = activate(L1)
    with act:
        with pytest.raises(ActivationError), act:
            pass
        assert names() == ["L1"]
    assert names() == []
    with act:  # reusable after a normal exit
        assert names() == ["L1"]
    assert names() == []


def test_b18_global_activation_and_scoped_masking(trace: Any) -> None:
    activate_globally(L1)
    seen: list[list[str]] = []
    t = threading.Thread(target=lambda: seen.append(names()))
    t.start()
    t.join()
    assert seen == [["L1"]]
    assert asyncio.run(_names_async()) == ["L1"]
    with deactivate(L1):
        assert names() == []
        assert trace() == "base"
    assert names() == ["L1"]
    deactivate_globally(L1)


async def _names_async() -> list[str]:
    return names()


def test_b19_global_activation_is_counted() -> None:
    activate_globally(L1)
    activate_globally(L1)
    deactivate_globally(L1)
    assert names() == ["L1"]
    deactivate_globally(L1)
    assert names() == []
    with pytest.raises(ActivationError):
        deactivate_globally(L1)


def test_b20_scoped_activation_is_invisible_to_other_threads() -> None:
    seen: list[list[str]] = []
    ready, done = threading.Event(), threading.Event()

    def other() -> None:
        ready.wait()
        seen.append(names())
        done.set()

    t = threading.Thread(target=other)
    t.start()
    with activate(L1):
        ready.set()
        done.wait()
    t.join()
    assert seen == [[]]


def test_b21_asyncio_tasks_executors_and_bind() -> None:
    async def main() -> None:
        gate = asyncio.Event()
        seen: dict[str, list[str]] = {}

        async def a() -> None:
            with activate(L1):
                await gate.wait()
                seen["a"] = names()

        async def b() -> None:
            seen["b"] = names()
            gate.set()

        await asyncio.gather(a(), b())
        assert seen == {"a": ["L1"], "b": []}

        with activate(L2):
            child = asyncio.create_task(_child_changes())
            with activate(L3):
                await child
            assert names() == ["L2"]
            assert await asyncio.to_thread(names) == ["L2"]
            loop = asyncio.get_running_loop()
            assert await loop.run_in_executor(None, names) == []
            assert await loop.run_in_executor(None, bind(names)) == ["L2"]

    asyncio.run(main())
    with ThreadPoolExecutor(1) as pool, activate(L1):
        assert pool.submit(names).result() == []
        assert pool.submit(bind(names)).result() == ["L1"]


async def _child_changes() -> None:
    assert names() == ["L2"]  # inherits what was current when it was created, not L3
    with activate(L1):
        assert names() == ["L1", "L2"]


def test_b22_layered_generators_do_not_leak() -> None:
    @layered_generator
    def gen():  # type: ignore[no-untyped-def]
        with activate(L1):
            yield names()
            yield names()

    g = gen()
    assert next(g) == ["L1"]
    assert names() == []  # suspended inside the block: nothing leaks to the consumer
    assert next(g) == ["L1"]
    t = threading.Thread(target=g.close)
    t.start()
    t.join()

    @layered_generator
    async def agen():  # type: ignore[no-untyped-def]
        with activate(L2):
            yield names()

    async def consume() -> None:
        ag = agen()
        assert await ag.__anext__() == ["L2"]
        assert names() == []
        await ag.aclose()

    asyncio.run(consume())


def test_b22_an_unfinished_layered_generator_dropped_by_its_consumer_leaks_nothing() -> None:
    @layered_generator
    def gen():  # type: ignore[no-untyped-def]
        with activate(L2):
            yield names()

    with activate(L1):
        g = gen()
        assert next(g) == ["L2", "L1"]
    del g  # closed while suspended inside its block, from the consumer's context
    gc.collect()
    assert names() == []


def test_b22_undecorated_generator_leaks_as_documented_but_never_raises() -> None:
    import contextvars

    def gen():  # type: ignore[no-untyped-def]
        with activate(L1):
            yield 1
            yield 2

    def scenario() -> None:
        g = gen()
        next(g)
        assert names() == ["L1"]  # the documented leak
        contextvars.copy_context().run(g.close)  # closing from another Context: no error

    contextvars.copy_context().run(scenario)
    assert names() == []


def test_b23_capture_and_replay(trace: Any) -> None:
    with activate(L1):
        snap = snapshot()
    with activate(L2):
        assert run_with(snap, names) == ["L1"]
        assert run_with(snap, trace) == "L1(base)"
