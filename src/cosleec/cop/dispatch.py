"""Layered functions and their dispatch (cop-runtime.md §4).

A dispatch snapshots the composition once, selects at most one member per hedge group
(evaluating each predicate at most once), finds the chain for that configuration in a
bounded per-function cache, and runs it. ``proceed`` is passed to ``around`` partials as a
keyword argument and walks the frozen chain: there is no "current chain" in global state,
so exceptions cannot corrupt it (the contextpy3 defect) and async partials simply
``await proceed(...)``.

Speed: when nothing is active, no hook is installed and the function has no hedge group,
a layered function runs its base directly. Where the base's source is available, the
check is compiled into a copy of the base (a *dispatch prologue*), so that the common
case costs one ContextVar read and no extra call.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import inspect
import textwrap
import types
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from cosleec.cop import state
from cosleec.cop.errors import DefinitionError, HedgeEvaluationError
from cosleec.cop.layer import Layer, LayerGroup, policy_last
from cosleec.cop.state import EMPTY, RT, composition, dyn_get

KINDS = ("before", "around", "after")
_NO_CONTEXT = object()

RT.functions = weakref.WeakSet()


@dataclass(frozen=True)
class DispatchRecord:
    """What one dispatch decided (SD16): the input of tracing, audit logs and explanations."""

    function: str
    composition: tuple[str, ...]
    predicates: dict[str, dict[str, bool | None]]
    selected: dict[str, str | None]
    snapshot_id: object
    undetermined: bool = False
    error: str | None = None
    forced: dict[str, str] = field(default_factory=dict)


class _Context:
    """The context snapshot predicates read when a function has no context provider."""

    from contextvars import ContextVar as _CV

    var: _CV[object] = _CV("cosleec.cop.context", default=_NO_CONTEXT)


def current_context() -> Any:
    ctx = _Context.var.get()
    if ctx is _NO_CONTEXT:
        raise LookupError("no context snapshot: use `with using_context(snapshot):` or a context= provider")
    return ctx


class using_context:
    """``with using_context(snapshot):`` -- the snapshot hedge predicates read in this extent."""

    def __init__(self, snapshot: Any) -> None:
        self.snapshot = snapshot

    def __enter__(self) -> Any:
        self._token = _Context.var.set(self.snapshot)
        return self.snapshot

    def __exit__(self, *exc: object) -> None:
        _Context.var.reset(self._token)


class LayeredFunction:
    """The dispatch machinery of one layered function (the public callable wraps it)."""

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
        self.name = getattr(base, "__qualname__", repr(base))
        self.is_async = inspect.iscoroutinefunction(base)
        self.receiver = 1 if receiver else 0
        self.groups: tuple[LayerGroup, ...] = tuple(hedges)
        for g in self.groups:
            if g.policy is None:
                raise DefinitionError(f"group {g.name!r} has no selection policy; hedge groups need one")
            owner = getattr(g, "_cop_function", None)
            if owner is not None and owner() is not None:
                raise DefinitionError(f"hedge group {g.name!r} already belongs to {owner().name!r}")
            g._cop_function = weakref.ref(self)  # type: ignore[attr-defined]
        self._group_set = frozenset(self.groups)
        self.context = context
        self.partials: dict[Layer, dict[str, Callable[..., Any]]] = {}
        self.cache: dict[tuple[Any, ...], Callable[..., Any]] = {}
        self.max_chains = max_chains
        self.idle = True
        self.plain = True  # no hedge group and no dispatch hook: the memo may be used
        self.memo: tuple[Any, Any, Any] = (None, None, None)
        self.refresh()
        RT.functions.add(self)
        self.dispatch = self._make_dispatch()
        state.DISPATCH_CODES.add(self.dispatch.__code__)

    def refresh(self) -> None:
        """Recompute whether the base may run directly (called when global state changes)."""
        self.idle = RT.idle and not self.groups
        self.plain = not self.groups and not RT.dispatch_hooks
        self.memo = (None, None, None)

    # ------------------------------------------------------------------ registration
    def add_partial(self, layer: Layer, kind: str, fn: Callable[..., Any]) -> None:
        if not isinstance(layer, Layer):
            raise DefinitionError(f"a partial needs a Layer, got {layer!r}")
        if kind not in KINDS:
            raise DefinitionError(f"unknown partial kind {kind!r}")
        slot = self.partials.setdefault(layer, {})
        if kind in slot:
            raise DefinitionError(f"{layer.name!r} already has an {kind!r} partial for {self.name}")
        if inspect.iscoroutinefunction(fn) != self.is_async:
            raise DefinitionError(
                f"{'a synchronous' if self.is_async else 'an async'} partial for "
                f"{'async ' if self.is_async else ''}function {self.name}: partials must match the base"
            )
        group = layer.group
        if group is not None and group.policy is not None and group not in self._group_set:
            raise DefinitionError(
                f"{layer.name!r} is a member of hedge group {group.name!r}, which is not attached to {self.name}"
            )
        slot[kind] = fn
        self.cache.clear()  # a registration invalidates every chain (A8)
        self.memo = (None, None, None)

    def decorator(self, kind: str, layer: Layer) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
        def register(fn: Callable[..., Any]) -> Callable[..., Any]:
            self.add_partial(layer, kind, fn)
            return fn

        return register

    # ------------------------------------------------------------------ dispatch
    def _make_dispatch(self) -> Callable[..., Any]:
        """The dispatcher: generated with the base's exact signature where possible."""
        gen = _generated_dispatch(self)
        if gen is not None:
            return gen
        lf = self

        if self.is_async:

            async def dispatch_async(*args: Any, **kwargs: Any) -> Any:
                around, nxt, _fwd = lf.head(RT.state, dyn_get())
                try:
                    if around is None:
                        return await nxt(*args, **kwargs)
                    return await around(*args, proceed=_proceed(nxt, args, kwargs, lf.receiver), **kwargs)
                finally:
                    if RT.queued:
                        state.flush_if_outermost()

            return dispatch_async

        def dispatch(*args: Any, **kwargs: Any) -> Any:
            around, nxt, _fwd = lf.head(RT.state, dyn_get())
            try:
                if around is None:
                    return nxt(*args, **kwargs)
                return around(*args, proceed=_proceed(nxt, args, kwargs, lf.receiver), **kwargs)
            finally:
                if RT.queued:
                    state.flush_if_outermost()

        return dispatch

    def head(self, g: state.GlobalState, d: state.Frame) -> tuple[Any, Any, bool]:
        """The outermost around partial of the chain for this configuration, and what follows.

        ``(None, chain, False)`` when the chain does not start with a pure around partial.
        Remembers the last configuration: repeated calls in one configuration hit the memo.
        """
        memo = self.memo
        if memo[0] is g and memo[1] is d:
            return memo[2]  # type: ignore[no-any-return]
        chain = self.chain_for(g, d)
        h = getattr(chain, "_cop_head", None) or (None, chain, False)
        if self.plain:
            self.memo = (g, d, h)
        return h

    def chain_for(self, g: state.GlobalState, d: state.Frame) -> Callable[..., Any]:
        comp = composition(g, d)
        if self.groups:
            selected, record = self.select(comp, None, RT.dispatch_hooks)
            key: tuple[Any, ...] = (comp, selected)
        else:
            selected, record = (), None
            key = (comp,)
        chain = self.cache.get(key)
        if chain is None:
            chain = self._build(comp, selected)
            if len(self.cache) >= self.max_chains:
                del self.cache[next(iter(self.cache))]  # the oldest entry goes (bounded, H48)
            self.cache[key] = chain
        if RT.dispatch_hooks:
            if record is None:
                record = DispatchRecord(self.name, tuple(la.name for la in comp), {}, {}, None)
            for hook in RT.dispatch_hooks:
                hook(record)
        return chain

    def snapshot(self) -> Any:
        return self.context() if self.context is not None else current_context()

    def select(
        self, comp: tuple[Layer, ...], ctx: Any, hooks: tuple[Any, ...]
    ) -> tuple[tuple[Layer | None, ...], DispatchRecord | None]:
        """At most one member per hedge group (SD5, SD6, SD14), predicates read at most once."""
        if not hooks:  # nobody records this dispatch: no bookkeeping beyond the choice itself
            return self._select_fast(comp, ctx), None
        selected: list[Layer | None] = []
        preds: dict[str, dict[str, bool | None]] = {}
        chosen: dict[str, str | None] = {}
        forced_names: dict[str, str] = {}
        have_ctx = ctx is not None
        undetermined = False
        error: str | None = None
        for grp in self.groups:
            forced = [la for la in comp if la.group is grp]
            if forced:
                selected.append(forced[0])
                forced_names[grp.name] = forced[0].name
                chosen[grp.name] = forced[0].name
                continue
            if not have_ctx:
                ctx, have_ctx = self.snapshot(), True
            values: dict[str, bool | None] = {}
            try:
                pick = self._pick(grp, ctx, values, bool(hooks))
            except HedgeEvaluationError as e:
                if grp.on_error == "raise":
                    if hooks:
                        rec = DispatchRecord(
                            self.name,
                            tuple(la.name for la in comp),
                            {**preds, grp.name: values},
                            {**chosen, grp.name: None},
                            _snap_id(ctx),
                            True,
                            str(e),
                            forced_names,
                        )
                        for hook in hooks:
                            hook(rec)
                    raise
                undetermined, error = True, str(e)
                pick = (
                    None
                    if grp.on_error == "default"
                    else next(m for m in grp.members if m.name == grp.on_error)
                )
            selected.append(pick)
            preds[grp.name] = values
            chosen[grp.name] = pick.name if pick is not None else None
        record = None
        if hooks:
            record = DispatchRecord(
                self.name,
                tuple(la.name for la in comp),
                preds,
                chosen,
                _snap_id(ctx),
                undetermined,
                error,
                forced_names,
            )
        return tuple(selected), record

    def _select_fast(self, comp: tuple[Layer, ...], ctx: Any) -> tuple[Layer | None, ...]:
        out: list[Layer | None] = []
        have_ctx = ctx is not None
        scratch: dict[str, bool | None] = {}
        for grp in self.groups:
            forced = None
            for la in comp:
                if la.group is grp:
                    forced = la
                    break
            if forced is not None:
                out.append(forced)
                continue
            if not have_ctx:
                ctx, have_ctx = self.snapshot(), True
            try:
                out.append(self._pick(grp, ctx, scratch, False))
            except HedgeEvaluationError:
                if grp.on_error == "raise":
                    raise
                out.append(
                    None
                    if grp.on_error == "default"
                    else next(m for m in grp.members if m.name == grp.on_error)
                )
        return tuple(out)

    @staticmethod
    def _pick(grp: LayerGroup, ctx: Any, values: dict[str, bool | None], record_all: bool) -> Layer | None:
        members = grp.members
        policy = grp.policy
        assert policy is not None
        if grp.selector is not None:
            try:
                idx = grp.selector(ctx)
            except Exception as e:
                raise HedgeEvaluationError(grp.name, "<selector>", e) from e
            return members[idx] if idx is not None else None
        if policy is policy_last and not record_all:  # stop at the first that holds: same result
            for m in reversed(members):
                try:
                    held = m.predicate(ctx)  # type: ignore[misc]
                except Exception as e:
                    values[m.name] = None
                    raise HedgeEvaluationError(grp.name, m.name, e) from e
                if held:
                    return m
            return None

        def value(m: Layer) -> bool:
            try:
                v = bool(m.predicate(ctx))  # type: ignore[misc]
            except Exception as e:
                values[m.name] = None
                raise HedgeEvaluationError(grp.name, m.name, e) from e
            values[m.name] = v
            return v

        idx = policy([value(m) for m in members])
        return members[idx] if idx is not None else None

    def _build(self, comp: tuple[Layer, ...], selected: tuple[Layer | None, ...]) -> Callable[..., Any]:
        layers = [la for la in comp if la.group not in self._group_set]
        layers += [la for la in selected if la is not None]
        nxt: Callable[..., Any] = self.base
        for la in reversed(layers):
            parts = self.partials.get(la)
            if parts:
                nxt = (_async_step if self.is_async else _step)(parts, nxt, self.receiver)
        return nxt

    def layers_in_chain(self, comp: tuple[Layer, ...], selected: tuple[Layer | None, ...]) -> list[Layer]:
        layers = [la for la in comp if la.group not in self._group_set]
        layers += [la for la in selected if la is not None]
        return [la for la in layers if la in self.partials]


