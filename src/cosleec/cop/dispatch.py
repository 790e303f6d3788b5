"""Layered functions and the reference dispatcher (docs/reference/cop-runtime.md §4, "Dispatch, step by step").

One dispatch:

1. **snapshot** the configuration: the global state and the dynamic frame, read once;
   what they mean for this function (its *view*: the explicit layers that have partials
   for it, and the hedge members forced by explicit activation) is remembered for the
   last configuration seen (the *memo*), so repeated calls in one configuration skip it;
2. **select** at most one member per hedge group, each predicate evaluated once (SD5,
   SD6, SD14), recording the values only when a dispatch hook listens;
3. **find the chain** in a bounded per-function cache keyed by all the chain depends on:
   the layers whose partials it runs (the view's explicit layers, then the selected
   members). Layers without partials for this function never enter the key, so a
   composition full of unrelated layers that come and go neither thrashes the cache nor
   rebuilds chains;
4. **run** it: each ``around`` partial receives ``proceed`` (keyword-only) bound to the
   rest of the frozen chain -- no "current chain" in global state, so exceptions cannot
   corrupt it and async partials ``await proceed(...)``;
5. **report** one :class:`DispatchRecord` to the dispatch hooks, if any;
6. **apply** the global changes deferred during the dispatch when the outermost one ends (SD9).

:func:`reference_dispatcher` is the readable definition of that behaviour; ``fastpath.py``
generates a quicker one from it that must behave exactly the same.

Imports ``layer.py`` and ``state.py``.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from cosleec.cop.errors import DefinitionError, HedgeEvaluationError
from cosleec.cop.layer import Layer, LayerGroup
from cosleec.cop.state import (
    RT,
    Frame,
    GlobalState,
    bump_version,
    composition,
    dyn_get,
    flush_if_outermost,
    register_dispatch_code,
)

KINDS = ("before", "around", "after")
_UNSET: Any = object()
_registry: weakref.WeakSet[LayeredFunction] = weakref.WeakSet()


def all_layered() -> list[LayeredFunction]:
    """Every layered function alive (for introspection across functions, e.g. ``current_layers``)."""
    return list(_registry)


@dataclass(frozen=True, kw_only=True)
class DispatchRecord:
    """What one dispatch decided (SD16): the input of tracing, audit logs and explanations.

    Receive them with :func:`on_dispatch`. ``predicates`` maps each group to the value of
    every member's predicate (``None``: it raised); ``undetermined`` says a predicate raised.
    """

    function: str
    composition: tuple[str, ...]
    predicates: dict[str, dict[str, bool | None]]
    selected: dict[str, str | None]
    snapshot_id: object
    undetermined: bool = False
    error: str | None = None
    forced: dict[str, str] = field(default_factory=dict)


# ---------------------------------------------------------------- the context snapshot

_context: ContextVar[object] = ContextVar("cosleec.cop.context", default=_UNSET)


def current_context() -> Any:
    """The context snapshot hedge predicates read here (set by :class:`using_context`)."""
    ctx = _context.get()
    if ctx is _UNSET:
        raise LookupError("no context snapshot: use `with using_context(snapshot):` or a context= provider")
    return ctx


class using_context:
    """``with using_context(snapshot):`` -- the snapshot hedge predicates read in this extent.

    Use it when a layered function has no ``context=`` provider of its own.
    """

    def __init__(self, snapshot: Any) -> None:
        self.snapshot = snapshot

    def __enter__(self) -> Any:
        self._token = _context.set(self.snapshot)
        return self.snapshot

    def __exit__(self, *exc: object) -> None:
        _context.reset(self._token)


# ---------------------------------------------------------------- views, selections, chains


class View(NamedTuple):
    """What one configuration means for one layered function (step 1)."""

    composition: tuple[Layer, ...]
    explicit: tuple[Layer, ...]  # explicit layers with partials for the function, outermost first
    forced: tuple[Layer | None, ...]  # per hedge group: its member in the composition, if any
    settled: bool  # no group left to select by predicate: the chain is fixed
    generation: int  # the function's registrations when the view was taken


class Selection(NamedTuple):
    """The members selected (step 2), what to report, and the error to raise after reporting."""

    selected: tuple[Layer | None, ...]
    record: DispatchRecord | None
    failure: HedgeEvaluationError | None


Chain = tuple[Callable[..., Any], Callable[..., Any] | None, Callable[..., Any] | None]
"""A built chain, ``(call, around, proceed)``: ``call(*args, **kwargs)`` runs it. When its
outermost step is a lone ``around`` partial and the dispatcher links chains
(:attr:`LayeredFunction.link`, the fast path), ``around`` is that partial and ``proceed``
the function, made once per chain by ``link``, that runs the steps after it as that
partial's ``proceed`` (bound to one call's arguments by the dispatcher); otherwise both are
``None``. A plain tuple: the interpreter indexes and unpacks those quickest."""


Memo = tuple[
    GlobalState | None,
    Frame | None,
    Callable[..., Any] | None,
    Callable[..., Any] | None,
    Callable[..., Any] | None,
]
"""The last configuration seen and its chain, flat: ``(g, d, *chain)`` (one unpack in the fast path)."""
_NO_MEMO: Memo = (None, None, None, None, None)
_NO_VIEW: tuple[GlobalState | None, Frame | None, View | None] = (None, None, None)


class LayeredFunction:
    """The dispatch machinery of one layered function; ``@layered`` builds it, and the public
    callable carries it as ``.layered``.

    Use it for introspection (``explain``) and tuning: ``cache`` holds the built chains
    (at most ``max_chains``, least recently used evicted, H48), ``builds`` counts them.
    """

    def __init__(
        self,
        base: Callable[..., Any],
        *,
        hedges: Sequence[LayerGroup] = (),
        context: Callable[[], Any] | None = None,
        receiver: bool,
        max_chains: int = 256,
    ) -> None:
        self.base = base
        self.name: str = getattr(base, "__qualname__", repr(base))
        self.is_async = inspect.iscoroutinefunction(base)
        self.receiver = 1 if receiver else 0
        self.groups: tuple[LayerGroup, ...] = tuple(hedges)
        for g in self.groups:
            if g.policy is None:
                raise DefinitionError(f"group {g.name!r} has no selection policy; hedge groups need one")
            if g.owner is not None and g.owner() is not None:
                raise DefinitionError(f"hedge group {g.name!r} already belongs to another layered function")
            g.owner = weakref.ref(self)
        # the layers this function cares about: a hedge member -> its group's index, a layer
        # with partials -> -1; every other layer of a composition is skipped with one lookup
        self._interest: dict[Layer, int] = {m: i for i, g in enumerate(self.groups) for m in g.members}
        self.context = context
        self.partials: dict[Layer, dict[str, Callable[..., Any]]] = {}
        self.cache: dict[tuple[Layer, ...], Chain] = {}
        if max_chains < 1:
            raise DefinitionError(f"max_chains must be at least 1, not {max_chains}")
        self.max_chains = max_chains
        self.builds = 0
        self.generation = 0
        self.memo: Memo = _NO_MEMO  # set only for a settled chain and no dispatch hook
        self._view = _NO_VIEW  # the last configuration's view (step 1)
        # settled chains by dynamic frame (bounded like the cache): a function called under a
        # few recurring compositions -- one per rule clause, say -- finds its chain again
        # without recomputing its view when the one-slot memo held another
        self._by_frame: dict[Frame, tuple[GlobalState, Chain, View]] = {}
        # set by the fast path before any partial is registered: makes, from the rest of a
        # chain, the ``proceed`` function of the lone ``around`` step before it (see Chain)
        self.link: Callable[[Chain], Callable[..., Any]] | None = None
        self._lock = threading.Lock()
        _registry.add(self)

    # ------------------------------------------------------------------ registration
    def add_partial(self, layer: Layer, kind: str, fn: Callable[..., Any]) -> None:
        """Register ``fn`` as the ``kind`` partial of ``layer`` (SD12 checks); takes effect next dispatch."""
        if not isinstance(layer, Layer):
            raise DefinitionError(f"a partial needs a Layer, got {layer!r}")
        if kind not in KINDS:
            raise DefinitionError(f"unknown partial kind {kind!r}")
        slot = self.partials.get(layer, {})
        if kind in slot:
            raise DefinitionError(f"{layer.name!r} already has an {kind!r} partial for {self.name}")
        if inspect.iscoroutinefunction(fn) != self.is_async:
            raise DefinitionError(
                f"{'a synchronous' if self.is_async else 'an async'} partial for "
                f"{'async ' if self.is_async else ''}function {self.name}: partials must match the base"
            )
        group = layer.group
        if group is not None and group.policy is not None and group not in self.groups:
            raise DefinitionError(
                f"{layer.name!r} is a member of hedge group {group.name!r}, which is not attached to {self.name}"
            )
        with self._lock:
            self.partials[layer] = {**slot, kind: fn}
            self._interest.setdefault(layer, -1)
            self.generation += 1
            self.cache.clear()  # a registration invalidates every chain (A8)
            self.memo = _NO_MEMO
            self._view = _NO_VIEW
            self._by_frame = {}
        bump_version()  # and every memo that may still be filled from an older view

    def decorator(self, kind: str, layer: Layer) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
        """A decorator registering its function as the ``kind`` partial of ``layer``."""

        def register(fn: Callable[..., Any]) -> Callable[..., Any]:
            self.add_partial(layer, kind, fn)
            return fn

        return register

    # ------------------------------------------------------------------ steps 1-3 and 5
    def resolve(self, g: GlobalState, d: Frame) -> Chain:
        """Everything a dispatch does before running its chain, for global state ``g`` and frame ``d``."""
        hit = self._by_frame.get(d)
        if hit is not None and hit[0] is g:  # the same global state: the same settled chain
            self.memo = (g, d, *hit[1])
            return hit[1]
        view = self.view(g, d)
        hooks = g.dispatch_hooks
        if view.settled and not hooks:  # nothing to select, nobody to tell: remember the chain
            chain = self.chain_for(view, view.forced)
            self.memo = (g, d, *chain)
            by_frame = self._by_frame
            if len(by_frame) >= self.max_chains:
                # the oldest goes (bounded); another thread may be doing the same: then it went
                with contextlib.suppress(StopIteration, KeyError, RuntimeError):
                    del by_frame[next(iter(by_frame))]
            by_frame[d] = (g, chain, view)
            return chain
        sel = self.select(view, record=bool(hooks))
        for hook in hooks:
            hook(sel.record)
        if sel.failure is not None:
            raise sel.failure
        return self.chain_for(view, sel.selected)

    def view(self, g: GlobalState, d: Frame) -> View:
        """Step 1: the configuration ``(g, d)`` as this function sees it (memoised)."""
        memo = self._view
        if memo[0] is g and memo[1] is d and memo[2] is not None:
            return memo[2]
        comp = composition(g, d)
        forced: list[Layer | None] = [None] * len(self.groups)
        explicit: list[Layer] = []
        interest = self._interest
        for la in comp:
            i = interest.get(la)
            if i is None:
                continue  # no partial here: transparent (C27), and part of no key
            if i < 0:
                explicit.append(la)
            elif forced[i] is None:
                forced[i] = la  # explicitly activated: forced (SD6), at most one per group
        view = View(comp, tuple(explicit), tuple(forced), None not in forced, self.generation)
        self._view = (g, d, view)
        return view

    def context_snapshot(self) -> Any:
        """The context the predicates read: the ``context=`` provider's, else :func:`current_context`."""
        return self.context() if self.context is not None else current_context()

    def select(self, view: View, *, context: Any = _UNSET, record: bool = False) -> Selection:
        """Step 2: at most one member per hedge group (SD5, SD6, SD14).

        A forced member wins; otherwise every member's predicate is evaluated exactly once
        -- all of them, so that whether a predicate raises never depends on who listens --
        and the group's policy chooses. The values are kept only when ``record`` is asked.
        """
        selected: list[Layer | None] = []
        predicates: dict[str, dict[str, bool | None]] = {}
        failure: HedgeEvaluationError | None = None
        error: str | None = None
        ctx = context
        for grp, forced in zip(self.groups, view.forced):
            if forced is not None:
                selected.append(forced)
                continue
            if ctx is _UNSET:
                ctx = self.context_snapshot()
            held: list[bool] = []
            try:
                pick = _choose(grp, ctx, held)
            except HedgeEvaluationError as e:
                error, pick = str(e), _fallback(grp)
                if grp.on_error == "raise":
                    failure = e
            if record:
                predicates[grp.name] = _values(grp, held)
            selected.append(pick)
            if failure is not None:
                break  # SD14: no further selection, no chain; the record says undetermined
        rec = None
        if record:
            rec = DispatchRecord(
                function=self.name,
                composition=tuple(la.name for la in view.composition),
                predicates=predicates,
                selected={g.name: None if m is None else m.name for g, m in zip(self.groups, selected)},
                snapshot_id=_snap_id(None if ctx is _UNSET else ctx),
                undetermined=error is not None,
                error=error,
                forced={g.name: m.name for g, m in zip(self.groups, view.forced) if m is not None},
            )
        return Selection(tuple(selected), rec, failure)

    def chain_for(self, view: View, selected: tuple[Layer | None, ...]) -> Chain:
        """Step 3: the chain for the view's layers and the selected members, from the cache.

        The key is the tuple of layers whose partials the chain runs -- all it depends on.
        """
        key = tuple(self.layers_in_chain(view.explicit, selected))
        with self._lock:
            chain = self.cache.pop(key, None)
            if chain is None:
                chain = self._build(key)
                self.builds += 1
                while len(self.cache) >= self.max_chains:
                    del self.cache[next(iter(self.cache))]  # least recently used (H48)
            if view.generation == self.generation:  # not built from a superseded registration
                self.cache[key] = chain  # most recently used last
        return chain

    def layers_in_chain(self, explicit: tuple[Layer, ...], selected: tuple[Layer | None, ...]) -> list[Layer]:
        """The layers whose partials the chain runs, outermost first (SD7: hedges innermost)."""
        partials = self.partials
        return [*explicit, *(m for m in selected if m is not None and m in partials)]

    def _build(self, layers: tuple[Layer, ...]) -> Chain:
        make = _async_step if self.is_async else _step
        link = self.link
        chain: Chain = (self.base, None, None)
        for la in reversed(layers):
            parts = self.partials[la]
            step = make(parts, chain[0], self.receiver)
            around = parts.get("around")
            lone = around is not None and "before" not in parts and "after" not in parts
            # a lone around, linked: the fast path calls it with ``link(rest)`` as its proceed
            chain = (step, around, link(chain)) if lone and link is not None else (step, None, None)
        return chain


