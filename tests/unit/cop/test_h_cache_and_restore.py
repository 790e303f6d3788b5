"""Checklist H48 and beyond: a chain depends only on the layers that have partials for its
function, and the global configuration can be saved and restored. Dispatching tests run on
both dispatchers.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from typing import Any

import pytest

from cosleec.cop import (
    DispatchRecord,
    HedgeGroup,
    Layer,
    LayerGroup,
    Snapshot,
    activate,
    activate_globally,
    active_layers,
    add_activation_hook,
    deactivate_globally,
    global_count,
    global_state,
    on_dispatch,
    restore_globally,
    run_with,
    using_context,
)
from cosleec.testing import isolated_cop

Layered = Callable[..., Any]


def rule_function(layered: Layered, name: str, clauses: int) -> tuple[Any, list[Layer]]:
    """One rule as the SLEEC runtime builds it: an exclusive group of clause layers, one variant each."""
    layers = [Layer(f"{name}.{i + 1}") for i in range(clauses)]
    LayerGroup(name, layers)

    @layered(method=False)
    def handle(decision: int) -> str:
        return f"{name}:default"

    for la in layers:

        def mk(la: Layer) -> None:
            @handle.variant(la)
            def _(decision, *, proceed):  # type: ignore[no-untyped-def]
                return la.name

        mk(la)
    return handle, layers


def test_unrelated_layers_in_the_composition_never_rebuild_a_chain(layered: Layered) -> None:
    rules = [rule_function(layered, f"R{i}", 2) for i in range(60)]
    (mine, my_layers), others = rules[0], rules[1:]
    rng = random.Random(7)
    lf = mine.layered
    for clause in (1, 2, 1, 2):  # warm: one chain per clause
        comp = (my_layers[clause - 1], *(rng.choice(ls) for _, ls in others))
        assert run_with(Snapshot(comp), mine, 0) == f"R0.{clause}"
    builds = lf.builds
    for _ in range(500):  # the other rules' clauses come and go, in a fresh composition each time
        others_active = tuple(rng.choice(ls) for _, ls in others if rng.random() < 0.5)
        clause = rng.choice((1, 2))
        snap = Snapshot((*others_active[:10], my_layers[clause - 1], *others_active[10:]))
        assert run_with(snap, mine, 0) == f"R0.{clause}"
        assert run_with(Snapshot(others_active), mine, 0) == "R0:default"
    assert lf.builds == builds + 1  # only the default chain was new
    assert len(lf.cache) == 3


def test_a_small_cache_is_not_thrashed_by_unrelated_global_changes(layered: Layered) -> None:
    mine = Layer("mine")
    unrelated = [Layer(f"U{i}") for i in range(40)]

    @layered(max_chains=2)
    def f(x: int) -> int:
        return x

    @f.variant(mine)
    def _(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed() + 1

    with activate(mine):
        assert f(1) == 2
        for la in unrelated:
            activate_globally(la)
            assert f(1) == 2
        for la in unrelated:
            deactivate_globally(la)
            assert f(1) == 2
    assert f(1) == 1
    assert f.layered.builds == 2 and len(f.layered.cache) == 2


def test_a_hedge_function_keys_its_chains_by_the_selected_member(layered: Layered) -> None:
    a, b = Layer("a", when=lambda c: c == "a"), Layer("b", when=lambda c: c == "b")
    noise = [Layer(f"N{i}") for i in range(20)]

    @layered(hedges=HedgeGroup("h", [a, b]))
    def r() -> str:
        return "default"

    @r.variant(a)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return "a"

    for i, la in enumerate(noise):
        with activate(la), using_context("ab"[i % 2]):
            assert r() == ("a" if i % 2 == 0 else "default")  # b has no partial here
        with using_context(None):
            assert r() == "default"
    assert r.layered.builds == 2  # the chain through a, and the base alone (b's and the default's)
    assert len(r.layered.cache) == 2


def test_restore_globally_returns_to_a_saved_configuration(layered: Layered) -> None:
    a, b = Layer("a"), Layer("b")
    log: list[str] = []
    b.on_enter(lambda la: log.append("enter b"))
    b.on_exit(lambda la: log.append("exit b"))
    activate_globally(a)
    saved = global_state()
    activate_globally(a)
    activate_globally(b)
    records: list[DispatchRecord] = []
    on_dispatch(records.append)
    add_activation_hook(lambda la, how: log.append("hook " + la.name))

    @layered
    def f() -> str:
        return "f"

    f()
    assert records
    restore_globally(saved)
    assert (global_count(a), global_count(b)) == (1, 0)
    assert log == ["enter b", "exit b"]  # b's hooks saw it go; the activation hook is gone
    with activate(b):
        pass
    assert log == ["enter b", "exit b", "enter b", "exit b"]
    n = len(records)
    f()
    assert len(records) == n  # the dispatch hook is gone too
    deactivate_globally(a)


def test_restore_globally_inside_a_dispatch_waits_for_its_end(layered: Layered) -> None:
    a = Layer("a")
    saved = global_state()
    seen: list[tuple[str, ...]] = []

    @layered
    def step() -> None:
        activate_globally(a)
        restore_globally(saved)
        activate_globally(a)
        seen.append(tuple(la.name for la in active_layers()))

    step()
    assert seen == [()]  # nothing applied during the step
    assert global_count(a) == 1  # then, in order: on, back to saved, on
    deactivate_globally(a)


def test_isolated_cop_undoes_what_the_block_did() -> None:
    a = Layer("a")
    with isolated_cop():
        activate_globally(a)
        activate_globally(a)
        assert global_count(a) == 2
    assert global_count(a) == 0
    with pytest.raises(RuntimeError), isolated_cop():
        activate_globally(a)
        raise RuntimeError
    assert global_count(a) == 0


def test_equal_snapshots_share_a_frame_and_a_layer_listed_twice_runs_once(layered: Layered) -> None:
    a, b = Layer("a"), Layer("b")

    @layered
    def f() -> str:
        return "base"

    for la in (a, b):

        def mk(la: Layer) -> None:
            @f.variant(la)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return la.name + "(" + proceed() + ")"

        mk(la)
    assert Snapshot((a, b)).frame is Snapshot((a, b)).frame  # a memo recognises a rebuilt snapshot
    assert run_with(Snapshot((a, b)), f) == "a(b(base))"
    assert run_with(Snapshot((b, a)), f) == "b(a(base))"
    assert run_with(Snapshot((a, b, a)), f) == "a(b(base))"
    assert run_with(Snapshot(()), f) == "base"
    builds = f.layered.builds
    for _ in range(10):
        assert run_with(Snapshot((a, b)), f) == "a(b(base))"
    assert f.layered.builds == builds
