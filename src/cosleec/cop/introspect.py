"""Introspection (docs/reference/cop-runtime.md SD16): the composition, the chain a call would run, and why.

Imports ``layer.py``, ``state.py`` and ``dispatch.py``; runs nothing of the user's but predicates.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from cosleec.cop.dispatch import LayeredFunction, all_layered
from cosleec.cop.layer import Layer
from cosleec.cop.state import RT, active_layers, dyn_get


def current_layers(context: Any = None) -> tuple[Layer, ...]:
    """The explicit composition; with ``context``, plus the predicate layers that hold on it.

    Use it to show an operator what is active; ``active_layers()`` is the cheaper explicit-only form.
    """
    comp = active_layers()
    if context is None:
        return comp
    extra: list[Layer] = []
    for f in all_layered():
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


@dataclass(frozen=True, kw_only=True)
class Explanation:
    """The chain a call would run, outermost first, and each hedge group's selection (``explain``)."""

    function: str
    composition: tuple[str, ...]
    chain: tuple[str, ...]
    selected: dict[str, str | None]
    predicates: dict[str, dict[str, bool | None]]

    def __str__(self) -> str:
        sel = ", ".join(f"{g}: {m or 'default'}" for g, m in self.selected.items())
        return f"{self.function}: {' -> '.join([*self.chain, 'base'])}" + (f" [{sel}]" if sel else "")


def explain(fn: Any, *args: Any, context: Any = None) -> Explanation:
    """What calling ``fn(*args)`` would run here and now, without running it.

    Use it to answer "why did this variant run?": the chain, the selected hedge members
    and the predicate values, evaluated on ``context`` (default: the function's own).
    ``args`` never change the answer -- COP chooses by composition and context, never by
    argument values -- they are accepted so that the call reads like the call it explains.
    """
    lf = getattr(fn, "layered", fn)
    if not isinstance(lf, LayeredFunction):
        raise TypeError(f"{fn!r} is not a layered function")
    view = lf.view(RT.state, dyn_get())
    # the function's own context is read only if a hedge group needs it
    sel = lf.select(view, record=True) if context is None else lf.select(view, context=context, record=True)
    if sel.failure is not None:
        raise sel.failure
    assert sel.record is not None
    return Explanation(
        function=lf.name,
        composition=tuple(la.name for la in view.composition),
        chain=tuple(la.name for la in lf.layers_in_chain(view.explicit, sel.selected)),
        selected=sel.record.selected,
        predicates=sel.record.predicates,
    )
