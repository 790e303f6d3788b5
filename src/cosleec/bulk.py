"""Bulk construction: pause the cyclic garbage collector while a rule set is built, and
build frozen records quickly.

Building a rule set allocates hundreds of thousands of small objects (tokens, AST nodes,
compiled functions) and frees almost none of them, so the collector's passes over the
growing heap find nothing to collect -- yet they take about a third of a 10,000-rule build.
:func:`paused_gc` switches it off for such a stretch and restores the state it found,
whatever happens inside; reference counting still frees everything that is not in a cycle.
On the way out, what was built joins the oldest generation without being scanned
(``gc.freeze`` then ``gc.unfreeze``), so the first collection afterwards does not walk it
all either; a cycle among it is found by the next full collection, as any other.

Use it only around work that is bounded and creates no long-lived garbage cycles: while
it runs the collector is off for every thread of the process (``gc`` is global).
"""

from __future__ import annotations

import dataclasses
import gc
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

C = TypeVar("C", bound=type)


@contextmanager
def paused_gc() -> Iterator[None]:
    """``with paused_gc():`` -- no cyclic collection inside; the previous state (on or off)
    comes back on the way out, also when the body raises. Nests: only the outermost
    pause turns the collector back on."""
    was_on = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_on:
            if gc.get_freeze_count() == 0:  # (a process that froze objects itself keeps them frozen)
                gc.freeze()  # what was built moves to the oldest generation, unscanned: the
                gc.unfreeze()  # next young collection would otherwise walk all of it, for nothing
            gc.enable()


def quick_init(cls: C) -> C:
    """Class decorator (under ``@dataclass(frozen=True, slots=True)``): give ``cls`` an
    ``__init__`` with the same signature and effect as the generated one, that sets each
    field through its slot directly; returns ``cls``.

    The generated ``__init__`` of a frozen dataclass sets every field with
    ``object.__setattr__(self, name, value)``, a generic attribute look-up per field; a
    slot's own setter is a third of the cost. Use it on records made by the thousand: AST
    nodes (one per grammar reduction), compiled rules, obligations (one per decision).
    Instances stay frozen: assignment still raises ``FrozenInstanceError``. A class with a
    ``__post_init__`` keeps its own ``__init__``; a field with a default factory or
    ``init=False`` is refused (TypeError), as this ``__init__`` would not make it.
    """
    fields = dataclasses.fields(cls)
    # the generated one would call it, this one does not: a class that has one keeps its own
    if not fields or hasattr(cls, "__post_init__"):
        return cls
    positional: list[str] = []
    keywords: list[str] = []
    env: dict[str, object] = {}
    for f in fields:
        if not f.init or f.default_factory is not dataclasses.MISSING:
            raise TypeError(
                f"quick_init cannot make {cls.__name__}.{f.name} (init=False or a default factory)"
            )
        env[f"_set_{f.name}"] = cls.__dict__[f.name].__set__
        param = f.name
        if f.default is not dataclasses.MISSING:
            env[f"_default_{f.name}"] = f.default
            param = f"{f.name}=_default_{f.name}"
        (keywords if f.kw_only else positional).append(param)
    params = ", ".join(["self", *positional, *(["*", *keywords] if keywords else [])])
    body = "".join(f"\n    _set_{f.name}(self, {f.name})" for f in fields)
    exec(f"def __init__({params}) -> None:{body}", env)
    init: Any = env["__init__"]
    original: Any = cls.__dict__["__init__"]
    init.__qualname__ = original.__qualname__
    init.__annotations__ = original.__annotations__
    init.__module__ = cls.__module__
    setattr(cls, "__init__", init)  # noqa: B010 - mypy refuses a plain assignment to a method
    return cls


def positional_init(cls: type, given: tuple[str, ...]) -> Any:
    """``init(obj, *values)``: what ``cls``'s dataclass ``__init__`` does with ``given``'s
    fields passed in that order (positionally) -- every other field from its default or
    default factory -- without matching keywords; for a hot path that makes one record
    (``object.__new__(cls)`` then ``init``) where a keyword-only ``__init__`` would cost
    more than the record. ``cls`` must be a non-frozen dataclass without ``__post_init__``
    whose fields outside ``given`` all have a default (TypeError otherwise)."""
    fields = dataclasses.fields(cls)
    names = {f.name for f in fields}
    frozen = getattr(getattr(cls, "__dataclass_params__", None), "frozen", True)
    if frozen or hasattr(cls, "__post_init__") or not set(given) <= names:
        raise TypeError(f"positional_init cannot make {cls.__name__} from {given}")
    env: dict[str, Any] = {}
    body = []
    for f in fields:  # in the dataclass's field order, as its own __init__ stores them
        if f.name in given:
            body.append(f"    obj.{f.name} = {f.name}")
        elif f.default_factory is not dataclasses.MISSING:
            env[f"_factory_{f.name}"] = f.default_factory
            body.append(f"    obj.{f.name} = _factory_{f.name}()")
        elif f.default is not dataclasses.MISSING:
            env[f"_default_{f.name}"] = f.default
            body.append(f"    obj.{f.name} = _default_{f.name}")
        else:
            raise TypeError(f"positional_init: {cls.__name__}.{f.name} has no default and is not given")
    exec(f"def init(obj, {', '.join(given)}) -> None:\n" + "\n".join(body), env)
    init: Any = env["init"]
    init.__qualname__ = f"{cls.__name__}.positional_init"
    return init
