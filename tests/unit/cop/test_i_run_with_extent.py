"""run_with: a captured composition, and what the code run under it activates itself (SD17, SD4)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from cosleec.cop import Layer, Snapshot, activate, active_layers, deactivate, run_with


def test_activations_inside_a_captured_composition_take_effect(layered: Callable[..., Any]) -> None:
    a, b = Layer("A"), Layer("B")

    @layered
    def f() -> str:
        return "base"

    @f.variant(b)
    def _(*, proceed: Any) -> str:
        return "B(" + proceed() + ")"

    def inner() -> tuple[list[str], str, list[str]]:
        with activate(b):
            inside = [la.name for la in active_layers()], f()
        return inside[0], inside[1], [la.name for la in active_layers()]

    names, result, after = run_with(Snapshot((a,)), inner)
    assert names == ["B", "A"]  # the newer activation is outermost, the captured layer kept
    assert result == "B(base)"
    assert after == ["A"]  # and the block's end restores the captured composition


def test_deactivation_inside_a_captured_composition_masks_it() -> None:
    a, b = Layer("A"), Layer("B")

    def inner() -> list[str]:
        with deactivate(a):
            return [la.name for la in active_layers()]

    assert run_with(Snapshot((a, b)), inner) == ["B"]


def test_a_chain_cache_needs_room_for_one_chain() -> None:
    import pytest

    from cosleec.cop import DefinitionError, layered

    with pytest.raises(DefinitionError, match="max_chains"):

        @layered(max_chains=0)
        def f() -> None: ...


def test_recurring_compositions_find_their_chain_without_a_rebuild(layered: Callable[..., Any]) -> None:
    layers = [Layer(f"L{i}") for i in range(4)]

    @layered
    def f() -> str:
        return "base"

    for la in layers:
        f.variant(la)(lambda *, proceed, name=la.name: name)
    snaps = [Snapshot((la,)) for la in layers]
    for _ in range(3):  # round robin: the one-slot memo always holds another composition
        assert [run_with(s, f) for s in snaps] == ["L0", "L1", "L2", "L3"]
    assert f.layered.builds == 4  # one chain per composition, built once