def _snap_id(ctx: Any) -> object:
    if ctx is None:
        return None
    return getattr(ctx, "id", None) or id(ctx)


def _step(parts: dict[str, Callable[..., Any]], nxt: Callable[..., Any], recv: int) -> Callable[..., Any]:
    before, around, after = parts.get("before"), parts.get("around"), parts.get("after")
    if around is not None and before is None and after is None:
        fwd = forwards_only(around)

        def around_step(*args: Any, **kwargs: Any) -> Any:
            proceed = functools.partial(nxt, *args, **kwargs) if fwd else _proceed(nxt, args, kwargs, recv)
            return around(*args, proceed=proceed, **kwargs)

        around_step._cop_head = (around, nxt, fwd)  # type: ignore[attr-defined]
        return around_step

    def step(*args: Any, **kwargs: Any) -> Any:
        if before is not None:
            before(*args, **kwargs)
        if around is not None:

            def proceed(*a: Any, **k: Any) -> Any:
                if a or k:
                    return nxt(*args[:recv], *a, **k)
                return nxt(*args, **kwargs)

            result = around(*args, proceed=proceed, **kwargs)
        else:
            result = nxt(*args, **kwargs)
        if after is not None:
            result = after(*args, result=result, **kwargs)
        return result

    return step


def _proceed(nxt: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any], recv: int) -> Any:
    """``proceed`` for one call: no arguments forward the call's own; arguments replace them (SD3)."""

    def proceed(*a: Any, **k: Any) -> Any:
        if a or k:
            return nxt(*args[:recv], *a, **k)
        return nxt(*args, **kwargs)

    return proceed


