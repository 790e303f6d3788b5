"""Where the composition lives and how it changes (cop-runtime.md SD1, SD4, SD6-SD9, SD13, SD17).

- The *dynamic* composition is an immutable :class:`Frame` in a ``ContextVar``: correct
  across threads, asyncio tasks and (with ``layered_generator``) generators.
- The *global* composition is one immutable :class:`GlobalState`, replaced copy-on-write
  under a lock; readers take no lock.
- A dispatch reads both once (prompt-loyal). Global changes requested while the current
  thread/task runs a dispatch chain, or inside ``critical()``, are queued and applied in
  request order when the outermost dispatch ends.
"""

from __future__ import annotations

import itertools
import sys
import threading
from collections.abc import Callable, Iterable
from contextvars import ContextVar, Token
from types import TracebackType
from typing import Any, TypeVar

from cosleec.cop.errors import ActivationError, ExclusionError
from cosleec.cop.layer import Layer

_stamps = itertools.count(1)
_lock = threading.RLock()


class Frame:
    """An immutable dynamic composition: layers added in this extent, layers masked.

    ``absolute`` (set by ``run_with``) replaces the whole composition. ``comp`` caches the
    effective composition computed against one global state.
    """

    __slots__ = ("absolute", "added", "comp", "masked", "transitions")

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


EMPTY = Frame((), frozenset())


class GlobalState:
    """The immutable global composition: active layers with activation stamps and counts."""

    __slots__ = ("counts", "layers", "version")

    def __init__(self, version: int, layers: tuple[tuple[Layer, int], ...], counts: dict[Layer, int]) -> None:
        self.version = version
        self.layers = layers
        self.counts = counts


class _Hooked:
    """How many layers have enter/exit hooks (none: scopes skip computing what changed)."""

    count = 0


HOOKED = _Hooked()


class _Runtime:
    """Mutable module state, read without locks (each field is replaced atomically)."""

    __slots__ = ("activation_hooks", "dispatch_hooks", "functions", "idle", "queued", "state")

    def __init__(self) -> None:
        self.state = GlobalState(0, (), {})
        self.idle = True  # no global layer, no dispatch hook: layered functions may run their base directly
        self.queued = 0  # global requests waiting for a dispatch to end, in any thread
        self.dispatch_hooks: tuple[Callable[[Any], None], ...] = ()
        self.activation_hooks: tuple[Callable[[Layer, str], None], ...] = ()
        self.functions: Any = None  # weakref.WeakSet of layered functions (set by dispatch.py)


RT = _Runtime()
_dyn: ContextVar[Frame] = ContextVar("cosleec.cop.dynamic", default=EMPTY)
_queue: ContextVar[list[tuple[str, Layer]] | None] = ContextVar("cosleec.cop.queue", default=None)
_critical: ContextVar[int] = ContextVar("cosleec.cop.critical", default=0)
dyn_get = _dyn.get

# code objects of the frames that mean "a dispatch chain is running" (filled by dispatch.py)
DISPATCH_CODES: set[Any] = set()


def _refresh_idle(force: bool = False) -> None:
    """Recompute the fast-path flags; functions are visited only when the flag flips."""
    idle = not RT.state.layers and not RT.dispatch_hooks
    if idle == RT.idle and not force:
        return  # most global changes keep the process busy (or idle): nothing to tell
    RT.idle = idle
    funcs = RT.functions
    if funcs is not None:
        for f in list(funcs):
            f.refresh()


def hooks_changed() -> None:
    """A hook was added: drop every cached transition so that none bypasses it (E37)."""
    _clear_transitions(EMPTY)
    _refresh_idle(force=True)


def _clear_transitions(frame: Frame) -> None:
    children = list(frame.transitions.values())
    frame.transitions.clear()
    for c in children:
        _clear_transitions(c)


# ---------------------------------------------------------------- effective composition


def composition(g: GlobalState, d: Frame) -> tuple[Layer, ...]:
    """Explicit layers, outermost first: priority descending, then most recent first (SD7)."""
    cached = d.comp
    if cached[0] is g:
        return cached[1]
    if d.absolute is not None:
        comp = d.absolute
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
    return composition(RT.state, _dyn.get())


def is_active(layer: Layer) -> bool:
    return layer in active_layers()


# ---------------------------------------------------------------- scoped activation


