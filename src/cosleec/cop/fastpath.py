"""GENERATED FAST PATH -- a quicker copy of ``dispatch.reference_dispatcher``.

It must behave exactly like the reference dispatcher: the whole COP checklist in
``tests/unit/cop`` runs against both (``layered(..., fast=False)`` selects the reference).
Change the reference first, then this template, never this alone.

What is generated, and why it is the same:

- The reference takes ``*args, **kwargs``; packing them costs as much as a small base.
  The fast dispatcher takes the base's *k* required positional arguments as
  positional-only slots defaulting to a private sentinel, then ``*rest, **kw``. A call
  that fills every slot and passes nothing else -- the usual call -- reaches the chain
  with the very arguments the caller gave; any other shape is rebuilt exactly
  (positionals fill slots in order, so the given slots are a prefix) and takes the
  reference's route. Partials therefore see the caller's arguments as the caller passed
  them, as in the reference. Parameter names never appear in the generated code, so no
  name of the base can clash with it.
- The dispatcher reads the memo as one flat tuple ``(g, d, call, around, proceed)``: two
  identity checks say whether the configuration is the one last seen, and then the
  chain is at hand without further lookups (``LayeredFunction.resolve`` otherwise).
- A chain whose outer steps are lone ``around`` partials is linked (``dispatch.Chain``):
  each lone ``around`` step carries the ``proceed`` function of the steps after it, made
  once per chain by this template's ``link``. The usual call runs the outermost ``around``
  here with that function bound to the call's arguments (``MethodType`` over the one
  argument, or the tuple of them: one C-level object per layer, no closure, no node to
  unpack); called with no arguments it runs the next ``around`` the same way, down to the
  first step that is not a lone ``around`` (or the base), which it calls with the call's
  arguments. Called with arguments it calls the rest of the chain's closure, the receiver
  kept, exactly as ``dispatch.proceed_body`` does with ``nxt``: the partials see the same
  calls, in the same order, as under the reference. Where nothing need be bound the
  ``proceed`` is made once: with no required positional, or a receiver alone before the
  base (``MethodType(base, self)`` is then exactly the reference's ``proceed``).

Templates are compiled once per (k, sync/async, receiver) and shared by every layered
function of that shape: one code object each, registered as a dispatch (SD9). What does
not vary between functions (``RT``, the frame getter, the sentinel, ``MethodType``) is a
global of the template, so a dispatcher's frame carries one free variable (its
:class:`LayeredFunction`); the end-of-dispatch test reads ``RT.pending``, a bool kept
with ``RT.queued`` (SD9 flushes exactly when it did). The cost that remains with no layer
active is the dispatcher's own frame: CPython 3.11 cannot specialise a call to a function
with ``*args``/``**kwargs`` and builds the ``**kw`` dict on every call (that frame alone is
2.1x a plain call of B-min in instructions; reading the ``ContextVar`` and the memo check
most of the rest); with layers, each costs a call of its partial (keyword ``proceed``), one
bound method (``MethodType``, made by a generic type call: the largest single item) and
the frame of ``proceed`` (``**k`` again).

Imports ``dispatch.py`` and ``state.py``.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import inspect
import threading
from collections.abc import Callable
from types import FunctionType, MethodType
from typing import Any

from cosleec.cop.dispatch import Chain, LayeredFunction
from cosleec.cop.state import RT, dyn_get, flush_if_outermost, register_dispatch_code

_TEMPLATE = """
# globals of every dispatcher of this shape: RT, get, flush, M, E, MT (set before exec),
# so that a dispatcher's frame carries one free variable, its LayeredFunction

def link(rest):  # the proceed of a lone around whose chain continues with ``rest`` (dispatch.Chain)
    call, around, p = rest
{link_body}

def make(lf):
    {async_}def dispatch({slots}*_r, **_k):
        try:
            mg, md, call, around, p = lf.memo
            if mg is not RT.state or md is not get():
                call, around, p = lf.resolve(RT.state, get())
            if {usual}:
                if around is None:
                    return {await_}call({args})
                return {await_}around({args}{comma}proceed={bind})
            return {await_}call(*[a for a in ({args}{tuple_comma}) if a is not M], *_r, **_k)
        finally:
            if RT.pending:
                flush()

    return dispatch
"""

# ``link`` bodies: what ``proceed`` does, as ``dispatch.proceed_body`` does it with the call's
# arguments bound -- arguments given replace them (the receiver kept); none given: the rest
# of the chain runs with the bound ones, the next lone around called here with its proceed.
# ``a is not E or k`` first: the usual ``proceed()`` passes CPython's empty-tuple singleton
# and tests one identity; any other empty tuple is tested again, just as right.

# no required positional: nothing to bind, one proceed per chain, made here
_LINK_0 = """
    if around is None:
        return call  # proceed(*a, **k) is call(*a, **k), proceed() is call(): proceed_body's
    def proceed(*a, **k):
        if a or k:
            return call(*a, **k)
        return around(proceed=p)
    return proceed