_forward_cache: dict[Any, bool] = {}


def forwards_only(fn: Callable[..., Any]) -> bool:
    """Does ``fn`` call ``proceed`` only without arguments, and never let it escape?

    Then ``proceed`` can be a C-level ``functools.partial`` of the next step: no Python
    frame of its own. Decided from the partial's source; unknown means no.
    """
    code = getattr(fn, "__code__", None)
    if code is None:
        return False
    hit = _forward_cache.get(code)
    if hit is not None:
        return hit
    ok = False
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
        fdef = tree.body[0]
        if isinstance(fdef, ast.FunctionDef | ast.AsyncFunctionDef):
            ok = True
            calls = {id(n.func) for n in ast.walk(fdef) if isinstance(n, ast.Call)}
            for n in ast.walk(fdef):
                if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "proceed":
                    ok = ok and not n.args and not n.keywords
                elif isinstance(n, ast.Name) and n.id == "proceed" and id(n) not in calls:
                    ok = False  # proceed escapes (stored, passed on, returned): keep full semantics
    except (OSError, TypeError, SyntaxError, IndentationError, IndexError):
        ok = False
    _forward_cache[code] = ok
    return ok


def _async_step(
    parts: dict[str, Callable[..., Any]], nxt: Callable[..., Any], recv: int
) -> Callable[..., Any]:
    before, around, after = parts.get("before"), parts.get("around"), parts.get("after")

    async def step(*args: Any, **kwargs: Any) -> Any:
        if before is not None:
            await before(*args, **kwargs)
        if around is not None:

            async def proceed(*a: Any, **k: Any) -> Any:
                if a or k:
                    return await nxt(*args[:recv], *a, **k)
                return await nxt(*args, **kwargs)

            result = await around(*args, proceed=proceed, **kwargs)
        else:
            result = await nxt(*args, **kwargs)
        if after is not None:
            result = await after(*args, result=result, **kwargs)
        return result

    return step


