"""Running the recursive passes of the front end over expressions thousands of levels deep.

The passes over the AST (dialect facts, the checker, the printer, ...) recurse once per
level of an expression, and a generated rule (``a and b and ... `` with 10,000 terms, 10,000
``not``s, 10,000 nested parentheses) is that many levels deep: past Python's recursion limit
(1,000). Rewriting every pass without recursion would cost the common case, whose
expressions are a few levels deep. Instead :func:`deeply` runs a pass as it is, and only if
it meets the limit, runs it again in a thread of its own whose C stack is large
(:data:`STACK_BYTES`) with the recursion limit raised to :data:`DEEP_LIMIT` meanwhile. The
passes are pure functions of their input, so running one again gives what the first run
would have.

May import: the standard library only.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")

DEEP_LIMIT = 1_000_000
"""The recursion limit while a deep pass runs (Python frames; the passes take a few per level
of an expression)."""

STACK_BYTES = 1 << 30
"""The C stack of the thread a deep pass runs in: address space only, used as it is touched.
Python-to-Python calls take none of it (CPython 3.11); hashing or comparing nested nodes, and
CPython's own compiler, take some per level."""

_lock = threading.Lock()
_active = 0
_saved_limit = 0


def deeply(fn: Callable[[], T]) -> T:
    """``fn()``; if it exceeds the recursion limit, ``fn()`` again in a deep thread (see module)."""
    try:
        return fn()
    except RecursionError:
        pass
    return in_deep_thread(fn)


def in_deep_thread(fn: Callable[[], T]) -> T:
    """``fn()`` run in a thread with a large stack and a raised recursion limit; its
    exception, if any, is raised here."""
    global _active, _saved_limit
    box: list[T] = []
    failure: list[BaseException] = []

    def target() -> None:
        try:
            box.append(fn())
        except BaseException as e:  # handed to the caller's thread
            failure.append(e)

    with _lock:
        if _active == 0:
            _saved_limit = sys.getrecursionlimit()
            sys.setrecursionlimit(max(_saved_limit, DEEP_LIMIT))
        _active += 1
        try:
            thread = _start(target)
        except BaseException:
            _leave()
            raise
    try:
        thread.join()
    finally:
        with _lock:
            _leave()
    if failure:
        raise failure[0]
    return box[0]


def _start(target: Callable[[], None]) -> threading.Thread:
    """A started thread running ``target`` on the largest stack the system grants, from
    :data:`STACK_BYTES` down (a limit on address space may refuse 1 GiB)."""
    size = STACK_BYTES
    while True:
        old = threading.stack_size(size)
        try:
            thread = threading.Thread(target=target, name="cosleec-deep", daemon=True)
            thread.start()
            return thread
        except (RuntimeError, MemoryError):
            if size <= 1 << 24:
                raise
            size //= 4
        finally:
            threading.stack_size(old)


def _leave() -> None:
    """One deep pass less; the last one restores the recursion limit (hold ``_lock``)."""
    global _active
    _active -= 1
    if _active == 0:
        sys.setrecursionlimit(_saved_limit)