def _choose(grp: LayerGroup, ctx: Any, held: list[bool]) -> Layer | None:
    """Evaluate every member's predicate once (appending to ``held``) and apply the policy."""
    for m in grp.members:
        try:
            held.append(bool(m.predicate(ctx)))  # type: ignore[misc]
        except Exception as e:
            raise HedgeEvaluationError(grp.name, m.name, e) from e
    assert grp.policy is not None
    idx = grp.policy(held)
    return grp.members[idx] if idx is not None else None


def _fallback(grp: LayerGroup) -> Layer | None:
    """The member a group selects when a predicate raised and ``on_error`` names one (SD14)."""
    if grp.on_error in ("raise", "default"):
        return None
    return next(m for m in grp.members if m.name == grp.on_error)


def _values(grp: LayerGroup, held: list[bool]) -> dict[str, bool | None]:
    """Predicate values for the record; the member whose predicate raised maps to None."""
    values: dict[str, bool | None] = dict(zip((m.name for m in grp.members), held))
    if len(held) < len(grp.members):
        values[grp.members[len(held)].name] = None
    return values


def _snap_id(ctx: Any) -> object:
    if ctx is None:
        return None
    return getattr(ctx, "id", None) or id(ctx)


# ---------------------------------------------------------------- step 4: running a chain