# ---------------------------------------------------------------------- the public wrapper


def _call_args(sig: inspect.Signature) -> str:
    """Source text that passes a function's own parameters on: ``a, b, *args, k=k, **kw``."""
    out = []
    for p in sig.parameters.values():
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD):
            out.append(p.name)
        elif p.kind is p.VAR_POSITIONAL:
            out.append("*" + p.name)
        elif p.kind is p.KEYWORD_ONLY:
            out.append(f"{p.name}={p.name}")
        else:
            out.append("**" + p.name)
    return ", ".join(out)


def _generated_dispatch(lf: LayeredFunction) -> Callable[..., Any] | None:
    """A dispatcher with the base's exact signature: no ``*args`` repacking on the hot path."""
    try:
        sig = inspect.signature(lf.base)
    except (TypeError, ValueError):
        return None
    params = []
    for p in sig.parameters.values():
        if p.kind is p.VAR_POSITIONAL:
            params.append("*" + p.name)
        elif p.kind is p.VAR_KEYWORD:
            params.append("**" + p.name)
        elif p.kind is p.KEYWORD_ONLY:
            if not any(x.startswith("*") for x in params):
                params.append("*")
            params.append(p.name)
        else:
            params.append(p.name)
            if p.kind is p.POSITIONAL_ONLY and not any(
                q.kind is q.POSITIONAL_ONLY for q in list(sig.parameters.values())[len(params) :]
            ):
                params.append("/")
    names = {p.name for p in sig.parameters.values()}
    if any(n.startswith("_cop_") for n in names) or names & {
        "_F",
        "_RT",
        "_get",
        "_flush",
        "_partial",
        "_MT",
        "proceed",
        "memo",
        "around",
        "nxt",
        "fwd",
    }:
        return None
    call = _call_args(sig)
    recv = next(iter(sig.parameters), None) if lf.receiver else None
    aw = "await " if lf.is_async else ""
    positional = [p.name for p in sig.parameters.values()]
    simple = 0 < len(positional) <= 3 and all(
        p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in sig.parameters.values()
    )
    sep = ", " if call else ""
    if simple:
        # C-level bound callables: MethodType(f, a)() == f(a), nested for more arguments;
        # MethodType refuses None as its object, so those calls use functools.partial.
        bound = "nxt"
        for a in positional:
            bound = f"_MT({bound}, {a})"
        nones = " or ".join(f"{a} is None" for a in positional)
        fwd_proceed = f"_partial(nxt, {call}) if {nones} else {bound}"
    else:
        fwd_proceed = f"_partial(nxt{sep}{call})"
    src = f"""
{"async " if lf.is_async else ""}def dispatch({", ".join(params)}):
    memo = _F.memo
    if memo[0] is _RT.state and memo[1] is _get():
        around, nxt, fwd = memo[2]
    else:
        around, nxt, fwd = _F.head(_RT.state, _get())
    try:
        if around is None:
            return {aw}nxt({call})
        if fwd:
            return {aw}around({call}{sep}proceed={fwd_proceed})
        {"async " if lf.is_async else ""}def _cop_proceed(*_cop_a, **_cop_k):
            if _cop_a or _cop_k:
                return {aw}nxt({recv + ", " if recv else ""}*_cop_a, **_cop_k)
            return {aw}nxt({call})
        return {aw}around({call}{sep}proceed=_cop_proceed)
    finally:
        if _RT.queued:
            _flush()
"""
    ns: dict[str, Any] = {
        "_F": lf,
        "_RT": RT,
        "_get": dyn_get,
        "_flush": state.flush_if_outermost,
        "_partial": functools.partial,
        "_MT": types.MethodType,
    }
    try:
        exec(compile(src, f"<cosleec.cop dispatch of {lf.name}>", "exec"), ns)
    except SyntaxError:
        return None
    fn: Callable[..., Any] = ns["dispatch"]
    return fn


