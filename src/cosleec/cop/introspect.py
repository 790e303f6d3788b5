"""Introspection (SD16): the composition, the chain a call would run, and why."""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

from cosleec.cop.dispatch import LayeredFunction
from cosleec.cop.layer import Layer, LayerGroup
from cosleec.cop.state import RT, _dyn, composition

_groups: weakref.WeakSet[LayerGroup] = weakref.WeakSet()


def current_layers(context: Any = None) -> tuple[Layer, ...]:
    """The explicit composition; with ``context``, plus the predicate layers that hold on it."""
    comp = composition(RT.state, _dyn.get())
    if context is None:
        return comp
    extra: list[Layer] = []
    for f in list(RT.functions):
        for g in f.groups:
            for m in g.members:
                if m in comp or m in extra or m.predicate is None:
                    continue
                try:
                    holds = bool(m.predicate(context))
                except Exception:  # a predicate written for another kind of context
                    holds = False
                if holds:
                    extra.append(m)
    return (*comp, *extra)


@dataclass(frozen=True)
class Explanation:
    """The chain a call would run, outermost first, and each hedge group's selection."""

    function: str
    composition: tuple[str, ...]
    chain: tuple[str, ...]
    selected: dict[str, str | None]
    predicates: dict[str, dict[str, bool | None]]

    def __str__(self) -> str:
        sel = ", ".join(f"{g}: {m or 'default'}" for g, m in self.selected.items())
        return f"{self.function}: {' -> '.join([*self.chain, 'base'])}" + (f" [{sel}]" if sel else "")


def explain(fn: Any, *args: Any, context: Any = None) -> Explanation:
    """What calling ``fn(*args)`` would run now, without running anything."""
    lf = getattr(fn, "layered", fn)
    if not isinstance(lf, LayeredFunction):
        raise TypeError(f"{fn!r} is not a layered function")
    comp = composition(RT.state, _dyn.get())
    selected: tuple[Layer | None, ...] = ()
    preds: dict[str, dict[str, bool | None]] = {}
    chosen: dict[str, str | None] = {}
    if lf.groups:
        ctx = context if context is not None else lf.snapshot()
        selected, record = lf.select(comp, ctx, (True,))
        assert record is not None
        preds, chosen = record.predicates, record.selected
    chain = tuple(la.name for la in lf.layers_in_chain(comp, selected))
    return Explanation(lf.name, tuple(la.name for la in comp), chain, chosen, preds)