def proceed_body(
    nxt: Callable[..., Any], args: tuple[Any, ...], kwargs: Mapping[str, Any], recv: int, /, *a: Any, **k: Any
) -> Any:
    """What every ``proceed`` does (SD3); an ``around`` partial receives it bound to one call,
    ``functools.partial(proceed_body, nxt, args, kwargs, recv)`` -- made at C level, cheaper
    per call than a closure.

    With no arguments it forwards the call's own ``args``/``kwargs`` to ``nxt``, the rest
    of the chain; arguments replace them, the receiver (the ``recv`` leading arguments)
    kept. In an async chain ``nxt`` returns a coroutine, which the partial awaits.
    """
    if a or k:
        return nxt(*args[:recv], *a, **k)
    return nxt(*args, **kwargs)


def _step(parts: dict[str, Callable[..., Any]], nxt: Callable[..., Any], recv: int) -> Callable[..., Any]:
    """One layer's partials around the rest of the chain: before, around, after (A6)."""
    before, around, after = parts.get("before"), parts.get("around"), parts.get("after")

    def step(*args: Any, **kwargs: Any) -> Any:
        if before is not None:
            before(*args, **kwargs)
        if around is not None:
            result = around(*args, proceed=functools.partial(proceed_body, nxt, args, kwargs, recv), **kwargs)
        else:
            result = nxt(*args, **kwargs)
        if after is not None:
            result = after(*args, result=result, **kwargs)
        return result

    return step


