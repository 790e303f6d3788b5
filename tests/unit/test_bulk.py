"""paused_gc: the collector is off inside, back as it was outside, whatever happens."""

from __future__ import annotations

import gc
from collections.abc import Iterator

import pytest

from cosleec.bulk import paused_gc


@pytest.fixture(autouse=True)
def _restore() -> Iterator[None]:
    was = gc.isenabled()
    yield
    gc.unfreeze()
    if was:
        gc.enable()
    else:
        gc.disable()


def test_off_inside_and_on_again_after() -> None:
    gc.enable()
    with paused_gc():
        assert not gc.isenabled()
    assert gc.isenabled()


def test_on_again_after_an_exception() -> None:
    gc.enable()
    with pytest.raises(ValueError), paused_gc():
        raise ValueError("boom")
    assert gc.isenabled()


def test_a_nested_pause_leaves_it_off_until_the_outermost_ends() -> None:
    gc.enable()
    with paused_gc():
        with paused_gc():
            pass
        assert not gc.isenabled()
    assert gc.isenabled()


def test_a_collector_the_process_turned_off_stays_off() -> None:
    gc.disable()
    with paused_gc():
        pass
    assert not gc.isenabled()


def test_as_a_decorator_each_call_pauses() -> None:
    gc.enable()
    seen = []

    @paused_gc()
    def build() -> None:
        seen.append(gc.isenabled())

    build()
    build()
    assert seen == [False, False]
    assert gc.isenabled()


def test_objects_the_process_froze_stay_frozen() -> None:
    gc.enable()
    gc.freeze()
    frozen = gc.get_freeze_count()
    assert frozen > 0
    with paused_gc():
        _ = [[] for _ in range(100)]
    assert gc.get_freeze_count() == frozen


def test_what_was_built_is_still_collectable_when_it_becomes_garbage() -> None:
    gc.enable()
    gc.collect()

    class Node:
        pass

    with paused_gc():
        a, b = Node(), Node()
        a.other, b.other = b, a  # type: ignore[attr-defined]
    assert gc.get_freeze_count() == 0  # nothing left behind in the permanent generation
    import weakref

    gone = weakref.ref(a)
    del a, b
    gc.collect()
    assert gone() is None
