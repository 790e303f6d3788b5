"""Both dispatchers held equal to a plain-Python model of layered dispatch, on random programs.

The model (``Oracle``) is written here from docs/reference/cop-runtime.md alone: a
composition is the global layers plus the scoped ones, masked ones removed, outermost
first by priority then recency (SD4, SD7, SD13); a chain runs before/around/after per layer
(A6); ``proceed()`` forwards the call's arguments, ``proceed(...)`` replaces them, the
receiver kept (SD3); a kept ``proceed`` runs its frozen chain later (SD2); global
activations requested inside a dispatch wait for the outermost one to end, raising or not
(SD9). Hypothesis draws the layers' priorities and partials, nested ``with`` blocks, global
(de)activations, call shapes (the fast path's usual shape and the general one), partials
that nest calls under a deactivation of their own layer, raise, catch, keep ``proceed`` or
activate globally mid-call. Every shape of base the fast path generates differently runs:
no required positional, one, two, and methods (a receiver alone, a receiver and one more).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.cop import (
    ActivationError,
    Layer,
    activate,
    activate_globally,
    deactivate,
    deactivate_globally,
    global_state,
    layered,
    restore_globally,
)

N = 4
KINDS = ["none", "pass", "args", "skip", "raise", "catch", "nest", "global", "keep", "ba", "bab"]
SHAPES = ["k0", "k1", "k2", "m1", "m2"]


class Boom(Exception):
    pass


@dataclass
class Env:
    """What a partial may do besides ``proceed``: call the function again, mask its own layer
    for a block, activate a layer globally -- on the real runtime or on the model."""

    call: Callable[[int, int], Any]
    without: Callable[[int], contextlib.AbstractContextManager[Any]]
    gact: Callable[[int], None]
    log: list[Any] = field(default_factory=list)
    kept: list[Callable[..., Any]] = field(default_factory=list)
    depth: int = 0


def partials(kind: str, i: int, env: Env, recv: int) -> dict[str, Callable[..., Any]]:
    """The partials of layer ``i`` for ``kind``, logging to ``env`` (shared by runtime and model)."""

    def note(tag: str, a: tuple[Any, ...], k: dict[str, Any]) -> None:
        env.log.append((tag, i, a[recv:], sorted(k.items())))

    def around(*a: Any, proceed: Callable[..., Any], **k: Any) -> Any:
        note(kind, a, k)
        if kind == "args":
            return proceed(*[v + 100 for v in a[recv:]], **{n: v + 100 for n, v in k.items()})
        if kind == "skip":
            return ("skip", i)
        if kind == "raise":
            raise Boom(i)
        if kind == "catch":
            try:
                return proceed()
            except Boom as e:
                return ("caught", i, e.args)
        if kind == "nest" and env.depth < 2:
            env.depth += 1
            try:
                with env.without(i):
                    inner = env.call(1000 * env.depth, 7)
            finally:
                env.depth -= 1
            return (inner, proceed())
        if kind == "global":
            env.gact((i + 1) % N)
        if kind == "keep":
            env.kept.append(proceed)
        return proceed()

    def before(*a: Any, **k: Any) -> None:
        note("before", a, k)

    def after(*a: Any, result: Any, **k: Any) -> Any:
        note("after", a, k)
        return ("after", i, result)

    if kind == "none":
        return {}
    if kind == "ba":
        return {"before": before, "after": after}
    if kind == "bab":
        return {"before": before, "around": around, "after": after}
    return {"around": around}


# ---------------------------------------------------------------- the model


class Oracle:
    """Layered dispatch as the reference document defines it, with no cache and no memo."""

    def __init__(self, prios: list[int], parts: list[dict[str, Callable[..., Any]]], base: Any, recv: int):
        self.prios, self.parts, self.base, self.recv = prios, parts, base, recv
        self.stamp = 0
        self.glob: dict[int, int] = {}  # layer -> stamp of its activation
        self.counts: dict[int, int] = {}
        self.scopes: list[tuple[dict[int, int], frozenset[int]]] = [({}, frozenset())]  # (added, masked)
        self.in_dispatch = 0
        self.pending: list[tuple[str, int]] = []

    def composition(self) -> list[int]:
        added, masked = self.scopes[-1]
        stamps = {la: s for la, s in self.glob.items() if la not in masked}
        for la, s in added.items():
            stamps[la] = max(s, stamps.get(la, 0))
        return sorted(stamps, key=lambda la: (-self.prios[la], -stamps[la]))

    @contextlib.contextmanager
    def scope(self, mode: str, layers: list[int]) -> Iterator[None]:
        added, masked = self.scopes[-1]
        added, masked = dict(added), set(masked)
        for la in layers:
            if mode == "activate":
                if la in self._comp(added, masked):
                    continue  # re-activation: a no-op that keeps the position (SD4)
                masked.discard(la)
                if la not in added:
                    self.stamp += 1
                    added[la] = self.stamp
            else:
                added.pop(la, None)
                masked.add(la)
        self.scopes.append((added, frozenset(masked)))
        try:
            yield
        finally:
            self.scopes.pop()

    def _comp(self, added: dict[int, int], masked: set[int]) -> set[int]:
        return {la for la in self.glob if la not in masked} | set(added)

    def global_op(self, op: str, la: int) -> None:
        if self.in_dispatch:
            self.pending.append((op, la))  # SD9
            return
        self._apply(op, la)

    def _apply(self, op: str, la: int) -> None:
        n = self.counts.get(la, 0)
        if op == "activate":
            if n == 0:
                self.stamp += 1
                self.glob[la] = self.stamp
            self.counts[la] = n + 1
        elif n == 0:
            raise ActivationError(la)
        elif n == 1:
            del self.counts[la], self.glob[la]
        else:
            self.counts[la] = n - 1

    def dispatch(self, *args: Any, **kwargs: Any) -> Any:
        chain = [la for la in self.composition() if self.parts[la]]  # read once (SD2)
        self.in_dispatch += 1
        try:
            return self.run(chain, args, kwargs)
        finally:
            self.in_dispatch -= 1
            if not self.in_dispatch:
                queued, self.pending = self.pending, []
                for op, la in queued:
                    self._apply(op, la)

    def run(self, chain: list[int], args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
        if not chain:
            return self.base(*args, **kwargs)
        parts, rest = self.parts[chain[0]], chain[1:]

        def proceed(*a: Any, **k: Any) -> Any:
            if a or k:
                return self.run(rest, (*args[: self.recv], *a), k)
            return self.run(rest, args, kwargs)

        if "before" in parts:
            parts["before"](*args, **kwargs)
        if "around" in parts:
            result = parts["around"](*args, proceed=proceed, **kwargs)
        else:
            result = proceed()
        if "after" in parts:
            result = parts["after"](*args, result=result, **kwargs)
        return result


# ---------------------------------------------------------------- programs

Step = tuple[Any, ...]
calls = st.tuples(
    st.just("call"), st.sampled_from(["usual", "pos", "kw"]), st.integers(0, 9), st.integers(0, 9)
)
globals_ = st.tuples(st.sampled_from(["gact", "gdeact"]), st.integers(0, N - 1))
layer_lists = st.lists(st.integers(0, N - 1), min_size=1, max_size=3)
programs = st.recursive(
    st.lists(st.one_of(calls, globals_), max_size=4),
    lambda inner: st.lists(
        st.one_of(
            calls,
            globals_,
            st.tuples(st.just("with"), st.sampled_from(["activate", "deactivate"]), layer_lists, inner),
        ),
        max_size=4,
    ),
    max_leaves=12,
)


def make_base(shape: str, log: list[Any]) -> tuple[Any, int, Callable[[Any, str, int, int], Any]]:
    """A base of ``shape`` (unlayered), its receiver count, and how a call of each shape is made."""

    def body(x: int, y: int) -> Any:
        log.append(("base", x, y))
        return ("base", x, y)

    if shape == "k0":

        def f0(x: int = 0, y: int = 0) -> Any:
            return body(x, y)

        return f0, 0, lambda fn, how, x, y: fn() if how == "usual" else _plain(fn, how, x, y)
    if shape == "k1":

        def f1(x: int, y: int = 0) -> Any:
            return body(x, y)

        return f1, 0, lambda fn, how, x, y: fn(x) if how == "usual" else _plain(fn, how, x, y)
    if shape == "k2":

        def f2(x: int, y: int) -> Any:
            return body(x, y)

        return f2, 0, _plain
    if shape == "m1":

        def m1(self: Any, x: int = 0, y: int = 0) -> Any:
            return body(x, y)

        return m1, 1, lambda fn, how, x, y: fn(OBJ) if how == "usual" else _plain(fn, how, x, y, OBJ)

    def m2(self: Any, x: int, y: int = 0) -> Any:
        return body(x, y)

    return m2, 1, lambda fn, how, x, y: fn(OBJ, x) if how == "usual" else _plain(fn, how, x, y, OBJ)


OBJ = object()


def _plain(fn: Any, how: str, x: int, y: int, *recv: Any) -> Any:
    return fn(*recv, x, y) if how in ("pos", "usual") else fn(*recv, x=x, y=y)


def run_program(program: list[Step], env: Env, call: Callable[[str, int, int], Any], ops: Any) -> None:
    """Interpret ``program`` against the real runtime or the model (``ops``), logging outcomes."""
    for step in program:
        try:
            if step[0] == "call":
                env.log.append(("=", call(step[1], step[2], step[3])))
            elif step[0] == "with":
                with ops.scope(step[1], step[2]):
                    run_program(step[3], env, call, ops)
            else:
                ops.global_op("activate" if step[0] == "gact" else "deactivate", step[1])
        except Boom as e:
            env.log.append(("raised", e.args))
        except ActivationError:
            env.log.append(("activation error",))


class RealOps:
    def __init__(self, layers: list[Layer]) -> None:
        self.layers = layers

    def scope(self, mode: str, idx: list[int]) -> contextlib.AbstractContextManager[Any]:
        las = [self.layers[i] for i in idx]
        return activate(*las) if mode == "activate" else deactivate(*las)

    def global_op(self, op: str, i: int) -> None:
        (activate_globally if op == "activate" else deactivate_globally)(self.layers[i])


def outcome_of_runtime(
    fast: bool, shape: str, prios: list[int], kinds: list[str], program: list[Step]
) -> list[Any]:
    layers = [Layer(f"P{i}", priority=p) for i, p in enumerate(prios)]
    ops = RealOps(layers)
    env = Env(
        call=lambda x, y: None,
        without=lambda i: deactivate(layers[i]),
        gact=lambda i: ops.global_op("activate", i),
    )
    base, recv, make_call = make_base(shape, env.log)
    fn = layered(base, method=bool(recv), fast=fast)
    for i, kind in enumerate(kinds):
        for part, p in partials(kind, i, env, recv).items():
            getattr(fn, part)(layers[i])(p)
    env.call = lambda x, y: make_call(fn, "usual", x, y)
    saved = global_state()
    try:
        run_program(program, env, lambda how, x, y: make_call(fn, how, x, y), ops)
        finish(env)
    finally:
        restore_globally(saved)
    return env.log


def outcome_of_model(shape: str, prios: list[int], kinds: list[str], program: list[Step]) -> list[Any]:
    env = Env(call=lambda x, y: None, without=lambda i: contextlib.nullcontext(), gact=lambda i: None)
    base, recv, make_call = make_base(shape, env.log)
    oracle = Oracle(prios, [partials(k, i, env, recv) for i, k in enumerate(kinds)], base, recv)
    env.without = lambda i: oracle.scope("deactivate", [i])
    env.gact = lambda i: oracle.global_op("activate", i)
    env.call = lambda x, y: make_call(oracle.dispatch, "usual", x, y)
    run_program(program, env, lambda how, x, y: make_call(oracle.dispatch, how, x, y), oracle)
    finish(env)
    return env.log


def finish(env: Env) -> None:
    """Call every kept ``proceed`` again, with and without arguments: its frozen chain runs."""
    for p in list(env.kept):
        for args in ((), (5, 6)):
            try:
                env.log.append(("kept", p(*args) if args else p()))
            except (Boom, TypeError) as e:
                env.log.append(("kept raised", type(e).__name__))


@pytest.mark.parametrize("fast", [True, False], ids=["fast", "reference"])
@pytest.mark.parametrize("shape", SHAPES)
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    prios=st.lists(st.integers(0, 1), min_size=N, max_size=N),
    kinds=st.lists(st.sampled_from(KINDS), min_size=N, max_size=N),
    program=programs,
)
def test_dispatch_equals_the_model(
    fast: bool, shape: str, prios: list[int], kinds: list[str], program: list[Step]
) -> None:
    assert outcome_of_runtime(fast, shape, prios, kinds, program) == outcome_of_model(
        shape, prios, kinds, program
    )


@pytest.mark.parametrize("fast", [True, False], ids=["fast", "reference"])
def test_a_scope_entered_again_after_a_global_activation_is_the_most_recent(fast: bool) -> None:
    """Found by the model: entering ``activate(a)`` again reused the frame cached the first
    time, with its old stamp, so a layer activated globally in between came out outermost."""
    a, b = Layer("A"), Layer("B")
    seen: list[str] = []

    @layered(fast=fast)
    def f(x: int) -> int:
        return x

    for la in (a, b):

        @f.variant(la)
        def _(x, *, proceed, _n=la.name):  # type: ignore[no-untyped-def]
            seen.append(_n)
            return proceed()

    with activate(a):
        pass
    saved = global_state()
    activate_globally(b)
    try:
        with activate(a):
            assert f(1) == 1
    finally:
        restore_globally(saved)
    assert seen == ["A", "B"]
