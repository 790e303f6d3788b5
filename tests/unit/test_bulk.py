"""paused_gc: the collector is off inside, back as it was outside, whatever happens;
quick_init: the same records as the dataclass __init__ makes, sooner."""

from __future__ import annotations

import dataclasses
import gc
import inspect
from collections.abc import Iterator

import pytest

from cosleec.bulk import paused_gc, positional_init, quick_init
from cosleec.runtime import model as M


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
    # judged on one object of ours, not on the count: another test's thread may free a
    # frozen object meanwhile (the count drops), but only an unfreeze moves ours back
    # into the generations the collector scans
    gc.enable()
    ours: list[object] = []
    gc.freeze()
    assert gc.get_freeze_count() > 0
    with paused_gc():
        _ = [[] for _ in range(100)]
    assert not _scanned(ours)
    gc.unfreeze()
    assert _scanned(ours)  # (the check can see it: it is tracked once unfrozen)


def _scanned(thing: object) -> bool:
    """Whether the collector's generations (not the permanent one) hold ``thing``."""
    return any(o is thing for generation in range(3) for o in gc.get_objects(generation))


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


# ---------------------------------------------------------------- quick_init


def _signature(cls: type) -> list[tuple[str, object, object]]:
    """What dataclasses' generated __init__ takes: (name, kind, default), in order."""
    out = []
    for kw_only in (False, True):
        for f in dataclasses.fields(cls):
            if f.kw_only is kw_only:
                kind = inspect.Parameter.KEYWORD_ONLY if kw_only else inspect.Parameter.POSITIONAL_OR_KEYWORD
                default = inspect.Parameter.empty if f.default is dataclasses.MISSING else f.default
                out.append((f.name, kind, default))
    return out


@dataclasses.dataclass(frozen=True, slots=True)
class Point:
    x: int
    y: int = 2
    label: str = dataclasses.field(default="p", kw_only=True)


FastPoint = quick_init(
    dataclasses.make_dataclass(
        "FastPoint",
        [
            ("x", int),
            ("y", int, dataclasses.field(default=2)),
            ("label", str, dataclasses.field(default="p", kw_only=True)),
        ],
        frozen=True,
        slots=True,
    )
)


def test_quick_init_keeps_the_signature_the_values_and_frozenness() -> None:
    got = inspect.signature(FastPoint.__init__).parameters.values()
    assert [(p.name, p.kind, p.default) for p in got][1:] == _signature(Point)
    a, b = FastPoint(1), Point(1)
    assert (a.x, a.y, a.label) == (b.x, b.y, b.label) == (1, 2, "p")
    assert FastPoint(3, 4, label="q").label == "q"
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.x = 5  # type: ignore[misc]
    with pytest.raises(TypeError):
        FastPoint(1, 2, "positional label")  # type: ignore[misc]
    with pytest.raises(TypeError):
        FastPoint()  # type: ignore[call-arg]


def test_quick_init_refuses_what_it_cannot_make_and_leaves_a_post_init_alone() -> None:
    @dataclasses.dataclass(frozen=True, slots=True)
    class Listy:
        xs: list[int] = dataclasses.field(default_factory=list)

    with pytest.raises(TypeError, match="default factory"):
        quick_init(Listy)

    seen: list[int] = []

    @dataclasses.dataclass(frozen=True, slots=True)
    class Checked:
        x: int

        def __post_init__(self) -> None:
            seen.append(self.x)

    before = Checked.__init__
    assert quick_init(Checked) is Checked and Checked.__init__ is before
    Checked(7)
    assert seen == [7]


@pytest.mark.parametrize("cls", [M.Obligation, M.ItemSpec, M.Clause, M.ResponseSpec, M.CompiledRule])
def test_the_runtime_records_built_quickly_keep_the_dataclass_signature(cls: type) -> None:
    got = inspect.signature(cls.__init__).parameters.values()
    assert [(p.name, p.kind, p.default) for p in got][1:] == _signature(cls)
    assert cls.__init__.__qualname__ == f"{cls.__qualname__}.__init__"


# ---------------------------------------------------------------------------- positional_init
@dataclasses.dataclass(slots=True, kw_only=True)
class _Record:
    a: int
    b: str
    c: list[int] = dataclasses.field(default_factory=list)
    d: float = 1.5
    e: int | None = None


def test_positional_init_stores_what_the_dataclass_init_stores() -> None:
    init = positional_init(_Record, ("b", "e", "a"))  # any order: the given ones, positional
    r = object.__new__(_Record)
    init(r, "x", 7, 3)
    assert r == _Record(a=3, b="x", e=7) and r.c == [] and r.d == 1.5
    other = object.__new__(_Record)
    init(other, "y", None, 4)
    assert other.c is not r.c  # a default factory makes a new value for each record


def test_positional_init_refuses_what_it_cannot_make() -> None:
    with pytest.raises(TypeError, match="no default"):
        positional_init(_Record, ("a",))  # b has no default and is not given
    with pytest.raises(TypeError, match="cannot make"):
        positional_init(_Record, ("a", "b", "z"))  # no field z
    with pytest.raises(TypeError, match="cannot make"):
        positional_init(M.Obligation, ("event",))  # frozen: its fields are not stored so