class _Scope:
    """``with activate(...)`` / ``with deactivate(...)``: one dynamic extent.

    The object cannot be entered again while it is active (B17); after a normal exit it
    can be reused.
    """

    __slots__ = ("_active", "_before", "_entered", "_exited", "_layers", "_mode", "_token")

    def __init__(self, mode: str, layers: tuple[Layer, ...]) -> None:
        for la in layers:
            if not isinstance(la, Layer):
                raise TypeError(f"expected Layer objects, got {la!r}")
        self._mode = mode
        self._layers = layers
        self._active = False
        self._token: Token[Frame] | None = None
        self._before: Frame = EMPTY
        self._entered: tuple[Layer, ...] = ()
        self._exited: tuple[Layer, ...] = ()

    def __enter__(self) -> _Scope:
        if self._active:
            raise ActivationError("this activation is already in effect; use a new activate(...) for nesting")
        g = RT.state
        before = _dyn.get()
        frame = before
        for layer in self._layers:
            frame = _transition(frame, self._mode, layer, g)
        self._before = before
        self._token = _dyn.set(frame)
        self._active = True
        if HOOKED.count:  # what changed matters only to enter/exit hooks
            old, new = composition(g, before), composition(g, frame)
            self._entered = tuple([la for la in new if la not in old])
            self._exited = tuple([la for la in old if la not in new])
            _fire(self._entered, "enter")
            _fire(self._exited, "exit")
        return self

    def __exit__(
        self, et: type[BaseException] | None, ev: BaseException | None, tb: TracebackType | None
    ) -> None:
        token, self._token = self._token, None
        self._active = False
        if token is not None:
            try:
                _dyn.reset(token)
            except ValueError:  # exited in another Context (an undecorated generator): restore
                _dyn.set(self._before)
        _fire(self._exited, "enter")
        _fire(self._entered, "exit")


def _transition(frame: Frame, mode: str, layer: Layer, g: GlobalState) -> Frame:
    key = (mode, layer)
    nxt = frame.transitions.get(key)
    if nxt is not None and not RT.activation_hooks and not _conflicts(nxt, layer, g):
        return nxt  # a cached transition is used only when no hook must see the activation (E37)
    if mode == "activate":
        for hook in RT.activation_hooks:
            hook(layer, "scoped")  # a hook vetoes by raising: nothing has changed yet
        added, masked = frame.added, frame.masked
        current = composition(g, frame)
        rivals = _rivals(layer, current)
        if rivals:
            _check_exclusion(layer, rivals, "")
            added = tuple(x for x in added if x[0] not in rivals)
            masked = masked | frozenset(rivals)
        if layer in current and layer not in masked:
            return frame  # re-activation is a no-op and keeps the position (SD4)
        if not any(x[0] is layer for x in added):
            added = (*added, (layer, next(_stamps)))
        nxt = Frame(added, masked - {layer}, frame.absolute)
    else:
        added = tuple(x for x in frame.added if x[0] is not layer)
        absolute = frame.absolute
        if absolute is not None:
            absolute = tuple(x for x in absolute if x is not layer)
        nxt = Frame(added, frame.masked | {layer}, absolute)
    frame.transitions[key] = nxt
    return nxt


def _conflicts(frame: Frame, layer: Layer, g: GlobalState) -> bool:
    """A cached transition is stale if a global change made it violate exclusion."""
    if layer.group is None:
        return False
    members = set(layer.group.members)
    return sum(1 for la in composition(g, frame) if la in members) > 1


def _check_exclusion(layer: Layer, rivals: list[Layer], how: str) -> None:
    """Strict groups reject a second member (SD6, SD11); weak ones let the caller replace."""
    group = layer.group
    assert group is not None
    if group.exclusion == "strict":
        raise ExclusionError(
            f"cannot activate {layer.name!r}{how}: {rivals[0].name!r} of exclusive group {group.name!r} is active"
        )


def _rivals(layer: Layer, current: Iterable[Layer]) -> list[Layer]:
    group = layer.group
    if group is None:
        return []
    return [la for la in current if la is not layer and la.group is group]


def activate(*layers: Layer) -> _Scope:
    """Context manager: the layers are active for the code run inside the block (dynamic extent)."""
    return _Scope("activate", layers)


def deactivate(*layers: Layer) -> _Scope:
    """Context manager: the layers are inactive inside the block, global ones included (SD13)."""
    return _Scope("deactivate", layers)


def _fire(layers: Iterable[Layer], which: str) -> None:
    for la in layers:
        for hook in la._enter if which == "enter" else la._exit:
            hook(la)


# ---------------------------------------------------------------- global activation


def activate_globally(layer: Layer) -> None:
    """Activate ``layer`` process-wide; counted: n activations need n deactivations (SD8)."""
    _request("activate", layer)


def deactivate_globally(layer: Layer) -> None:
    _request("deactivate", layer)


def _request(op: str, layer: Layer) -> None:
    if not isinstance(layer, Layer):
        raise TypeError(f"expected a Layer, got {layer!r}")
    if _critical.get() or _in_dispatch():
        q = _queue.get()
        if q is None:
            q = []
            _queue.set(q)
        q.append((op, layer))
        with _lock:
            RT.queued += 1
        return
    _apply([(op, layer)])