def _compile_prologue(fn: Callable[..., Any], lf: LayeredFunction) -> Callable[..., Any] | None:
    """A copy of ``fn`` with the dispatch compiled in (cop-runtime.md §7).

    The copy's first statement checks "nothing active": then the base body runs in place,
    with no extra call. Otherwise, when the last configuration's chain starts with a
    forwarding-only ``around`` partial (the memo of :meth:`LayeredFunction.head`), that
    partial is called right here, ``proceed`` bound at C level; anything else goes to the
    dispatcher. The body runs inside ``try/finally`` that applies global changes deferred
    during it (SD9) -- free in CPython 3.11 unless something was deferred.
    """
    code = getattr(fn, "__code__", None)
    if code is None or code.co_freevars or inspect.isgeneratorfunction(fn) or inspect.isasyncgenfunction(fn):
        return None
    try:
        src = textwrap.dedent(inspect.getsource(fn))
        tree = ast.parse(src)
        ast.increment_lineno(tree, code.co_firstlineno - 1)  # tracebacks keep the real line numbers
    except (OSError, TypeError, SyntaxError, IndentationError):
        return None
    if len(tree.body) != 1 or not isinstance(tree.body[0], ast.FunctionDef | ast.AsyncFunctionDef):
        return None
    fdef = tree.body[0]
    if fdef.name != fn.__name__:
        return None
    if any(isinstance(n, ast.Name) and n.id.startswith("_cop_") for n in ast.walk(fdef)):
        return None
    sig = inspect.signature(fn)
    fdef.decorator_list = []
    aw = "await " if lf.is_async else ""
    args = _call_args(sig)
    params = list(sig.parameters.values())
    simple = 0 < len(params) <= 3 and all(
        p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params
    )
    inline = ""
    if simple:
        bound = "_cop_n"
        for p in params:
            bound = f"_cop_MT({bound}, {p.name})"
        not_none = " and ".join(f"{p.name} is not None" for p in params)
        inline = f"""
        _cop_m = _cop_F.memo
        if _cop_m[0] is _cop_RT.state and _cop_m[1] is _cop_d:
            _cop_a, _cop_n, _cop_f = _cop_m[2]
            if _cop_a is not None and _cop_f and {not_none}:
                return {aw}_cop_a({args}, proceed={bound})"""
    # the whole function -- fast check, inline head, dispatcher call, body -- is one dispatch:
    # global changes requested anywhere inside it are applied when it ends (SD9)
    src_new = f"""
_cop_d = _cop_get()
try:
    if _cop_d is not _cop_E or not _cop_F.idle:{inline}
        return {aw}_cop_D({args})
    pass
finally:
    if _cop_RT.queued:
        _cop_flush()
"""
    first, guard = ast.parse(textwrap.dedent(src_new)).body
    for node in (first, guard):
        ast.increment_lineno(node, fdef.lineno - 1)
    body = fdef.body
    doc = (
        body[:1] if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) else []
    )
    assert isinstance(guard, ast.Try)
    guard.body = [guard.body[0], *(body[len(doc) :] or [ast.Pass()])]
    fdef.body = [*doc, first, guard]
    names = ("_cop_get", "_cop_E", "_cop_F", "_cop_D", "_cop_RT", "_cop_MT", "_cop_flush")
    factory = ast.FunctionDef(
        name="__cop_factory__",
        args=ast.arguments(
            posonlyargs=[], args=[ast.arg(n) for n in names], kwonlyargs=[], kw_defaults=[], defaults=[]
        ),
        body=[fdef, ast.Return(ast.Name(fdef.name, ast.Load()))],
        decorator_list=[],
    )
    module = ast.Module(body=[factory], type_ignores=[])
    ast.copy_location(factory, fdef)
    ast.fix_missing_locations(module)
    ns: dict[str, Any] = {}
    try:
        filename = inspect.getsourcefile(fn) or code.co_filename
        exec(compile(module, filename, "exec"), fn.__globals__, ns)
        new = ns["__cop_factory__"](
            dyn_get, EMPTY, lf, lf.dispatch, RT, types.MethodType, state.flush_if_outermost
        )
    except Exception:
        return None
    new.__defaults__ = fn.__defaults__
    new.__kwdefaults__ = fn.__kwdefaults__
    new.__doc__ = fn.__doc__
    new.__qualname__ = fn.__qualname__
    new.__module__ = fn.__module__
    new.__dict__.update(fn.__dict__)
    state.DISPATCH_CODES.add(new.__code__)  # its frames count as a running dispatch (SD9)
    return new  # type: ignore[no-any-return]