"""

# one: bound to the argument itself (``MT(proceed, _a0)``); a receiver's next step bound directly
_LINK_1 = """
    if around is None:
        if {recv}:
            return call  # MT(call, self): proceed(*a, **k) is call(self, *a, **k)
        def proceed(_a0, /, *a, **k):
            if a is not E or k:
                if a or k:
                    return call(*a, **k)
            return call(_a0)
        return proceed
    def proceed(_a0, /, *a, **k):
        if a is not E or k:
            if a or k:
                return call({recv_a}*a, **k)
        return around(_a0, proceed=MT(p, _a0))
    return proceed
"""

# two or more: bound to the tuple of the arguments, passed on as it is
_LINK_N = """
    def proceed(st, /, *a, **k):
        if a is not E or k:
            if a or k:
                return call({recv_st}*a, **k)
        {args}, = st
        if around is None:
            return call({args})
        return around({args}, proceed=MT(p, st))
    return proceed
"""

_MISSING = object()
Factory = tuple[Callable[[LayeredFunction], Callable[..., Any]], Callable[[Chain], Callable[..., Any]]]
"""A compiled template: ``make(lf)``, the dispatcher of ``lf``, and ``link(rest)`` (dispatch.Chain)."""
_factories: dict[tuple[int, bool, bool], Factory] = {}
_lock = threading.Lock()


def _factory(k: int, is_async: bool, receiver: bool) -> Factory:
    """The compiled template for ``k`` slots (built on first use, then shared)."""
    key = (k, is_async, receiver)
    make = _factories.get(key)
    if make is not None:
        return make
    with _lock:
        make = _factories.get(key)
        if make is None:
            slots = [f"_a{i}" for i in range(k)]
            args = ", ".join(slots)
            link = (_LINK_0, _LINK_1, _LINK_N)[min(k, 2)].format(
                recv=receiver,
                recv_a="_a0, " if receiver else "",
                recv_st="st[0], " if receiver else "",
                args=args,
            )
            bind = ("p", "MT(p, _a0)", f"MT(p, ({args}))")[min(k, 2)]
            src = _TEMPLATE.format(
                link_body=link,
                bind=bind,
                async_="async " if is_async else "",
                await_="await " if is_async else "",
                slots="".join(f"{s}=M, " for s in slots) + ("/, " if k else ""),
                # ``_r is E``: no extra positional (CPython passes its empty-tuple singleton; were
                # it another empty tuple, the call would take the general route, just as right)
                usual=" and ".join(["_r is E"] + [f"{s} is not M" for s in slots[-1:]] + ["not _k"]),
                args=args,
                comma=", " if k else "",
                tuple_comma="," if k == 1 else "",
            )
            ns: dict[str, Any] = {
                "RT": RT,
                "get": dyn_get,
                "flush": flush_if_outermost,
                "M": _MISSING,
                "E": (),
                "MT": MethodType,
            }
            exec(compile(src, f"<cosleec.cop fast dispatcher, {k} slots>", "exec"), ns)
            make = ns["make"], ns["link"]
            register_dispatch_code(_inner_code(make[0]))
            _factories[key] = make
    return make


def _inner_code(make: Callable[..., Any]) -> Any:
    """The code object of the dispatcher a factory makes (the frame SD9 looks for)."""
    return next(c for c in make.__code__.co_consts if inspect.iscode(c) and c.co_name == "dispatch")


def required_positionals(fn: Callable[..., Any]) -> int:
    """How many positional arguments a call of ``fn`` must give (0 when its signature is unknown).

    For a plain function -- no ``__wrapped__``, ``__signature__`` or ``_partialmethod`` that
    ``inspect.signature`` would follow -- the answer is read from its code and defaults:
    the positional parameters without a default, as ``inspect`` counts them, without
    building a ``Signature`` (a SLEEC manager decorates one handler per rule). Anything
    else asks ``inspect``.
    """
    if type(fn) is FunctionType and not (_FOLLOWED & fn.__dict__.keys()):
        n = fn.__code__.co_argcount - len(fn.__defaults__ or ())
        if n >= 0:
            return n
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return 0
    k = 0
    for p in params:
        if p.kind not in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) or p.default is not p.empty:
            break
        k += 1
    return k


_FOLLOWED = frozenset({"__wrapped__", "__signature__", "_partialmethod", "__partialmethod__"})
"""Attributes through which ``inspect.signature`` reports another signature than the code's."""


def fast_dispatcher(lf: LayeredFunction) -> Callable[..., Any]:
    """The generated dispatcher of ``lf``: same behaviour as ``reference_dispatcher(lf)``."""
    make, link = _factory(required_positionals(lf.base), lf.is_async, bool(lf.receiver))
    lf.link = link
    return make(lf)
