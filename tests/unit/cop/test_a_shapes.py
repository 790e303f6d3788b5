"""Checklist A, every shape of callable: the base runs as written, in its class, with its
closure, defaults and decorators, whatever its parameters are called -- on both dispatchers.

Several of these failed when the dispatcher recompiled the user's function outside its
class (private names lost their mangling; an inner decorator was dropped).
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from cosleec.cop import Layer, activate, active_layers, layered_generator

L = Layer("L")
Layered = Callable[..., Any]


def names() -> list[str]:
    return [la.name for la in active_layers()]


def test_a_method_reading_a_private_name_keeps_its_mangling(layered: Layered) -> None:
    class Account:
        def __init__(self, balance: int) -> None:
            self.__balance = balance

        @layered
        def balance(self) -> int:
            return self.__balance

        @balance.variant(L)
        def _audited(self, *, proceed):  # type: ignore[no-untyped-def]
            return ("audited", proceed(), self.__balance)

    assert Account(5).balance() == 5
    with activate(L):
        assert Account(5).balance() == ("audited", 5, 5)


def test_a_method_of_a_slotted_class(layered: Layered) -> None:
    class Point:
        __slots__ = ("__x", "y")

        def __init__(self, x: int, y: int) -> None:
            self.__x, self.y = x, y

        @layered
        def norm1(self) -> int:
            return abs(self.__x) + abs(self.y)

        @norm1.variant(L)
        def _scaled(self, *, proceed):  # type: ignore[no-untyped-def]
            return proceed() * 10

    class Point3(Point):
        __slots__ = ("z",)

        def __init__(self, x: int, y: int, z: int) -> None:
            super().__init__(x, y)
            self.z = z

        @layered
        def norm1(self) -> int:
            return super().norm1() + abs(self.z)

    assert Point(1, -2).norm1() == 3
    assert Point3(1, 2, 3).norm1() == 6
    with activate(L):
        assert Point(1, -2).norm1() == 30
        assert Point3(1, 2, 3).norm1() == 33


def test_closures_keep_their_free_variables(layered: Layered) -> None:
    def make(offset: int) -> Any:
        @layered
        def add(x: int) -> int:
            return x + offset

        @add.variant(L)
        def _(x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed(x + offset)

        return add

    add1, add10 = make(1), make(10)
    assert (add1(0), add10(0)) == (1, 10)
    with activate(L):
        assert (add1(0), add10(0)) == (2, 20)


def test_an_inner_decorator_is_kept(layered: Layered) -> None:
    calls: list[int] = []

    def counted(fn: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            calls.append(1)
            return fn(*args, **kwargs)

        return wrapper

    @layered
    @counted
    def f(x: int) -> int:
        return x + 1

    assert f(1) == 2
    assert calls == [1]


def test_defaults_and_keyword_only_arguments_reach_partials_as_the_caller_gave_them(layered: Layered) -> None:
    seen: list[tuple[Any, ...]] = []

    @layered
    def f(a: int, b: int = 2, *, c: int, d: int = 4) -> tuple[int, int, int, int]:
        return (a, b, c, d)

    @f.variant(L)
    def _(a, b=20, *, c, d=40, proceed):  # type: ignore[no-untyped-def]
        seen.append((a, b, c, d))  # the partial's own defaults fill what the caller left out
        return proceed()

    with pytest.raises(TypeError):
        f(1)  # c is required
    with activate(L):
        assert f(1, c=3) == (1, 2, 3, 4)
        assert f(1, 5, c=3, d=6) == (1, 5, 3, 6)
        assert f(a=1, c=3) == (1, 2, 3, 4)
    assert seen == [(1, 20, 3, 40), (1, 5, 3, 6), (1, 20, 3, 40)]


def test_var_positional_and_var_keyword(layered: Layered) -> None:
    @layered
    def f(*args: int, **kwargs: int) -> tuple[tuple[int, ...], dict[str, int]]:
        return args, kwargs

    @f.variant(L)
    def _(*args, proceed, **kwargs):  # type: ignore[no-untyped-def]
        if kwargs.get("replace"):
            return proceed(9, z=1)
        return proceed()

    assert f() == ((), {})
    with activate(L):
        assert f(1, 2, x=3) == ((1, 2), {"x": 3})
        assert f(1, replace=1) == ((9,), {"z": 1})


def test_positional_only_parameters(layered: Layered) -> None:
    @layered
    def f(a: int, b: int, /, c: int = 0, **kw: int) -> tuple[int, int, int, dict[str, int]]:
        return (a, b, c, kw)

    @f.variant(L)
    def _(a, b, /, c=0, *, proceed, **kw):  # type: ignore[no-untyped-def]
        return proceed(a * 10, b, c, **kw) if a < 0 else proceed()

    for call in (lambda: f(1, 2), lambda: f(1, 2, 3), lambda: f(1, 2, c=3), lambda: f(1, 2, a=5)):
        plain = call()
        with activate(L):
            assert call() == plain
    assert f(1, 2, a=5) == (1, 2, 0, {"a": 5})  # a positional-only name may travel in **kw
    with activate(L):
        assert f(-1, 2, a=5) == (-10, 2, 0, {"a": 5})
    with pytest.raises(TypeError):
        f(1)


def test_parameters_named_like_the_dispatcher_internals(layered: Layered) -> None:
    @layered
    def f(proceed: int, _F: int = 1, _a0: int = 2, *_r: int, **_k: int) -> tuple[Any, ...]:
        return (proceed, _F, _a0, _r, _k)

    @f.variant(L)
    def _(p, _F=1, _a0=2, *r, proceed, **k):  # type: ignore[no-untyped-def]
        return ("L", p, _F, proceed())

    assert f(10) == (10, 1, 2, (), {})
    assert f(10, _F=3, _k=4, M=5) == (10, 3, 2, (), {"_k": 4, "M": 5})
    assert f(10, 20, 30, 40) == (10, 20, 30, (40,), {})
    with activate(L):
        assert f(10, _F=3) == ("L", 10, 3, (10, 3, 2, (), {}))
        assert f(10, 20, 30, 40) == ("L", 10, 20, (10, 20, 30, (40,), {}))


def test_static_and_class_methods_keep_or_have_no_receiver(layered: Layered) -> None:
    class Shape:
        sides = 0

        @layered
        @classmethod
        def make(cls, n: int) -> tuple[str, int]:
            return (cls.__name__, n)

        @make.variant(L)
        def _make(cls, n, *, proceed):  # type: ignore[no-untyped-def]
            return proceed(n + 1)  # the receiver cls is kept

        @layered
        @staticmethod
        def area(w: int, h: int) -> int:
            return w * h

        @area.variant(L)
        def _area(w, h, *, proceed):  # type: ignore[no-untyped-def]
            return proceed(w + 1, h)  # no receiver to keep

    class Square(Shape):
        pass

    assert Square.make(1) == ("Square", 1)
    assert Square().area(2, 3) == 6
    with activate(L):
        assert Square.make(1) == ("Square", 2)
        assert Shape().make(1) == ("Shape", 2)
        assert Shape.area(2, 3) == 9


def test_async_bases_and_partials(layered: Layered) -> None:
    log: list[str] = []

    class Store:
        def __init__(self) -> None:
            self.data = {"a": 1}

        @layered
        async def get(self, key: str) -> int:
            await asyncio.sleep(0)
            return self.data[key]

        @get.before(L)
        async def _before(self, key):  # type: ignore[no-untyped-def]
            log.append("before " + key)

        @get.variant(L)
        async def _around(self, key, *, proceed):  # type: ignore[no-untyped-def]
            return await proceed("a") + await proceed()  # proceed("a") keeps self

        @get.after(L)
        async def _after(self, key, *, result):  # type: ignore[no-untyped-def]
            return result * 10

    async def main() -> tuple[int, int]:
        s = Store()
        s.data["b"] = 2
        plain = await s.get("b")
        with activate(L):
            return plain, await s.get("b")

    assert asyncio.run(main()) == (2, 30)
    assert log == ["before b"]


def test_functools_partial_bases_sync_and_async(layered: Layered) -> None:
    def scale(k: int, x: int) -> int:
        return k * x

    async def ascale(k: int, x: int) -> int:
        return k * x

    f = layered(functools.partial(scale, 3))
    af = layered(functools.partial(ascale, 3))

    @f.variant(L)
    def _(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed(x + 1)

    @af.variant(L)
    async def _a(x, *, proceed):  # type: ignore[no-untyped-def]
        return await proceed(x + 1)

    assert (f(1), asyncio.run(af(1))) == (3, 3)
    with activate(L):
        assert f(1) == 6
        assert asyncio.run(af(1)) == 6


def test_builtins_and_lambdas_as_bases(layered: Layered) -> None:
    size = layered(len)
    inc = layered(lambda x: x + 1)

    @size.variant(L)
    def _(obj, *, proceed):  # type: ignore[no-untyped-def]
        return proceed() * 2

    assert (size("abc"), inc(1)) == (3, 2)
    with activate(L):
        assert size("abc") == 6


def test_generator_functions_as_bases_and_partials(layered: Layered) -> None:
    @layered
    def count(n: int) -> Iterator[int]:
        yield from range(n)

    @count.variant(L)
    def _(n, *, proceed):  # type: ignore[no-untyped-def]
        for x in proceed():
            yield x * 10

    assert list(count(3)) == [0, 1, 2]
    with activate(L):
        gen = count(3)
    assert list(gen) == [0, 10, 20]  # the chain was chosen when the call was made


def test_layered_generators_keep_their_activations(layered: Layered) -> None:
    M = Layer("M")

    @layered
    @layered_generator
    def watch() -> Iterator[list[str]]:
        with activate(M):
            yield names()
            yield names()

    @watch.variant(L)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return proceed()

    with activate(L):
        g = watch()
        assert next(g) == ["M", "L"]
        assert names() == ["L"]  # M does not leak to the consumer while the generator waits
    assert next(g) == ["M", "L"]
    assert names() == []
