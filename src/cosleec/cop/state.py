"""Where the composition lives, and its global changes (docs/reference/cop-runtime.md SD1, SD6-SD9).

- The *dynamic* composition is an immutable :class:`Frame` in a ``ContextVar``: correct
  across threads, asyncio tasks and (with ``layered_generator``) generators. ``extent.py``
  changes it for a ``with`` block or a ``run_with`` call.
- The *global* configuration is one immutable :class:`GlobalState` -- active layers,
  activation counts and the installed hooks -- replaced copy-on-write under a lock;
  readers take no lock.
- A dispatch reads both once (prompt-loyal). Global changes requested while the current
  thread/task runs a dispatch, or inside ``critical()``, are queued and applied in request
  order when the outermost dispatch ends.

This module knows layers (``layer.py``), not layered functions: the dispatchers tell it
which code objects mean "a dispatch is running" through :func:`register_dispatch_code`.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import itertools
import sys
import threading
from collections.abc import Callable, Iterable, Mapping
from contextvars import ContextVar
from dataclasses import dataclass, field, replace
from types import CodeType, MappingProxyType
from typing import Any

from cosleec.cop.errors import ActivationError
from cosleec.cop.layer import Layer, displaced, fire_hooks

next_stamp = itertools.count(1).__next__
"""A fresh activation stamp: later activations get larger stamps (the recency order of SD7)."""
_lock = threading.RLock()

DispatchHook = Callable[[Any], None]
ActivationHook = Callable[[Layer, str], None]


class Frame:
    """An immutable dynamic composition: layers added in this extent, layers masked.

    ``absolute`` (set by ``run_with``) replaces the whole composition. ``comp`` caches the
    effective composition computed against one global state. ``basis``: the global layers
    when ``extent`` cached this frame as a transition (it is reused only under the same ones).
    """

    __slots__ = ("absolute", "added", "basis", "comp", "masked", "transitions")

    def __init__(
        self,
        added: tuple[tuple[Layer, int], ...],
        masked: frozenset[Layer],
        absolute: tuple[Layer, ...] | None = None,
    ) -> None:
        self.added = added
        self.masked = masked
        self.absolute = absolute
        self.comp: tuple[GlobalState | None, tuple[Layer, ...]] = (None, ())
        self.transitions: dict[tuple[str, Layer], Frame] = {}
        self.basis: tuple[tuple[Layer, int], ...] | None = None


EMPTY = Frame((), frozenset())


@dataclass(frozen=True, kw_only=True, slots=True, eq=False)
class GlobalState:
    """The global configuration: active layers with activation stamps and counts, and hooks.

    One immutable value, replaced as a whole by every change: a dispatch that read it sees
    one consistent configuration. Keep one from :func:`global_state` to return to it later
    with :func:`restore_globally`.
    """

    version: int = 0
    layers: tuple[tuple[Layer, int], ...] = ()
    counts: Mapping[Layer, int] = field(default_factory=lambda: MappingProxyType({}))
    dispatch_hooks: tuple[DispatchHook, ...] = ()
    activation_hooks: tuple[ActivationHook, ...] = ()


class _Runtime:
    """Mutable module state, read without locks (each field is replaced atomically)."""

    __slots__ = ("pending", "queued", "state")

    def __init__(self) -> None:
        self.state = GlobalState()
        self.queued = 0  # global requests waiting for a dispatch to end, in any thread
        # ``queued > 0``, kept with it under the lock: what a dispatch tests as it ends (a
        # bool: the interpreter tests one without a call)
        self.pending = False


RT = _Runtime()
dynamic: ContextVar[Frame] = ContextVar("cosleec.cop.dynamic", default=EMPTY)
"""The dynamic composition of this thread/task (set by ``extent.py`` for a ``with`` block or ``run_with``)."""
_queue: ContextVar[list[tuple[str, Any]] | None] = ContextVar("cosleec.cop.queue", default=None)
_critical: ContextVar[int] = ContextVar("cosleec.cop.critical", default=0)
dyn_get = dynamic.get
"""The current dynamic frame (one ``ContextVar.get``): what a dispatch reads with ``RT.state``."""

# code objects of the frames that mean "a dispatch is running" (SD9)
_dispatch_codes: set[CodeType] = set()


def register_dispatch_code(code: CodeType) -> None:
    """Frames running ``code`` count as a running dispatch: global requests made below them
    wait until the outermost one ends (SD9). Called by the dispatchers for their own code."""
    _dispatch_codes.add(code)


# ---------------------------------------------------------------- effective composition


def composition(g: GlobalState, d: Frame) -> tuple[Layer, ...]:
    """Explicit layers, outermost first: priority descending, then most recent first (SD7)."""
    cached = d.comp
    if cached[0] is g:
        return cached[1]
    if d.absolute is not None:  # a captured composition (run_with), plus what was activated inside it
        comp = tuple(la for la in d.absolute if la not in d.masked)
        if d.added:
            ages = dict.fromkeys(comp, 0)  # captured layers: older than any activated inside
            for layer, stamp in d.added:
                ages[layer] = max(stamp, ages.get(layer, 0))
            comp = tuple(
                sorted(ages, key=lambda la: (-la.priority, -ages[la]))
            )  # stable: keeps capture order
    else:
        stamped: dict[Layer, int] = {}
        for layer, stamp in g.layers:
            if layer not in d.masked:
                stamped[layer] = stamp
        for layer, stamp in d.added:
            stamped[layer] = max(stamp, stamped.get(layer, 0))
        comp = tuple(sorted(stamped, key=lambda la: (-la.priority, -stamped[la])))
    d.comp = (g, comp)
    return comp


def active_layers() -> tuple[Layer, ...]:
    """The explicit composition seen here and now, outermost first."""
    return composition(RT.state, dynamic.get())


def is_active(layer: Layer) -> bool:
    """Is ``layer`` explicitly active here and now (globally or in an enclosing scope)?"""
    return layer in active_layers()


# ---------------------------------------------------------------- global activation


def activate_globally(layer: Layer) -> None:
    """Activate ``layer`` process-wide; counted: n activations need n deactivations (SD8).

    Use it for modes that hold everywhere (maintenance, a user profile) until switched off.
    """
    _request("activate", layer)


def deactivate_globally(layer: Layer) -> None:
    """Undo one :func:`activate_globally`; the layer goes when its count reaches zero (SD8)."""
    _request("deactivate", layer)


def _defer(requests: list[tuple[str, Any]]) -> bool:
    """Queue requests if a dispatch or ``critical()`` is running here (SD9); True if queued."""
    if not (_critical.get() or _in_dispatch(3)):
        return False
    q = _queue.get()
    if q is None:
        q = []
        _queue.set(q)
    q.extend(requests)
    with _lock:
        RT.queued += len(requests)
        RT.pending = RT.queued > 0
    return True


def _request(op: str, layer: Layer) -> None:
    if not isinstance(layer, Layer):
        raise TypeError(f"expected a Layer, got {layer!r}")
    if not _defer([(op, layer)]):
        _apply([(op, layer)])


def _apply(requests: list[tuple[str, Any]]) -> None:
    """Apply global requests atomically: one new state, or none if any request fails."""
    with _lock:
        g = RT.state
        old = dict(g.layers)
        layers, counts = dict(old), dict(g.counts)
        hooks = (g.dispatch_hooks, g.activation_hooks)
        for op, x in requests:
            if op == "restore":
                layers, counts = dict(x.layers), dict(x.counts)
                hooks = (x.dispatch_hooks, x.activation_hooks)
            elif op == "activate":
                _count_up(x, layers, counts, hooks[1])
            else:
                _count_down(x, layers, counts)
        RT.state = GlobalState(
            version=g.version + 1,
            layers=tuple(layers.items()),
            counts=MappingProxyType(counts),
            dispatch_hooks=hooks[0],
            activation_hooks=hooks[1],
        )
    fire_hooks(exited=[la for la in old if la not in layers], entered=[la for la in layers if la not in old])


def _count_up(
    layer: Layer, layers: dict[Layer, int], counts: dict[Layer, int], hooks: tuple[ActivationHook, ...]
) -> None:
    n = counts.get(layer, 0)
    if n == 0:
        for hook in hooks:
            hook(layer, "global")
        for r in displaced(layer, layers, " globally"):
            layers.pop(r, None)
            counts.pop(r, None)
        layers[layer] = next_stamp()
    counts[layer] = n + 1


def _count_down(layer: Layer, layers: dict[Layer, int], counts: dict[Layer, int]) -> None:
    n = counts.get(layer, 0)
    if n == 0:
        raise ActivationError(f"{layer.name!r} is not globally active")
    if n == 1:
        del counts[layer]
        del layers[layer]
    else:
        counts[layer] = n - 1


def swap_globally(activate: Iterable[Layer] = (), deactivate: Iterable[Layer] = ()) -> None:
    """Apply several global changes as one atomic swap: a concurrent reader sees the
    configuration before or after, never in between (event transitions, SD10)."""
    reqs = [("deactivate", la) for la in deactivate] + [("activate", la) for la in activate]
    for _, la in reqs:
        if not isinstance(la, Layer):
            raise TypeError(f"expected a Layer, got {la!r}")
    if not _defer(reqs):
        _apply(reqs)


def bump_version() -> None:
    """A new global state with the same content: every memo keyed on the old one is stale.

    For changes that alter what a configuration means, e.g. a partial registered.
    """
    with _lock:
        RT.state = replace(RT.state, version=RT.state.version + 1)


def global_count(layer: Layer) -> int:
    """How many :func:`activate_globally` calls on ``layer`` are outstanding (SD8)."""
    return RT.state.counts.get(layer, 0)


def global_state() -> GlobalState:
    """The current global configuration, an immutable value: keep it to :func:`restore_globally` it.

    Use it around work that must leave the process as it found it: a what-if simulation,
    an operator session that is rolled back, a test.
    """
    return RT.state


def restore_globally(saved: GlobalState) -> None:
    """Make ``saved`` (from :func:`global_state`) the global configuration again, atomically.

    Global layers, their counts and the dispatch and activation hooks become those of
    ``saved``; enter/exit hooks fire for the layers that leave or come back. Requested
    inside a dispatch or ``critical()``, it waits for the end like any global change (SD9).
    Scoped activations are untouched: they end with their ``with`` blocks.
    """
    if not _defer([("restore", saved)]):
        _apply([("restore", saved)])


# ---------------------------------------------------------------- deferral (SD9)


def _in_dispatch(skip: int = 2) -> bool:
    """Is a dispatch running in this thread/task? (Walks the stack: requests are rare.)"""
    f: Any = sys._getframe(skip)
    codes = _dispatch_codes
    while f is not None:
        if f.f_code in codes:
            return True
        f = f.f_back
    return False


def flush_if_outermost() -> None:
    """Apply the requests queued in this thread/task if no dispatch is running any more.

    Called by the dispatchers when a dispatch ends while requests are queued somewhere.
    """
    q = _queue.get()
    if not q or _critical.get() or _in_dispatch(3):  # 3: above the dispatch that is ending
        return
    _queue.set(None)
    with _lock:
        RT.queued -= len(q)
        RT.pending = RT.queued > 0
    changes = [(op, x) for op, x in q if op != "call"]
    if changes:
        _apply(changes)
    for op, fn in q:  # safe-point callbacks run after the changes queued before them
        if op == "call":
            fn()


def at_safe_point(fn: Callable[[], object]) -> None:
    """Run ``fn`` at the next safe point: now if no dispatch runs in this thread/task, else
    when the outermost one ends -- never in the middle of a step (SD15, checklist F42).

    For optional policies such as re-evaluating a decision when a hedge predicate changes.
    """
    if not _defer([("call", fn)]):
        fn()


class critical:
    """``with critical():`` defers global (de)activations made in the block until it ends (SD9).

    Use it to make several global changes take effect together, as one step.
    """

    def __enter__(self) -> critical:
        self._token = _critical.set(_critical.get() + 1)
        return self

    def __exit__(self, *exc: object) -> None:
        _critical.reset(self._token)
        if not _critical.get():
            flush_if_outermost()


# ---------------------------------------------------------------- hooks


def _set_hooks(dispatch: tuple[DispatchHook, ...], activation: tuple[ActivationHook, ...]) -> None:
    g = RT.state
    RT.state = replace(g, version=g.version + 1, dispatch_hooks=dispatch, activation_hooks=activation)


def add_activation_hook(hook: ActivationHook) -> Callable[[], None]:
    """``hook(layer, "global" | "scoped")`` runs before each activation; raising vetoes it (E37).

    Returns a function that removes the hook. Use it for access control or constraints
    that the groups cannot express.
    """
    with _lock:
        _set_hooks(RT.state.dispatch_hooks, (*RT.state.activation_hooks, hook))

    def remove() -> None:
        with _lock:
            _set_hooks(RT.state.dispatch_hooks, tuple(h for h in RT.state.activation_hooks if h is not hook))

    return remove


def add_dispatch_hook(hook: DispatchHook) -> Callable[[], None]:
    """Install ``hook(record)`` for every dispatch; returns its remover (``on_dispatch`` is the face)."""
    with _lock:
        _set_hooks((*RT.state.dispatch_hooks, hook), RT.state.activation_hooks)

    def remove() -> None:
        with _lock:
            _set_hooks(tuple(h for h in RT.state.dispatch_hooks if h is not hook), RT.state.activation_hooks)

    return remove
