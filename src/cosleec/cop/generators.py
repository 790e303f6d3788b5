"""Generators that keep their activations to themselves (SD18).

A plain generator that enters ``with activate(L):`` and yields inside it leaks L to its
consumer while suspended (PEP 568 was never adopted). ``@layered_generator`` runs every
resumption of the generator, sync or async, in the generator's own ``contextvars.Context``.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import functools
import inspect
from collections.abc import AsyncIterator, Callable, Iterator
from typing import Any


class _ContextGenerator:
    __slots__ = ("_ctx", "_gen")

    def __init__(self, gen: Any, ctx: contextvars.Context) -> None:
        self._gen = gen
        self._ctx = ctx

    def __iter__(self) -> _ContextGenerator:
        return self

    def __next__(self) -> Any:
        return self._ctx.run(next, self._gen)

    def send(self, value: Any) -> Any:
        return self._ctx.run(self._gen.send, value)

    def throw(self, *exc: Any) -> Any:
        return self._ctx.run(self._gen.throw, *exc)

    def close(self) -> None:
        self._ctx.run(self._gen.close)

    def __del__(self) -> None:
        # an unfinished generator is closed here, in its own context, rather than by the
        # garbage collector in whatever context happens to be current
        with contextlib.suppress(RuntimeError, ValueError):  # its context is busy elsewhere
            self.close()


class _ContextAsyncGenerator:
    __slots__ = ("_ctx", "_gen")

    def __init__(self, gen: Any, ctx: contextvars.Context) -> None:
        self._gen = gen
        self._ctx = ctx

    def __aiter__(self) -> _ContextAsyncGenerator:
        return self

    async def _run(self, coro: Any) -> Any:
        # each step of the generator runs as a task in the generator's own context
        return await asyncio.create_task(coro, context=self._ctx)

    async def __anext__(self) -> Any:
        return await self._run(self._gen.__anext__())

    async def asend(self, value: Any) -> Any:
        return await self._run(self._gen.asend(value))

    async def athrow(self, *exc: Any) -> Any:
        return await self._run(self._gen.athrow(*exc))

    async def aclose(self) -> None:
        await self._run(self._gen.aclose())


def layered_generator(fn: Callable[..., Any]) -> Callable[..., Iterator[Any] | AsyncIterator[Any]]:
    """Decorate a (sync or async) generator function so its activations never leak.

    Use it on every generator that enters ``with activate(...)`` and yields inside the
    block; combine it with ``@layered`` (``@layered`` outermost) to make it layered too.
    """
    if not (inspect.isgeneratorfunction(fn) or inspect.isasyncgenfunction(fn)):
        raise TypeError(f"{fn!r} is not a generator function")
    is_async = inspect.isasyncgenfunction(fn)

    @functools.wraps(fn)
    def make(*args: Any, **kwargs: Any) -> Any:
        ctx = contextvars.copy_context()
        gen = ctx.run(fn, *args, **kwargs)
        return _ContextAsyncGenerator(gen, ctx) if is_async else _ContextGenerator(gen, ctx)

    return make
