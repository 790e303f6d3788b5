"""Checklist B: ``activating(layers, fn, *args)`` is ``with activate(*layers): fn(*args)``.

The runtime runs every decision's implementation through it; these hold it to the scope it
replaces: the same composition inside (whatever was active, globally or in an enclosing
scope), the same one after (also when ``fn`` raises), the same hooks, the same refusals.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.cop import (
    Layer,
    activate,
    activate_globally,
    activating,
    active_layers,
    deactivate,
    deactivate_globally,
)

LAYERS = [Layer(f"A{i}", priority=i % 2) for i in range(4)]
indices = st.lists(st.integers(0, 3), max_size=3)


def names() -> list[str]:
    return [la.name for la in active_layers()]


@given(outer=indices, masked=indices, globally=indices, inner=indices)
def test_inside_and_after_it_is_the_scope(
    outer: list[int], masked: list[int], globally: list[int], inner: list[int]
) -> None:
    layers = tuple(LAYERS[i] for i in inner)
    for i in globally:
        activate_globally(LAYERS[i])
    try:
        with activate(*(LAYERS[i] for i in outer)), deactivate(*(LAYERS[i] for i in masked)):
            with activate(*layers):
                want = names()
            before = names()
            assert activating(layers, names) == want
            assert names() == before
    finally:
        for i in globally:
            deactivate_globally(LAYERS[i])


def test_it_passes_the_arguments_and_returns_the_result() -> None:
    assert activating((LAYERS[0],), lambda a, b: (a, b, names()), 1, 2) == (1, 2, ["A0"])


def test_after_a_raise_the_layers_are_gone() -> None:
    def boom() -> None:
        assert names() == ["A1"]
        raise KeyError("x")

    with pytest.raises(KeyError):
        activating((LAYERS[1],), boom)
    assert names() == []


def test_hooks_fire_as_for_the_scope() -> None:
    la = Layer("Hooked")
    seen: list[str] = []
    la.on_enter(lambda layer: seen.append(f"enter {layer.name}"))
    la.on_exit(lambda layer: seen.append(f"exit {layer.name}"))
    activating((la,), lambda: seen.append("inside"))
    assert seen == ["enter Hooked", "inside", "exit Hooked"]


def test_something_that_is_no_layer_is_refused() -> None:
    with pytest.raises(TypeError, match="expected Layer objects"):
        activating(("A0",), names)  # type: ignore[arg-type]
