"""The branches the fast path adds (``fastpath.py``), on both dispatchers: the flat memo
checked by identity, the linked chain of lone ``around`` partials walked by ``proceed``,
the unusual call shapes, async and generator bases, SD9 deferral through the walked
chain, and ``required_positionals`` read from the code instead of ``inspect``.

Each test would fail if its branch diverged from the reference dispatcher.
"""

from __future__ import annotations

import asyncio
import functools
import inspect
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from cosleec.cop import (
    Layer,
    activate,
    activate_globally,
    deactivate,
    deactivate_globally,
    global_count,
    on_dispatch,
)
from cosleec.cop.fastpath import required_positionals

Layered = Callable[..., Any]
LS = [Layer(f"J{i}") for i in range(10)]


def _passes(f: Any, log: list[str], layers: list[Layer]) -> None:
    """A pass-through ``around`` partial on every layer, logging entry and exit."""
    for la in layers:

        @f.variant(la)
        def _around(x, *, proceed, _n=la.name):  # type: ignore[no-untyped-def]
            log.append(f"+{_n}")
            r = proceed()
            log.append(f"-{_n}")
            return r


def test_memo_sees_a_layer_activated_after_calls_with_nothing_active(layered: Layered) -> None:
    @layered
    def f(x: int) -> int:
        return x + 1

    @f.variant(LS[0])
    def _(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed() * 10

    assert [f(1) for _ in range(3)] == [2, 2, 2]  # the memo now says: nothing active
    with activate(LS[0]):
        assert f(1) == 20
        with deactivate(LS[0]):
            assert f(1) == 2
        assert f(1) == 20
    assert f(1) == 2
    activate_globally(LS[0])
    try:
        assert f(1) == 20  # a global change replaces the state the memo was keyed on
    finally:
        deactivate_globally(LS[0])
    assert f(1) == 2


def test_a_partial_registered_after_calls_is_seen(layered: Layered) -> None:
    @layered
    def f(x: int) -> int:
        return x + 1

    with activate(LS[1]):
        assert f(1) == 2  # memo: LS[1] active, no partial for it

        @f.variant(LS[1])
        def _(x, *, proceed):  # type: ignore[no-untyped-def]
            return -proceed()

        assert f(1) == -2


def test_ten_lone_arounds_run_outermost_first_and_unwind_in_order(layered: Layered) -> None:
    log: list[str] = []

    @layered
    def f(x: int) -> int:
        log.append("base")
        return x + 1

    _passes(f, log, LS)
    with activate(*LS):
        assert f(1) == 2
    # the most recent activation is outermost (SD7): J9 first
    names = [la.name for la in reversed(LS)]
    assert log == [f"+{n}" for n in names] + ["base"] + [f"-{n}" for n in reversed(names)]


def test_proceed_with_arguments_in_the_middle_of_the_walked_chain(layered: Layered) -> None:
    seen: list[tuple[str, tuple[Any, ...], dict[str, Any]]] = []
    outer, middle, inner = LS[0], LS[1], LS[2]

    @layered
    def f(x: int, y: int = 0) -> tuple[int, int]:
        return (x, y)

    @f.variant(inner)
    def _inner(*a, proceed, **k):  # type: ignore[no-untyped-def]
        seen.append(("inner", a, k))
        return proceed()

    @f.variant(middle)
    def _middle(x, *, proceed):  # type: ignore[no-untyped-def]
        seen.append(("middle", (x,), {}))
        return proceed(x * 100, y=7)  # replaces the arguments for the rest of the chain

    @f.variant(outer)
    def _outer(x, *, proceed):  # type: ignore[no-untyped-def]
        seen.append(("outer", (x,), {}))
        return proceed()

    with activate(inner, middle, outer):  # outer is outermost
        assert f(3) == (300, 7)
    assert seen == [("outer", (3,), {}), ("middle", (3,), {}), ("inner", (300,), {"y": 7})]


def test_a_layer_with_before_and_after_between_lone_arounds(layered: Layered) -> None:
    log: list[str] = []
    a, b, c = LS[3], LS[4], LS[5]

    @layered
    def f(x: int) -> int:
        log.append("base")
        return x

    _passes(f, log, [a, c])

    @f.before(b)
    def _before(x):  # type: ignore[no-untyped-def]
        log.append("before-b")

    @f.after(b)
    def _after(x, *, result):  # type: ignore[no-untyped-def]
        log.append("after-b")
        return result + 1

    with activate(a, b, c):  # c outermost, then b, then a
        assert f(1) == 2
    assert log == ["+J5", "before-b", "+J3", "base", "-J3", "after-b", "-J5"]


@pytest.mark.parametrize("how", ["keyword", "extra", "missing", "usual"])
def test_unusual_call_shapes_reach_partials_as_the_caller_gave_them(layered: Layered, how: str) -> None:
    seen: list[tuple[tuple[Any, ...], dict[str, Any]]] = []

    @layered
    def f(x: int = -1, *rest: int, **kw: int) -> tuple[Any, ...]:
        return (x, rest, kw)

    for la in (LS[6], LS[7]):

        @f.variant(la)
        def _(*a, proceed, **k):  # type: ignore[no-untyped-def]
            seen.append((a, k))
            return proceed()

    call = {
        "keyword": lambda: f(x=1),
        "extra": lambda: f(1, 2, z=3),
        "missing": lambda: f(),
        "usual": lambda: f(1),
    }[how]
    expect = {
        "keyword": ((), {"x": 1}),
        "extra": ((1, 2), {"z": 3}),
        "missing": ((), {}),
        "usual": ((1,), {}),
    }[how]
    with activate(LS[6], LS[7]):
        result = call()
    assert seen == [expect, expect]
    assert result == call()


def test_a_required_positional_passed_by_keyword_or_missing(layered: Layered) -> None:
    @layered
    def f(x: int, y: int) -> int:
        return x * 10 + y

    @f.variant(LS[8])
    def _(*a, proceed, **k):  # type: ignore[no-untyped-def]
        return ("seen", a, k, proceed())

    with activate(LS[8]):
        assert f(1, y=2) == ("seen", (1,), {"y": 2}, 12)
        assert f(x=1, y=2) == ("seen", (), {"x": 1, "y": 2}, 12)
        with pytest.raises(TypeError):
            f(1)
    assert f(1, 2) == 12
    with pytest.raises(TypeError):
        f(1)


def test_a_method_keeps_its_receiver_through_the_walked_chain(layered: Layered) -> None:
    class C:
        def __init__(self, k: int) -> None:
            self.k = k

        @layered
        def scale(self, x: int) -> int:
            return self.k * x

        @scale.variant(LS[0])
        def _outer(self, x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed()

        @scale.variant(LS[1])
        def _inner(self, x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed(x + 1)  # self is kept (SD3)

    with activate(LS[1], LS[0]):
        assert C(10).scale(1) == 20


def test_async_base_through_a_walked_chain(layered: Layered) -> None:
    log: list[str] = []

    @layered
    async def f(x: int) -> int:
        await asyncio.sleep(0)
        log.append("base")
        return x + 1

    for la in (LS[2], LS[3], LS[4]):

        @f.variant(la)
        async def _(x, *, proceed, _n=la.name):  # type: ignore[no-untyped-def]
            log.append(_n)
            return await (proceed(x * 2) if _n == "J3" else proceed())

    async def main() -> tuple[int, int]:
        plain = await f(1)
        with activate(LS[2], LS[3], LS[4]):
            return plain, await f(1)

    assert asyncio.run(main()) == (2, 3)  # J3 doubles the argument for J2 and the base
    assert log == ["base", "J4", "J3", "J2", "base"]


def test_generator_base_through_a_walked_chain(layered: Layered) -> None:
    @layered
    def count(n: int) -> Iterator[int]:
        yield from range(n)

    @count.variant(LS[5])
    def _outer(n, *, proceed):  # type: ignore[no-untyped-def]
        return (v * 10 for v in proceed())

    @count.variant(LS[6])
    def _inner(n, *, proceed):  # type: ignore[no-untyped-def]
        return proceed(n + 1)

    assert list(count(2)) == [0, 1]
    with activate(LS[6], LS[5]):
        assert list(count(2)) == [0, 10, 20]


def test_a_global_change_deep_in_the_walked_chain_waits_for_the_outermost_end(layered: Layered) -> None:
    target = Layer("target")
    during: list[int] = []

    @layered
    def f(x: int) -> int:
        activate_globally(target)  # requested in the base, below three partials
        during.append(global_count(target))
        return x

    @layered
    def g(x: int) -> int:
        r = f(x)  # a nested dispatch ends here: not the outermost one
        during.append(global_count(target))
        return r

    for fn in (f, g):
        for la in LS[:3]:

            @fn.variant(la)
            def _(x, *, proceed):  # type: ignore[no-untyped-def]
                return proceed()

    try:
        with activate(*LS[:3]):
            assert g(1) == 1
        assert during == [0, 0]
        assert global_count(target) == 1  # applied when g's dispatch ended
    finally:
        while global_count(target):
            deactivate_globally(target)


def test_a_global_change_is_applied_when_the_walked_chain_raises(layered: Layered) -> None:
    target = Layer("target")

    @layered
    def f(x: int) -> int:
        activate_globally(target)
        raise RuntimeError("boom")

    for la in LS[:2]:

        @f.variant(la)
        def _(x, *, proceed):  # type: ignore[no-untyped-def]
            return proceed()

    try:
        with activate(*LS[:2]), pytest.raises(RuntimeError):
            f(1)
        assert global_count(target) == 1
    finally:
        while global_count(target):
            deactivate_globally(target)


def test_proceed_kept_and_called_after_the_dispatch_runs_the_rest_of_the_chain(layered: Layered) -> None:
    kept: list[Callable[..., Any]] = []
    log: list[str] = []

    @layered
    def f(x: int) -> int:
        log.append("base")
        return x + 1

    @f.variant(LS[0])
    def _outer(x, *, proceed):  # type: ignore[no-untyped-def]
        kept.append(proceed)
        return 0

    _passes(f, log, [LS[1]])
    with activate(LS[1], LS[0]):
        assert f(1) == 0
    assert log == []
    assert kept[0]() == 2 and kept[0](5) == 6  # the chain frozen at dispatch time (SD2)
    assert log == ["+J1", "base", "-J1", "+J1", "base", "-J1"]


def test_dispatch_hooks_see_every_call_even_when_the_chain_is_memoised(layered: Layered) -> None:
    @layered
    def f(x: int) -> int:
        return x

    @f.variant(LS[9])
    def _(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed() + 1

    with activate(LS[9]):
        assert f(1) == 2  # memoised
        records: list[Any] = []
        remove = on_dispatch(records.append)
        try:
            assert f(1) == 2 and f(1) == 2
        finally:
            remove()
        assert len(records) == 2
        assert f(1) == 2


# ---------------------------------------------------------------- required_positionals


def _by_inspect(fn: Callable[..., Any]) -> int:
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


def _shapes() -> list[Callable[..., Any]]:
    def a() -> None: ...
    def b(x: int) -> None: ...
    def c(x: int, y: int = 1) -> None: ...
    def d(x: int, /, y: int, *r: int, z: int, **k: int) -> None: ...
    def e(x: int = 1, /, *r: int) -> None: ...
    def f(*, x: int) -> None: ...
    def g(x: int, y: int, z: int, *, w: int = 2) -> None: ...

    @functools.wraps(g)
    def wrapped(*a: Any, **k: Any) -> None: ...

    def sig(*a: Any) -> None: ...

    sig.__signature__ = inspect.signature(b)  # type: ignore[attr-defined]

    def redefaulted(x: int, y: int) -> None: ...

    redefaulted.__defaults__ = (5,)

    class K:
        def m(self, x: int) -> None: ...

        pm = functools.partialmethod(m, 1)

    return [
        a,
        b,
        c,
        d,
        e,
        f,
        g,
        wrapped,
        sig,
        redefaulted,
        lambda x, y=2: None,
        K.m,
        K().m,
        K,
        K.pm,
        len,
        print,
        functools.partial(g, 1),
        functools.partial(c, y=3),
    ]


@pytest.mark.parametrize("fn", _shapes())
def test_required_positionals_agrees_with_inspect(fn: Callable[..., Any]) -> None:
    assert required_positionals(fn) == _by_inspect(fn)


def test_required_positionals_follows_a_later_change_of_defaults() -> None:
    def h(x: int, y: int) -> None: ...

    assert required_positionals(h) == 2
    h.__defaults__ = (1,)
    assert required_positionals(h) == 1
    h.__defaults__ = None
    assert required_positionals(h) == 2