def _apply(requests: list[tuple[str, Layer]]) -> None:
    """Apply global requests atomically: one new state, or none if any request fails."""
    entered: list[Layer] = []
    exited: list[Layer] = []
    with _lock:
        g = RT.state
        layers = dict(g.layers)
        counts = dict(g.counts)
        for op, layer in requests:
            n = counts.get(layer, 0)
            if op == "activate":
                if n == 0:
                    for hook in RT.activation_hooks:
                        hook(layer, "global")
                    rivals = _rivals(layer, layers)
                    if rivals:
                        _check_exclusion(layer, rivals, " globally")
                        for r in rivals:
                            layers.pop(r, None)
                            counts.pop(r, None)
                            exited.append(r)
                    layers[layer] = next(_stamps)
                    entered.append(layer)
                counts[layer] = n + 1
            else:
                if n == 0:
                    raise ActivationError(f"{layer.name!r} is not globally active")
                if n == 1:
                    del counts[layer]
                    del layers[layer]
                    exited.append(layer)
                else:
                    counts[layer] = n - 1
        RT.state = GlobalState(g.version + 1, tuple(layers.items()), counts)
        _refresh_idle()
    _fire(exited, "exit")
    _fire(entered, "enter")


def swap_globally(activate: Iterable[Layer] = (), deactivate: Iterable[Layer] = ()) -> None:
    """Apply several global changes as one atomic swap (used by event transitions, SD10)."""
    reqs = [("deactivate", la) for la in deactivate] + [("activate", la) for la in activate]
    if _critical.get() or _in_dispatch():
        for op, la in reqs:
            _request(op, la)
        return
    _apply(reqs)


def global_count(layer: Layer) -> int:
    return RT.state.counts.get(layer, 0)


# ---------------------------------------------------------------- deferral (SD9)


def _in_dispatch(skip: int = 2) -> bool:
    """Is a dispatch chain running in this thread/task? (Walks the stack: requests are rare.)"""
    f: Any = sys._getframe(skip)
    codes = DISPATCH_CODES
    while f is not None:
        if f.f_code in codes:
            return True
        f = f.f_back
    return False


def flush_if_outermost() -> None:
    """Called when a dispatch ends while requests are queued somewhere."""
    q = _queue.get()
    if not q or _critical.get() or _in_dispatch(3):  # 3: above the dispatch that is ending
        return
    _queue.set(None)
    with _lock:
        RT.queued -= len(q)
    changes = [(op, x) for op, x in q if op != "call"]
    if changes:
        _apply(changes)
    for op, fn in q:  # safe-point callbacks run after the changes queued before them
        if op == "call":
            fn()  # type: ignore[operator]


def at_safe_point(fn: Callable[[], object]) -> None:
    """Run ``fn`` at the next safe point: now if no dispatch runs in this thread/task, else
    when the outermost one ends -- never in the middle of a step (SD15, checklist F42).

    For optional policies such as re-evaluating obligations when a hedge predicate changes.
    """
    if _critical.get() or _in_dispatch():
        q = _queue.get()
        if q is None:
            q = []
            _queue.set(q)
        q.append(("call", fn))  # type: ignore[arg-type]
        with _lock:
            RT.queued += 1
        return
    fn()


class critical:
    """Defer global (de)activations made in the block until it ends (SD9)."""

    def __enter__(self) -> critical:
        self._token = _critical.set(_critical.get() + 1)
        return self

    def __exit__(self, *exc: object) -> None:
        _critical.reset(self._token)
        if not _critical.get():
            flush_if_outermost()


# ---------------------------------------------------------------- hooks


def add_activation_hook(hook: Callable[[Layer, str], None]) -> Callable[[], None]:
    """``hook(layer, "global" | "scoped")`` runs before each activation; raising vetoes it."""
    with _lock:
        RT.activation_hooks = (*RT.activation_hooks, hook)
    hooks_changed()

    def remove() -> None:
        with _lock:
            RT.activation_hooks = tuple(h for h in RT.activation_hooks if h is not hook)
        hooks_changed()

    return remove


# ---------------------------------------------------------------- capture and replay (SD17)

F = TypeVar("F", bound=Callable[..., Any])


class Snapshot:
    """A captured explicit composition (``snapshot()``)."""

    __slots__ = ("frame", "layers")

    def __init__(self, layers: tuple[Layer, ...]) -> None:
        self.layers = layers
        self.frame = Frame((), frozenset(), layers)

    def __repr__(self) -> str:
        return f"Snapshot({[la.name for la in self.layers]})"


def snapshot() -> Snapshot:
    return Snapshot(active_layers())


def run_with(snap: Snapshot, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
    """Run ``fn`` under the captured composition, whatever is active now."""
    token = _dyn.set(snap.frame)
    try:
        return fn(*args, **kwargs)
    finally:
        _dyn.reset(token)


def bind(fn: F) -> F:
    """A callable that always runs under the composition current when ``bind`` was called.

    For executors, plain threads and middleware callbacks, which do not carry contextvars.
    """
    snap = snapshot()

    def bound(*args: Any, **kwargs: Any) -> Any:
        return run_with(snap, fn, *args, **kwargs)

    bound.__wrapped__ = fn  # type: ignore[attr-defined]
    return bound  # type: ignore[return-value]


def reset_for_tests() -> None:
    """Forget every global activation and hook (tests only)."""
    with _lock:
        RT.state = GlobalState(RT.state.version + 1, (), {})
        RT.dispatch_hooks = ()
        RT.activation_hooks = ()
    _queue.set(None)
    _dyn.set(EMPTY)
    hooks_changed()
