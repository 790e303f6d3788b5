"""Checklists F (events and consistency), G45 (thread stress) and H (cosleec additions).

Tests that dispatch run on both dispatchers.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from cosleec.cop import (
    DefinitionError,
    DispatchRecord,
    HedgeGroup,
    Layer,
    Transitions,
    activate,
    activate_globally,
    active_layers,
    at_safe_point,
    critical,
    deactivate_globally,
    global_state,
    on_dispatch,
    using_context,
)

G, S, OUTER = Layer("G"), Layer("S"), Layer("OUTER")
Layered = Callable[..., Any]


@pytest.fixture
def probe(layered: Layered) -> Any:
    @layered
    def probe() -> str:
        return "base"

    for la in (G, S):

        def mk(la: Layer) -> None:
            @probe.variant(la)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return la.name + ">" + proceed()

        mk(la)
    return probe


def names() -> list[str]:
    return [la.name for la in active_layers()]


def test_f39_changes_inside_a_running_dispatch(layered: Layered, probe: Any) -> None:
    seen: dict[str, object] = {}

    @layered
    def outer() -> str:
        return "outer-base"

    @outer.variant(OUTER)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        with activate(S):
            seen["scoped-nested"] = probe()
        activate_globally(G)
        seen["global-nested"] = probe()
        seen["names-inside"] = names()
        return proceed()

    with activate(OUTER):
        assert outer() == "outer-base"
    assert seen["scoped-nested"] == "S>base"
    assert seen["global-nested"] == "base"  # queued until the outermost dispatch ends
    assert "G" not in seen["names-inside"]  # type: ignore[operator]
    assert probe() == "G>base"  # the next top-level dispatch sees it
    deactivate_globally(G)


def test_f40_requests_are_applied_in_order_when_the_dispatch_or_critical_ends(layered: Layered) -> None:
    with critical():
        activate_globally(G)
        activate_globally(S)
        deactivate_globally(G)
        assert names() == []
    assert names() == ["S"]
    deactivate_globally(S)

    @layered
    def failing() -> None:
        raise RuntimeError

    @failing.variant(OUTER)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        activate_globally(G)
        activate_globally(S)
        return proceed()

    with activate(OUTER), pytest.raises(RuntimeError):
        failing()
    assert set(names()) >= {"G", "S"}
    deactivate_globally(G)
    deactivate_globally(S)


def test_f41_event_transition_swaps_atomically() -> None:
    L1, L2 = Layer("T1"), Layer("T2")
    table = Transitions()
    table.on("E", activate=[L2], deactivate=[L1])
    table.on("F", activate=[L1], deactivate=[L2])
    activate_globally(L1)
    bad: list[set[str]] = []
    stop = threading.Event()

    def reader() -> None:
        while not stop.is_set():
            current = {la.name for la, _ in global_state().layers}
            if current not in ({"T1"}, {"T2"}):
                bad.append(current)

    t = threading.Thread(target=reader)
    t.start()
    for _ in range(2000):
        table.fire("E")
        table.fire("F")
    stop.set()
    t.join()
    assert bad == []
    assert table.fire("nothing") is False
    deactivate_globally(L1)


def test_f42_a_decision_is_not_withdrawn_when_the_predicate_changes_later(layered: Layered) -> None:
    flag = {"on": True}
    hedge = Layer("H", when=lambda ctx: ctx["on"])

    @layered(hedges=HedgeGroup("r", [hedge]))
    def rule() -> dict[str, str]:
        return {"obligation": "Default"}

    @rule.variant(hedge)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return {"obligation": "Hedge"}

    with using_context(flag):
        result = rule()
        flag["on"] = False
        assert result == {"obligation": "Hedge"}
        assert rule() == {"obligation": "Default"}


def test_f43_dispatch_records_reproduce_a_scripted_run(layered: Layered, tmp_path) -> None:  # type: ignore[no-untyped-def]
    a = Layer("A", when=lambda ctx: ctx["a"])
    b = Layer("B", when=lambda ctx: ctx["b"])

    @layered(hedges=HedgeGroup("rule", [a, b]))
    def rule() -> str:
        return "default"

    for la in (a, b):

        def mk(la: Layer) -> None:
            @rule.variant(la)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return la.name

        mk(la)

    log = tmp_path / "decisions.jsonl"

    def record(r: DispatchRecord) -> None:
        with log.open("a") as fh:
            fh.write(
                json.dumps(
                    {
                        "fn": r.function,
                        "predicates": r.predicates,
                        "selected": r.selected,
                        "snapshot": r.snapshot_id,
                    }
                )
                + "\n"
            )

    script = [
        {"id": 1, "a": False, "b": False},
        {"id": 2, "a": True, "b": False},
        {"id": 3, "a": True, "b": True},
    ]
    remove = on_dispatch(record)
    try:
        results = []
        for ctx in script:

            class Snap(dict):  # type: ignore[type-arg]
                id = ctx["id"]

            with using_context(Snap(ctx)):
                results.append(rule())
    finally:
        remove()
    rows = [json.loads(x) for x in log.read_text().splitlines()]
    assert results == ["default", "A", "B"]
    assert [r["selected"]["rule"] for r in rows] == [None, "A", "B"]
    assert [r["snapshot"] for r in rows] == [1, 2, 3]
    assert rows[2]["predicates"]["rule"] == {"A": True, "B": True}  # every predicate is recorded


def test_g45_threads_hammering_global_activation_lose_nothing(probe: Any) -> None:
    layers = [Layer(f"W{i}") for i in range(8)]
    # what each reader saw, per version (bounded by the number of versions, however long
    # the readers spin), and every observation that disagreed with an earlier one
    by_version: dict[int, frozenset[str]] = {}
    torn: list[tuple[int, frozenset[str], frozenset[str]]] = []
    stop = threading.Event()
    errors: list[BaseException] = []

    def writer(la: Layer) -> None:
        try:
            for _ in range(300):
                activate_globally(la)
                activate_globally(la)
                deactivate_globally(la)
            # net effect per writer: 300 activations outstanding
        except BaseException as e:  # pragma: no cover - reported below
            errors.append(e)

    def reader() -> None:
        while not stop.is_set():
            st = global_state()
            comp = frozenset(la.name for la, _ in st.layers)
            first = by_version.setdefault(st.version, comp)
            if first != comp:
                torn.append((st.version, first, comp))
            probe()
            time.sleep(0)  # let the writers run: the readers only sample

    readers = [threading.Thread(target=reader) for _ in range(8)]
    writers = [threading.Thread(target=writer, args=(la,)) for la in layers]
    for t in readers + writers:
        t.start()
    for t in writers:
        t.join()
    stop.set()
    for t in readers:
        t.join()
    assert errors == []
    assert all(global_state().counts[la] == 300 for la in layers)
    assert by_version and torn == []  # one composition per version: none torn
    for la in layers:
        for _ in range(300):
            deactivate_globally(la)
    assert active_layers() == ()


def test_h46_a_hedge_without_then_returns_no_obligation_and_after_still_sees_it(layered: Layered) -> None:
    exempt = Layer("exempt", when=lambda ctx: True)
    audit = Layer("audit")
    seen: list[object] = []

    @layered(hedges=HedgeGroup("r", [exempt]))
    def rule() -> object:
        return "Obligation"

    @rule.variant(exempt)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return None

    @rule.after(audit)
    def _audit(*, result):  # type: ignore[no-untyped-def]
        seen.append(result)
        return result

    with using_context({}), activate(audit):
        assert rule() is None
    assert seen == [None]


def test_h47_switching_policy_needs_no_reregistration_and_leaves_no_stale_chain(layered: Layered) -> None:
    a, b = Layer("a", when=lambda c: c[0]), Layer("b", when=lambda c: c[1])
    group = HedgeGroup("p", [a, b])

    def nested(values: Any) -> int | None:  # the paper's formula, as a custom policy
        k = 0
        while k < len(values) and values[k]:
            k += 1
        return k - 1 if k else None

    @layered(hedges=group)
    def r() -> str:
        return "default"

    for la in (a, b):

        def mk(la: Layer) -> None:
            @r.variant(la)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return la.name

        mk(la)
    with using_context([False, True]):
        assert r() == "b"
        group.set_policy(nested)
        assert r() == "default"
        group.set_policy("last")
        assert r() == "b"


def test_h48_chain_cache_stays_bounded(layered: Layered) -> None:
    layers = [Layer(f"C{i}") for i in range(100)]

    @layered(max_chains=32)
    def f() -> int:
        return 0

    for la in layers:

        def mk(la: Layer) -> None:
            @f.variant(la)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return proceed() + 1

        mk(la)

    for i, (x, y) in enumerate(itertools.product(layers, layers)):
        if i >= 10_000:
            break
        with activate(x), activate(y):
            f()
        assert len(f.layered.cache) <= 32


def test_h49_async_partials_await_proceed(layered: Layered) -> None:
    la = Layer("async")

    @layered
    async def fetch(x: int) -> int:
        await asyncio.sleep(0)
        return x

    @fetch.variant(la)
    async def _(x, *, proceed):  # type: ignore[no-untyped-def]
        return await proceed(x + 1) * 10

    async def main() -> int:
        with activate(la):
            return await fetch(1)

    assert asyncio.run(main()) == 20
    with pytest.raises(DefinitionError):

        @fetch.before(la)
        def _sync(x):  # type: ignore[no-untyped-def]
            pass


def test_asyncio_stress_each_task_sees_only_its_own_layers(layered: Layered) -> None:
    layers = [Layer(f"A{i}") for i in range(20)]

    @layered
    async def who() -> tuple[str, ...]:
        await asyncio.sleep(0)
        return ()

    for la in layers:

        def mk(la: Layer) -> None:
            @who.variant(la)
            async def _(*, proceed):  # type: ignore[no-untyped-def]
                return (la.name, *(await proceed()))

        mk(la)

    async def worker(i: int) -> list[bool]:
        mine = (layers[i % 20], layers[(i * 7 + 3) % 20])
        oks = []
        for _ in range(50):
            with activate(mine[0]):
                await asyncio.sleep(0)  # other tasks run in between
                with activate(mine[1]):
                    got = await who()
                    want = tuple(dict.fromkeys(la.name for la in (mine[1], mine[0])))
                    oks.append(got == want and [la.name for la in active_layers()] == list(want))
                await asyncio.sleep(0)
            oks.append(await who() == ())
        return oks

    async def main() -> list[list[bool]]:
        return await asyncio.gather(*(worker(i) for i in range(200)))

    results = asyncio.run(main())
    assert all(all(r) for r in results) and sum(len(r) for r in results) == 200 * 100


def test_sd9_holds_when_the_outer_function_runs_its_base_directly(layered: Layered, probe: Any) -> None:
    @layered
    def _setup_step() -> tuple[str, list[str]]:
        activate_globally(G)  # requested while this function runs its base (nothing active)
        return probe(), names()

    inside, seen = _setup_step()
    assert (inside, seen) == ("base", [])  # not visible to nested dispatches of the same call
    assert probe() == "G>base"  # applied when it ended
    deactivate_globally(G)


def test_f42_reevaluation_hook_runs_at_the_next_safe_point_never_during_a_step(layered: Layered) -> None:
    flag = {"on": True}
    log: list[str] = []
    hedge = Layer("H42", when=lambda ctx: ctx["on"])

    @layered(hedges=HedgeGroup("r42", [hedge]))
    def rule() -> str:
        log.append("step starts")
        flag["on"] = False  # the predicate changes while the step runs...
        at_safe_point(lambda: log.append("re-evaluate"))  # ...and asks for re-evaluation
        log.append("step ends")
        return "Default"

    @rule.variant(hedge)
    def _(*, proceed):  # type: ignore[no-untyped-def]
        return "Hedge:" + proceed()

    with using_context(flag):
        assert rule() == "Hedge:Default"  # the decision of this step stands
    assert log == ["step starts", "step ends", "re-evaluate"]
    at_safe_point(lambda: log.append("now"))  # outside any step: at once
    assert log[-1] == "now"