def _closure_wrapper(fn: Callable[..., Any], lf: LayeredFunction) -> Callable[..., Any]:
    if lf.is_async:

        async def awrapper(*args: Any, **kwargs: Any) -> Any:
            if dyn_get() is EMPTY and lf.idle:
                return await fn(*args, **kwargs)
            return await lf.dispatch(*args, **kwargs)

        return awrapper

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        if dyn_get() is EMPTY and lf.idle:
            return fn(*args, **kwargs)
        return lf.dispatch(*args, **kwargs)

    return wrapper


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


def _decorate(
    fn: Callable[..., Any],
    hedges: Sequence[LayerGroup],
    context: Callable[[], Any] | None,
    method: bool | None,
    max_chains: int,
    compile_prologue: bool,
) -> Any:
    wrap_kind: type | None = None
    if isinstance(fn, staticmethod | classmethod):
        wrap_kind = type(fn)
        fn = fn.__func__
        method = wrap_kind is classmethod  # type: ignore[comparison-overlap]
    if not callable(fn):
        raise DefinitionError(f"@layered needs a function, got {fn!r}")
    receiver = _is_method(fn) if method is None else method
    lf = LayeredFunction(fn, hedges=hedges, context=context, receiver=receiver, max_chains=max_chains)
    public = (_compile_prologue(fn, lf) if compile_prologue else None) or _closure_wrapper(fn, lf)
    for attr in ("__module__", "__name__", "__qualname__", "__doc__"):
        with contextlib.suppress(AttributeError, TypeError):
            setattr(public, attr, getattr(fn, attr))
    public.__wrapped__ = fn  # type: ignore[attr-defined]
    public.layered = lf  # type: ignore[attr-defined]
    public.variant = lambda layer: lf.decorator("around", layer)  # type: ignore[attr-defined]
    public.around = public.variant  # type: ignore[attr-defined]
    public.before = lambda layer: lf.decorator("before", layer)  # type: ignore[attr-defined]
    public.after = lambda layer: lf.decorator("after", layer)  # type: ignore[attr-defined]
    if wrap_kind is not None:
        wrapped = _StaticLayered(public) if wrap_kind is staticmethod else _ClassLayered(public)
        return wrapped
    return public


