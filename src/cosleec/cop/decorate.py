"""``@layered``: how a function or method becomes layered, and how partials are attached.

The public callable is the dispatcher itself -- the reference (``dispatch.py``) or the
generated fast path (``fastpath.py``) -- so it binds as a method like any function, and
the user's function is never copied or recompiled: it runs as written, with its class,
closure, defaults and decorators. The dispatcher carries ``.layered`` (the
:class:`LayeredFunction`) and the registration decorators ``.variant``/``.around``,
``.before`` and ``.after``.

Imports ``layer.py``, ``state.py``, ``dispatch.py`` and ``fastpath.py``.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Sequence
from typing import Any

from cosleec.cop.dispatch import DispatchRecord, LayeredFunction, reference_dispatcher
from cosleec.cop.errors import DefinitionError
from cosleec.cop.fastpath import fast_dispatcher
from cosleec.cop.layer import Layer, LayerGroup
from cosleec.cop.state import add_dispatch_hook

FAST_BY_DEFAULT = True
"""Whether ``@layered`` uses the generated fast path unless told otherwise (``fast=``).

On because the whole COP checklist (``tests/unit/cop``) runs against both dispatchers and
passes on both; turn it off (or pass ``fast=False``) to debug with the readable reference.
"""


def _is_method(fn: Callable[..., Any]) -> bool:
    """Defined in a class body, with a conventional receiver name as first parameter."""
    parts = getattr(fn, "__qualname__", "").split(".")
    if len(parts) < 2 or parts[-2] == "<locals>":
        return False
    try:
        params = list(inspect.signature(fn).parameters)
    except (TypeError, ValueError):
        return False
    return bool(params) and params[0] in ("self", "cls", "mcs")


class _StaticLayered(staticmethod):  # type: ignore[type-arg]
    """A layered staticmethod that still offers ``.variant``/``.before``/``.after`` in the class body."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self.__func__, name)


class _ClassLayered(classmethod):  # type: ignore[type-arg]
    """A layered classmethod that still offers ``.variant``/``.before``/``.after`` in the class body."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self.__func__, name)


def _decorate(
    fn: Any,
    hedges: tuple[LayerGroup, ...],
    context: Callable[[], Any] | None,
    method: bool | None,
    max_chains: int,
    fast: bool,
) -> Any:
    wrap_kind: type | None = None
    if isinstance(fn, staticmethod | classmethod):
        wrap_kind = type(fn)
        fn = fn.__func__
        method = wrap_kind is classmethod
    if not callable(fn):
        raise DefinitionError(f"@layered needs a function, got {fn!r}")
    receiver = _is_method(fn) if method is None else method
    lf = LayeredFunction(fn, hedges=hedges, context=context, receiver=receiver, max_chains=max_chains)
    public = fast_dispatcher(lf) if fast else reference_dispatcher(lf)
    functools.update_wrapper(public, fn)
    public.layered = lf  # type: ignore[attr-defined]
    public.variant = public.around = functools.partial(lf.decorator, "around")  # type: ignore[attr-defined]
    public.before = functools.partial(lf.decorator, "before")  # type: ignore[attr-defined]
    public.after = functools.partial(lf.decorator, "after")  # type: ignore[attr-defined]
    if wrap_kind is staticmethod:
        return _StaticLayered(public)
    if wrap_kind is classmethod:
        return _ClassLayered(public)
    return public


def layered(
    fn: Callable[..., Any] | None = None,
    *,
    hedges: LayerGroup | Sequence[LayerGroup] = (),
    context: Callable[[], Any] | None = None,
    method: bool | None = None,
    max_chains: int = 256,
    fast: bool | None = None,
) -> Any:
    """Make a function or method layered: its body is the base implementation.

    Use it on every function whose behaviour should vary with the active layers; then
    attach partials with ``.variant(layer)`` (an ``around`` partial receiving
    ``proceed=``), ``.before(layer)`` and ``.after(layer)`` (receiving ``result=``).

    Parameters:
        hedges: hedge groups whose selected member runs innermost, around the base.
        context: returns the snapshot the predicates read, once per dispatch (default:
            the snapshot of ``using_context``).
        method: whether the first argument is a receiver that ``proceed(...)`` keeps
            (default: detected from the qualified name and a ``self``/``cls`` parameter).
        max_chains: how many chains the function caches (least recently used evicted).
        fast: use the generated fast path (default :data:`FAST_BY_DEFAULT`) or, with
            ``False``, the reference dispatcher. Both behave the same.

    Example::

        @layered
        def greet(name):
            return f"hello {name}"

        @greet.variant(loud)
        def _(name, *, proceed):
            return proceed().upper()
    """
    groups = (hedges,) if isinstance(hedges, LayerGroup) else tuple(hedges)
    use_fast = FAST_BY_DEFAULT if fast is None else fast

    def deco(f: Callable[..., Any]) -> Any:
        return _decorate(f, groups, context, method, max_chains, use_fast)

    return deco(fn) if fn is not None else deco


def partial(
    target: Any, layer: Layer, kind: str = "around"
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register a partial of ``layer`` on the layered function ``target``, from outside its definition.

    A layer cannot introduce a function: ``target`` must be layered (A10).
    """
    lf = getattr(target, "layered", None)
    if not isinstance(lf, LayeredFunction):
        raise DefinitionError(f"{getattr(target, '__qualname__', target)!r} is not a layered function")
    return lf.decorator(kind, layer)


def on_dispatch(hook: Callable[[DispatchRecord], None]) -> Callable[[], None]:
    """Call ``hook(record)`` with every dispatch decision (SD16); returns a function removing it.

    Use it for tracing, audit logs and runtime verification. While no hook is installed,
    no record is built.
    """
    return add_dispatch_hook(hook)
