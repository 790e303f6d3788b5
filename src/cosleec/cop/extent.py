"""The dynamic extent: scoped (de)activation and capture/replay (docs/reference/cop-runtime.md SD4, SD13, SD17).

``with activate(L):`` and ``with deactivate(L):`` replace the dynamic :class:`Frame` of
this thread/task for the block; ``run_with(snapshot, fn)`` does so for one call. Frames
are immutable and the transition from one frame to the next is cached, so entering the
same block again rebuilds nothing -- and a layered function recognises the frame it saw
last time (its memo).

Imports ``layer.py`` and ``state.py`` only.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from contextvars import Token
from typing import Any, TypeVar

from cosleec.cop.errors import ActivationError
from cosleec.cop.layer import Layer, displaced, fire_hooks
from cosleec.cop.state import EMPTY, RT, Frame, GlobalState, active_layers, composition, dynamic, next_stamp

R = TypeVar("R")


class _Scope:
    """``with activate(...)`` / ``with deactivate(...)``: one dynamic extent.

    The object cannot be entered again while it is active (B17); after a normal exit it
    can be reused.
    """

    __slots__ = ("_active", "_before", "_entered", "_exited", "_frame", "_layers", "_mode", "_token")

    def __init__(self, mode: str, layers: tuple[Layer, ...]) -> None:
        for la in layers:
            if not isinstance(la, Layer):
                raise TypeError(f"expected Layer objects, got {la!r}")
        self._mode = mode
        self._layers = layers
        self._active = False
        self._token: Token[Frame] | None = None
        self._before: Frame = EMPTY
        self._frame: Frame = EMPTY
        self._entered: tuple[Layer, ...] = ()
        self._exited: tuple[Layer, ...] = ()

    def __enter__(self) -> _Scope:
        if self._active:
            raise ActivationError("this activation is already in effect; use a new activate(...) for nesting")
        g = RT.state
        before = dynamic.get()
        frame = before
        for layer in self._layers:
            frame = _transition(frame, self._mode, layer, g)
        self._before, self._frame = before, frame
        self._token = dynamic.set(frame)
        self._active = True
        if Layer.hooked:  # what changed matters only to enter/exit hooks
            old, new = composition(g, before), composition(g, frame)
            self._entered = tuple([la for la in new if la not in old])
            self._exited = tuple([la for la in old if la not in new])
            fire_hooks(exited=self._exited, entered=self._entered)
        return self

    def __exit__(self, *exc: object) -> None:
        token, self._token = self._token, None
        self._active = False
        if token is not None:
            try:
                dynamic.reset(token)
            except ValueError:  # exited in another Context (SD18): never raise; restore what
                if dynamic.get() is self._frame:  # this block set, and never touch anything else
                    dynamic.set(self._before)
        fire_hooks(exited=self._entered, entered=self._exited)


def _transition(frame: Frame, mode: str, layer: Layer, g: GlobalState) -> Frame:
    key = (mode, layer)
    nxt = frame.transitions.get(key)
    if (
        nxt is not None
        and nxt.basis is g.layers
        and not g.activation_hooks
        and (layer.group is None or not g.layers or not _conflicts(nxt, layer, g))
    ):
        # a cached transition is used only when no hook must see the activation (E37), and
        # under the global layers it was made under: a layer activated globally since then
        # is more recent than the stamp it holds (SD7 orders by recency)
        return nxt
    if mode == "activate":
        for hook in g.activation_hooks:
            hook(layer, "scoped")  # a hook vetoes by raising: nothing has changed yet
        added, masked = frame.added, frame.masked
        current = composition(g, frame)
        rivals = displaced(layer, current)
        if rivals:
            added = tuple(x for x in added if x[0] not in rivals)
            masked = masked | frozenset(rivals)
        if layer in current and layer not in masked:
            return frame  # re-activation is a no-op and keeps the position (SD4)
        if not any(x[0] is layer for x in added):
            added = (*added, (layer, next_stamp()))
        nxt = Frame(added, masked - {layer}, frame.absolute)
    else:
        added = tuple(x for x in frame.added if x[0] is not layer)
        absolute = frame.absolute
        if absolute is not None:
            absolute = tuple(x for x in absolute if x is not layer)
        nxt = Frame(added, frame.masked | {layer}, absolute)
    nxt.basis = g.layers
    frame.transitions[key] = nxt
    return nxt


def _conflicts(frame: Frame, layer: Layer, g: GlobalState) -> bool:
    """A cached transition is stale if a global change made it violate exclusion.

    Only a globally active layer can make it so (the transition itself settled the
    frame's own rivals, and a captured composition ignores global layers): with none, it
    is not stale, and the common case -- a rule's clause layer entered for one dispatch --
    costs nothing here.
    """
    if layer.group is None or not g.layers:
        return False
    members = layer.group.members
    return sum(1 for la in composition(g, frame) if la in members) > 1


def activate(*layers: Layer) -> _Scope:
    """Context manager: the layers are active for the code run inside the block (dynamic extent).

    Use it for behaviour that should hold for one piece of work, in this thread or task only.
    """
    return _Scope("activate", layers)


def activating(layers: tuple[Layer, ...], fn: Callable[..., R], /, *args: Any) -> R:
    """``fn(*args)`` with ``layers`` active for its dynamic extent: ``with activate(*layers):
    return fn(*args)`` in one call, without a scope object.

    For a dispatcher that enters the same few layers around every call it makes (the
    runtime runs each decision's implementation so). With enter/exit hooks registered it
    takes the scope's way, which runs them.
    """
    if Layer.hooked:
        with _Scope("activate", layers):
            return fn(*args)
    g = RT.state
    frame = dynamic.get()
    for layer in layers:
        if not isinstance(layer, Layer):
            raise TypeError(f"expected Layer objects, got {layer!r}")
        nxt = frame.transitions.get(("activate", layer))
        if (  # the cached transition, as _transition takes it (without its call)
            nxt is not None
            and nxt.basis is g.layers
            and not g.activation_hooks
            and (layer.group is None or not g.layers)
        ):
            frame = nxt
        else:
            frame = _transition(frame, "activate", layer, g)
    token = dynamic.set(frame)
    try:
        return fn(*args)
    finally:
        dynamic.reset(token)


def deactivate(*layers: Layer) -> _Scope:
    """Context manager: the layers are inactive inside the block, global ones included (SD13)."""
    return _Scope("deactivate", layers)


# ---------------------------------------------------------------- capture and replay (SD17)

F = TypeVar("F", bound=Callable[..., Any])


_frames: dict[tuple[Layer, ...], Frame] = {}
_frames_lock = threading.Lock()
MAX_FRAMES = 1024
"""How many snapshot frames are remembered by their layers (the oldest is forgotten first)."""


class Snapshot:
    """A fixed explicit composition: capture one with :func:`snapshot`, or build one from layers.

    ``Snapshot((a, b))`` is the composition ``a`` outermost, then ``b``, whatever is active
    (taken as given: no priority ordering, no exclusion check); :func:`run_with` runs code
    under it. Cheap to build, and equal layers give the same
    frame: a layered function called again under an equal snapshot -- kept or built anew --
    recognises it (its memo) and does no work to find its chain.
    """

    __slots__ = ("frame", "layers")

    def __init__(self, layers: tuple[Layer, ...]) -> None:
        self.layers = layers = tuple(layers)
        frame = _frames.get(layers)
        if frame is None:
            frame = Frame((), frozenset(), tuple(dict.fromkeys(layers)))  # a layer runs once (SD4)
            with _frames_lock:
                if len(_frames) >= MAX_FRAMES:
                    del _frames[next(iter(_frames))]
                frame = _frames.setdefault(layers, frame)
        self.frame = frame

    def __repr__(self) -> str:
        return f"Snapshot({[la.name for la in self.layers]})"


def snapshot() -> Snapshot:
    """Capture the explicit composition seen here and now (SD17)."""
    return Snapshot(active_layers())


def run_with(snap: Snapshot, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
    """Run ``fn(*args, **kwargs)`` under the composition of ``snap``, whatever is active now."""
    token = dynamic.set(snap.frame)
    try:
        return fn(*args, **kwargs)
    finally:
        dynamic.reset(token)


def bind(fn: F) -> F:
    """A callable that always runs under the composition current when ``bind`` was called.

    For executors, plain threads and middleware callbacks, which do not carry contextvars.
    """
    snap = snapshot()

    def bound(*args: Any, **kwargs: Any) -> Any:
        return run_with(snap, fn, *args, **kwargs)

    bound.__wrapped__ = fn  # type: ignore[attr-defined]
    return bound  # type: ignore[return-value]