class _StaticLayered(staticmethod):  # type: ignore[type-arg]
    """A layered staticmethod that still offers ``.variant``/``.before``/``.after`` in the class body."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self.__func__, name)


class _ClassLayered(classmethod):  # type: ignore[type-arg]
    def __getattr__(self, name: str) -> Any:
        return getattr(self.__func__, name)


def layered(
    fn: Callable[..., Any] | None = None,
    *,
    hedges: LayerGroup | Sequence[LayerGroup] = (),
    context: Callable[[], Any] | None = None,
    method: bool | None = None,
    max_chains: int = 256,
    compile_prologue: bool = True,
) -> Any:
    """Make a function or method layered. Its body is the base implementation.

    ``hedges``: hedge groups whose selected member runs innermost, around the base.
    ``context``: returns the snapshot predicates read, once per dispatch (default: the
    snapshot of ``using_context``). ``method``: whether the first argument is a receiver
    (default: detected). The result has ``.variant(layer)`` (an ``around`` partial receiving
    ``proceed=``), ``.before(layer)`` and ``.after(layer)`` (receiving ``result=``).
    """
    groups = (hedges,) if isinstance(hedges, LayerGroup) else tuple(hedges)

    def deco(f: Callable[..., Any]) -> Any:
        return _decorate(f, groups, context, method, max_chains, compile_prologue)

    return deco(fn) if fn is not None else deco


def partial(
    target: Any, layer: Layer, kind: str = "around"
) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register a partial on ``target``; a layer cannot introduce a function (A10)."""
    lf = getattr(target, "layered", None)
    if not isinstance(lf, LayeredFunction):
        raise DefinitionError(f"{getattr(target, '__qualname__', target)!r} is not a layered function")
    return lf.decorator(kind, layer)


def on_dispatch(hook: Callable[[DispatchRecord], None]) -> Callable[[], None]:
    """Call ``hook(record)`` after every dispatch decision; returns a function that removes it."""
    with state._lock:
        RT.dispatch_hooks = (*RT.dispatch_hooks, hook)
        state._refresh_idle(force=True)

    def remove() -> None:
        with state._lock:
            RT.dispatch_hooks = tuple(h for h in RT.dispatch_hooks if h is not hook)
            state._refresh_idle(force=True)

    return remove
