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
- When the chain's outermost step is a lone ``around`` partial (its ``head``), the
  usual call runs it here, saving the step's frame. Its ``proceed`` does what
  ``dispatch.proceed_body`` does, specialised to *k* arguments and bound at C level
  (``MethodType`` over a tuple: cheaper to make per call than a closure).

Templates are compiled once per (k, sync/async, receiver) and shared by every layered
function of that shape: one code object each, registered as a dispatch (SD9).

Imports ``dispatch.py`` and ``state.py``.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import inspect
import threading
from collections.abc import Callable
from types import MethodType
from typing import Any

from cosleec.cop.dispatch import LayeredFunction
from cosleec.cop.state import RT, dyn_get, flush_if_outermost, register_dispatch_code

_TEMPLATE = """
def make(lf, RT, get, flush, M, MT):
    def proceed(st, /, *a, **k):  # dispatch.proceed_body for st = (next, the call's arguments)
        if a or k:
            return st[0]({receiver}*a, **k)
        return st[0]({st_args})

    {async_}def dispatch({slots}*_r, **_k):
        try:
            g, d = RT.state, get()
            memo = lf.memo
            chain = memo[2] if memo[0] is g and memo[1] is d else None
            if chain is None:
                chain = lf.resolve(g, d)
            call, head = chain
            if {usual}:
                if head is None:
                    return {await_}call({args})
                around, nxt = head
                return {await_}around({args}{comma}proceed=MT(proceed, (nxt, {args})))
            return {await_}call(*[a for a in ({args}{tuple_comma}) if a is not M], *_r, **_k)
        finally:
            if RT.queued:
                flush()

    return dispatch
"""

_MISSING = object()
_factories: dict[tuple[int, bool, bool], Callable[..., Callable[..., Any]]] = {}
_lock = threading.Lock()


def _factory(k: int, is_async: bool, receiver: bool) -> Callable[..., Callable[..., Any]]:
    """The compiled template for ``k`` slots (built on first use, then shared)."""
    key = (k, is_async, receiver)
    with _lock:
        make = _factories.get(key)
        if make is None:
            slots = [f"_a{i}" for i in range(k)]
            args = ", ".join(slots)
            src = _TEMPLATE.format(
                async_="async " if is_async else "",
                await_="await " if is_async else "",
                slots="".join(f"{s}=M, " for s in slots) + ("/, " if k else ""),
                usual=" and ".join([f"{s} is not M" for s in slots[-1:]] + ["not _r", "not _k"]),
                args=args,
                comma=", " if k else "",
                tuple_comma="," if k == 1 else "",
                receiver="st[1], " if receiver and k else "",
                st_args=", ".join(f"st[{i + 1}]" for i in range(k)),
            )
            ns: dict[str, Any] = {}
            exec(compile(src, f"<cosleec.cop fast dispatcher, {k} slots>", "exec"), ns)
            make = ns["make"]
            register_dispatch_code(_inner_code(make))
            _factories[key] = make
    return make


def _inner_code(make: Callable[..., Any]) -> Any:
    """The code object of the dispatcher a factory makes (the frame SD9 looks for)."""
    return next(c for c in make.__code__.co_consts if inspect.iscode(c) and c.co_name == "dispatch")


def required_positionals(fn: Callable[..., Any]) -> int:
    """How many positional arguments a call of ``fn`` must give (0 when its signature is unknown)."""
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


def fast_dispatcher(lf: LayeredFunction) -> Callable[..., Any]:
    """The generated dispatcher of ``lf``: same behaviour as ``reference_dispatcher(lf)``."""
    make = _factory(required_positionals(lf.base), lf.is_async, bool(lf.receiver))
    return make(lf, RT, dyn_get, flush_if_outermost, _MISSING, MethodType)
