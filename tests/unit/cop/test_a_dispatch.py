"""Checklist A: definition and dispatch (every test runs on both dispatchers)."""

from __future__ import annotations

import asyncio
import inspect
import traceback
from collections.abc import Callable
from typing import Any

import pytest

from cosleec.cop import DefinitionError, Layer, activate, partial

L = Layer("L")
Layered = Callable[..., Any]


@pytest.fixture
def square(layered: Layered) -> Any:
    @layered
    def square(a: int) -> int:
        return a * a

    @square.variant(L)
    def _square_l(a, *, proceed):  # type: ignore[no-untyped-def]
        return proceed(a * 2) + proceed(a * 3)

    return square


@pytest.fixture
def greeter(layered: Layered) -> type:
    class Greeter:
        prefix = "hi"

        @layered
        def greet(self, name: str) -> str:
            return f"{self.prefix} {name}"

        @greet.variant(L)
        def _greet_l(self, name: str, *, proceed):  # type: ignore[no-untyped-def]
            assert isinstance(self, Greeter)
            return proceed(name.upper()) + "!"

        @layered
        @classmethod
        def kind(cls) -> str:
            return cls.__name__

        @kind.variant(L)
        def _kind_l(cls, *, proceed):  # type: ignore[no-untyped-def]
            return "layered " + proceed()

        @layered
        @staticmethod
        def twice(x: int) -> int:
            return 2 * x

        @twice.variant(L)
        def _twice_l(x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed(x + 1)

    return Greeter


def test_a1_base_without_layers_for_every_kind_of_callable(
    layered: Layered, square: Any, greeter: Any
) -> None:
    assert square(3) == 9
    g = greeter()
    assert g.greet("ada") == "hi ada"
    assert greeter.kind() == "Greeter"
    assert greeter.twice(2) == 4
    assert g.twice(2) == 4

    @layered
    async def fetch(x: int) -> int:
        return x + 1

    assert asyncio.run(fetch(1)) == 2


def test_a2_partial_applies_inside_the_block_only(greeter: Any) -> None:
    with activate(L):
        assert greeter().greet("ada") == "hi ADA!"
        assert greeter.kind() == "layered Greeter"
        assert greeter.twice(2) == 6
    assert greeter().greet("ada") == "hi ada"


def test_a3_proceed_forwards_or_replaces_arguments_and_keeps_the_receiver(layered: Layered) -> None:
    @layered
    def f(a: int, b: int = 10) -> tuple[int, int]:
        return (a, b)

    @f.variant(L)
    def _(a, b=10, *, proceed):  # type: ignore[no-untyped-def]
        return (proceed(), proceed(a + 1, b=b + 1))

    with activate(L):
        assert f(1, b=2) == ((1, 2), (2, 3))
        assert f(1, 2) == ((1, 2), (2, 3))
        assert f(1) == ((1, 10), (2, 11))


def test_a4_proceed_called_twice_runs_the_rest_independently(square: Any) -> None:
    with activate(L):
        assert square(1) == 13


def test_a5_a_kept_proceed_runs_the_frozen_chain(layered: Layered) -> None:
    M = Layer("M")
    kept = []

    @layered
    def f(x: int) -> str:
        return "base"

    @f.variant(L)
    def _(x, *, proceed):  # type: ignore[no-untyped-def]
        kept.append(proceed)
        return "L>" + proceed()

    @f.variant(M)
    def _m(x, *, proceed):  # type: ignore[no-untyped-def]
        return "M>" + proceed()

    with activate(L):
        assert f(1) == "L>base"
    with activate(M):
        assert kept[0]() == "base"  # not "M>base": the chain was frozen at dispatch
        assert kept[0](2) == "base"


def test_a6_before_around_after_order_and_after_changes_result(layered: Layered) -> None:
    log: list[str] = []

    @layered
    def f(x: int) -> int:
        log.append("base")
        return x

    @f.before(L)
    def _b(x):  # type: ignore[no-untyped-def]
        log.append("before")

    @f.variant(L)
    def _a(x, *, proceed):  # type: ignore[no-untyped-def]
        log.append("around")
        return proceed() + 1

    @f.after(L)
    def _c(x, *, result):  # type: ignore[no-untyped-def]
        log.append("after")
        return result * 10

    with activate(L):
        assert f(1) == 20
    assert log == ["before", "around", "base", "after"]


def test_a6b_replacing_partial_never_calls_base(layered: Layered) -> None:
    calls = []

    @layered
    def f() -> str:
        calls.append(1)
        return "base"

    @f.variant(L)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return "replaced"

    with activate(L):
        assert f() == "replaced"
    assert calls == []


def test_a7_inheritance(layered: Layered, greeter: Any) -> None:
    class Polite(greeter):  # type: ignore[misc, valid-type]
        @layered
        def greet(self, name: str) -> str:
            return "dear " + super().greet(name)

    class Plain(greeter):  # type: ignore[misc, valid-type]
        prefix = "yo"

    p = Polite()
    assert p.greet("ada") == "dear hi ada"
    assert Plain().greet("ada") == "yo ada"
    with activate(L):
        assert p.greet("ada") == "dear hi ADA!"  # super() goes through the layered superclass method
        assert Plain().greet("ada") == "yo ADA!"  # inherited, still layered


def test_a8_partial_registered_while_active_takes_effect_next_dispatch(layered: Layered) -> None:
    N = Layer("N")

    @layered
    def f() -> int:
        return 1

    with activate(N):
        assert f() == 1

        @f.variant(N)
        def _(*, proceed):  # type: ignore[no-untyped-def]
            return 2

        assert f() == 2

        @f.after(N)
        def _after(*, result):  # type: ignore[no-untyped-def]
            return result * 10

        assert f() == 20  # a second kind on the same layer: the cached chain was dropped


def test_a9_two_partials_of_one_kind_for_one_layer_is_an_error(layered: Layered) -> None:
    @layered
    def f() -> int:
        return 1

    @f.variant(L)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return 2

    with pytest.raises(DefinitionError):

        @f.variant(L)
        def _again(*, proceed):  # type: ignore[no-untyped-def]
            return 3


def test_a10_a_layer_cannot_introduce_a_function() -> None:
    def plain() -> None: ...

    with pytest.raises(DefinitionError):
        partial(plain, L)


def test_a10_partial_registers_from_outside_the_definition(layered: Layered) -> None:
    @layered
    def f() -> int:
        return 1

    @partial(f, L, "after")
    def _(*, result):  # type: ignore[no-untyped-def]
        return result + 1

    with activate(L):
        assert f() == 2


def test_a11_recursion_gets_an_independent_chain_per_call(layered: Layered) -> None:
    @layered
    def fact(n: int) -> int:
        return 1 if n <= 1 else n * fact(n - 1)

    @fact.variant(L)
    def _(n, *, proceed):  # type: ignore[no-untyped-def]
        return proceed() + 0

    with activate(L):
        assert fact(6) == 720


def test_sync_partial_on_async_base_is_rejected(layered: Layered) -> None:
    @layered
    async def f() -> int:
        return 1

    with pytest.raises(DefinitionError):

        @f.variant(L)
        def _(*, proceed):  # type: ignore[no-untyped-def]
            return 2


def test_a1_the_base_runs_as_written_signature_defaults_and_tracebacks(layered: Layered) -> None:
    @layered
    def f(a: int, b: int = 5, *rest: int, k: int = 7, **kw: int) -> tuple:  # type: ignore[type-arg]
        """Docs."""
        if a < 0:
            raise ValueError("negative")
        return (a, b, rest, k, kw)

    assert f(1) == (1, 5, (), 7, {})
    assert f(1, 2, 3, k=4, z=5) == (1, 2, (3,), 4, {"z": 5})
    assert list(inspect.signature(f).parameters) == ["a", "b", "rest", "k", "kw"]
    assert (f.__name__, f.__doc__) == ("f", "Docs.")
    with activate(L):
        assert f(1, 2, 3, k=4, z=5) == (1, 2, (3,), 4, {"z": 5})
    with pytest.raises(ValueError) as info:
        f(-1)
    last = traceback.extract_tb(info.value.__traceback__)[-1]
    assert last.line == 'raise ValueError("negative")'
    with pytest.raises(TypeError):
        f()  # a wrong call fails as it would without @layered