def _async_step(
    parts: dict[str, Callable[..., Any]], nxt: Callable[..., Any], recv: int
) -> Callable[..., Any]:
    """:func:`_step` for ``async`` functions."""
    before, around, after = parts.get("before"), parts.get("around"), parts.get("after")

    async def step(*args: Any, **kwargs: Any) -> Any:
        if before is not None:
            await before(*args, **kwargs)
        if around is not None:
            result = await around(
                *args, proceed=functools.partial(proceed_body, nxt, args, kwargs, recv), **kwargs
            )
        else:
            result = await nxt(*args, **kwargs)
        if after is not None:
            result = await after(*args, result=result, **kwargs)
        return result

    return step


# ---------------------------------------------------------------- the reference dispatcher


def reference_dispatcher(lf: LayeredFunction) -> Callable[..., Any]:
    """The dispatcher of ``lf``: the public callable of a layered function, for any call shape."""
    if lf.is_async:

        async def dispatch_async(*args: Any, **kwargs: Any) -> Any:
            try:
                g, d = RT.state, dyn_get()
                memo = lf.memo
                call = memo[2] if memo[0] is g and memo[1] is d else None
                if call is None:
                    call = lf.resolve(g, d)[0]
                return await call(*args, **kwargs)
            finally:
                if RT.pending:
                    flush_if_outermost()

        register_dispatch_code(dispatch_async.__code__)
        return dispatch_async

    def dispatch(*args: Any, **kwargs: Any) -> Any:
        try:
            g, d = RT.state, dyn_get()
            memo = lf.memo
            call = memo[2] if memo[0] is g and memo[1] is d else None
            if call is None:
                call = lf.resolve(g, d)[0]
            return call(*args, **kwargs)
        finally:
            if RT.pending:
                flush_if_outermost()

    register_dispatch_code(dispatch.__code__)
    return dispatch
