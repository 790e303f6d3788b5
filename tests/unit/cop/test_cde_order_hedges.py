"""Checklists C (composition order), D (predicate layers), E (groups and constraints).

Tests that dispatch run on both dispatchers. The CO-SLEEC paper's ``nested`` formula is
not a policy of the generic core; it is written here as a custom policy, which is also
the test that any callable ``Sequence[bool] -> int | None`` works as a policy.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

import pytest

from cosleec.cop import (
    DispatchRecord,
    ExclusionError,
    HedgeEvaluationError,
    HedgeGroup,
    Layer,
    LayerGroup,
    activate,
    activate_globally,
    add_activation_hook,
    current_layers,
    deactivate_globally,
    explain,
    on_dispatch,
    policy_first,
    policy_last,
    using_context,
)

ADD, MUL = Layer("ADD"), Layer("MUL")
Layered = Callable[..., Any]


def nested(values: Sequence[bool]) -> int | None:
    """The CO-SLEEC paper's formula: member i iff predicates 1..i hold and i+1 does not."""
    k = 0
    while k < len(values) and values[k]:
        k += 1
    return k - 1 if k else None


@pytest.fixture
def f(layered: Layered) -> Any:
    @layered
    def f(x: int) -> int:
        return x

    @f.variant(ADD)
    def _add(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed(x) + 1

    @f.variant(MUL)
    def _mul(x, *, proceed):  # type: ignore[no-untyped-def]
        return proceed(x) * 3

    return f


def test_c25_activation_order_sets_chain_order(f: Any) -> None:
    with activate(ADD), activate(MUL):
        assert f(2) == 9
    with activate(MUL), activate(ADD):
        assert f(2) == 7


def test_c26_interleaved_global_deactivation(f: Any) -> None:
    activate_globally(ADD)
    activate_globally(MUL)
    deactivate_globally(ADD)
    assert f(2) == 6
    deactivate_globally(MUL)


def test_c27_a_layer_without_partial_is_transparent(f: Any) -> None:
    with activate(Layer("Other")):
        assert f(2) == 2


def test_c27a_priority_beats_recency_and_hedges_sit_innermost(layered: Layered) -> None:
    high = Layer("HIGH", priority=10)

    @layered
    def g(x: int) -> str:
        return "b"

    @g.variant(high)
    def _h(x, *, proceed):  # type: ignore[no-untyped-def]
        return "H(" + proceed() + ")"

    low = Layer("LOW")

    @g.variant(low)
    def _l(x, *, proceed):  # type: ignore[no-untyped-def]
        return "L(" + proceed() + ")"

    with activate(high), activate(low):
        assert g(0) == "H(L(b))"

    hedge = Layer("hedge", when=lambda ctx: ctx["on"])

    @layered(hedges=HedgeGroup("g2", [hedge]))
    def g2() -> str:
        return "b"

    @g2.variant(hedge)
    def _hedge(*, proceed):  # type: ignore[no-untyped-def]
        return "hedge"

    @g2.variant(high)
    def _high(*, proceed):  # type: ignore[no-untyped-def]
        return "H(" + proceed() + ")"

    with using_context({"on": True}), activate(high):
        assert g2() == "H(hedge)"


# ---------------------------------------------------------------- D: predicate layers


def make_rule(layered: Layered, n: int, policy: Any = "last"):  # type: ignore[no-untyped-def]
    members = [Layer(f"R.{i + 1}", when=lambda ctx, i=i: ctx[i]) for i in range(n)]
    group = HedgeGroup("R", members, policy=policy)

    @layered(hedges=group)
    def rule() -> int:
        return 0

    for i, m in enumerate(members):

        def make(i: int, m: Layer) -> None:
            @rule.variant(m)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return i + 1

        make(i, m)
    return rule, group, members


def test_d28_predicate_layers_follow_their_predicates(layered: Layered) -> None:
    rule, _, _ = make_rule(layered, 2)
    ctx = [True, False]
    with using_context(ctx):
        assert rule() == 1
        ctx[0], ctx[1] = False, True
        assert rule() == 2
        ctx[1] = False
        assert rule() == 0


def test_d29_current_layers_and_explain(layered: Layered) -> None:
    rule, _, members = make_rule(layered, 2)
    assert current_layers() == ()
    assert set(members) <= set(current_layers(context=[True, True]))
    assert not set(members) & set(current_layers(context=[False, False]))
    e = explain(rule, context=[True, False])
    assert e.selected == {"R": "R.1"} and e.chain == ("R.1",)


def test_d30_each_predicate_runs_at_most_once_per_dispatch_and_the_chain_is_frozen(layered: Layered) -> None:
    calls = {"a": 0, "b": 0}
    state = {"a": True, "b": False}

    def pa(ctx):  # type: ignore[no-untyped-def]
        calls["a"] += 1
        return state["a"]

    def pb(ctx):  # type: ignore[no-untyped-def]
        calls["b"] += 1
        return state["b"]

    a, b = Layer("a", when=pa), Layer("b", when=pb)

    @layered(hedges=HedgeGroup("g", [a, b], policy=nested))
    def h() -> str:
        return "base"

    @h.variant(a)
    def _a(*, proceed):  # type: ignore[no-untyped-def]
        state["a"] = False  # changes the world mid-dispatch
        return "a:" + proceed()

    @h.variant(b)
    def _b(*, proceed):  # type: ignore[no-untyped-def]
        return "b"

    with using_context(None):
        assert h() == "a:base"
    assert calls == {"a": 1, "b": 1}


def test_d31_raising_predicate_aborts_or_takes_the_declared_choice(layered: Layered) -> None:
    boom = Layer("boom", when=lambda ctx: 1 / 0)
    safe = Layer("safe", when=lambda ctx: False)
    records: list[DispatchRecord] = []
    ran: list[str] = []

    def build(on_error: str):  # type: ignore[no-untyped-def]
        b, s = Layer("boom", when=lambda ctx: 1 / 0), Layer("safe", when=lambda ctx: False)

        @layered(hedges=HedgeGroup("G", [s, b], on_error=on_error))
        def r() -> str:
            ran.append("base")
            return "default"

        @r.variant(s)
        def _(*, proceed):  # type: ignore[no-untyped-def]
            ran.append("safe")
            return "conservative"

        return r

    del boom, safe
    remove = on_dispatch(records.append)
    try:
        with using_context(None):
            with pytest.raises(HedgeEvaluationError) as info:
                build("raise")()
            assert isinstance(info.value.__cause__, ZeroDivisionError)
            assert ran == [] and records[-1].undetermined
            assert build("default")() == "default"
            assert build("safe")() == "conservative"
            assert records[-1].undetermined and records[-1].selected == {"G": "safe"}
    finally:
        remove()


# ---------------------------------------------------------------- E: groups


def test_e32_two_members_never_in_one_chain_even_when_forced(layered: Layered) -> None:
    rule, _, members = make_rule(layered, 3)
    with using_context([True, True, True]):
        assert rule() == 3
        with activate(members[0]):
            assert rule() == 1  # forced member replaces selection, never both


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_e33_policies_over_every_combination(layered: Layered, n: int) -> None:
    last, _, _ = make_rule(layered, n, "last")
    nst, _, _ = make_rule(layered, n, nested)
    first, _, _ = make_rule(layered, n, "first")
    for values in itertools.product([False, True], repeat=n):
        want_last = max((i + 1 for i, v in enumerate(values) if v), default=0)
        k = 0
        while k < n and values[k]:
            k += 1
        with using_context(list(values)):
            assert last() == want_last
            assert nst() == k
            assert first() == next((i + 1 for i, v in enumerate(values) if v), 0)
        assert policy_last(values) == (want_last - 1 if want_last else None)
        assert nested(values) == (k - 1 if k else None)
        assert policy_first(values) == next((i for i, v in enumerate(values) if v), None)


SLEEC_EXAMPLES = [
    # the SLEEC language reference §8, (condition values, last_wins clause, nested clause); 0 = default
    ([False, False], 0, 0),
    ([True, False], 1, 1),
    ([False, True], 2, 0),
    ([True, True], 2, 2),  # ex. 1 and 2
    ([False, True, False], 2, 0),
    ([False, False, True], 3, 0),
    ([False, True, True], 3, 0),  # ex. 3, DAISY
    ([True, False, False], 1, 1),
    ([True, True, False], 2, 2),
]


@pytest.mark.parametrize(("values", "last_clause", "nested_clause"), SLEEC_EXAMPLES)
def test_e33_worked_examples_of_the_language_reference(
    layered: Layered, values: list[bool], last_clause: int, nested_clause: int
) -> None:
    last, _, _ = make_rule(layered, len(values), "last")
    nst, _, _ = make_rule(layered, len(values), nested)
    with using_context(values):
        assert (last(), nst()) == (last_clause, nested_clause)


def test_e33_prefix_closed_conditions_make_the_modes_agree(layered: Layered) -> None:
    last, _, _ = make_rule(layered, 3, "last")
    nst, _, _ = make_rule(layered, 3, nested)
    for t in (30, 18, 16, 10):  # graded: t < 19, t < 17, t < 12 are prefix-closed
        values = [t < 19, t < 17, t < 12]
        with using_context(values):
            assert last() == nst()


def test_e34_weak_forcing_replaces_and_release_returns_to_predicates(layered: Layered) -> None:
    a, b = Layer("a", when=lambda c: False), Layer("b", when=lambda c: False)
    c = Layer("c", when=lambda c: True)
    group = HedgeGroup("W", [a, b, c], exclusion="weak")

    @layered(hedges=group)
    def r() -> str:
        return "base"

    for m in (a, b, c):

        def make(m: Layer) -> None:
            @r.variant(m)
            def _(*, proceed):  # type: ignore[no-untyped-def]
                return m.name

        make(m)
    with using_context(None):
        with activate(a):
            assert r() == "a"
            with activate(b):
                assert r() == "b"
            assert r() == "a"  # leaving the block restores the outer scope, as scopes do
        activate_globally(a)
        activate_globally(b)  # weak: replaces a
        assert r() == "b"
        deactivate_globally(b)
        assert r() == "c"  # back to predicate selection, not to a


def test_e35_strict_exclusion_raises_and_changes_nothing() -> None:
    x, y = Layer("x"), Layer("y")
    LayerGroup("modes", [x, y])
    with activate(x):
        with pytest.raises(ExclusionError), activate(y):
            pass
        assert [la.name for la in current_layers()] == ["x"]
    activate_globally(x)
    with pytest.raises(ExclusionError):
        activate_globally(y)
    assert [la.name for la in current_layers()] == ["x"]
    deactivate_globally(x)


def test_e37_activation_hook_can_veto() -> None:
    vetoed = Layer("vetoed")

    def hook(layer: Layer, scope: str) -> None:
        if layer is vetoed:
            raise PermissionError("not now")

    with activate(vetoed):
        pass  # caches a transition before the hook exists
    remove = add_activation_hook(hook)
    try:
        with pytest.raises(PermissionError), activate(vetoed):
            pass
        with pytest.raises(PermissionError):
            activate_globally(vetoed)
        assert current_layers() == ()
    finally:
        remove()


def test_e38_enter_exit_hooks_fire_once_per_effective_change() -> None:
    la = Layer("hooked")
    log: list[str] = []
    la.on_enter(lambda layer: log.append("enter"))
    la.on_exit(lambda layer: log.append("exit"))
    activate_globally(la)
    activate_globally(la)
    with activate(la):
        pass
    deactivate_globally(la)
    assert log == ["enter"]
    deactivate_globally(la)
    assert log == ["enter", "exit"]
    with activate(la), activate(la):
        pass
    assert log == ["enter", "exit", "enter", "exit"]


def test_d29_explain_needs_no_context_when_no_group_selects(f: Any) -> None:
    with activate(ADD):
        e = explain(f, 1)  # no using_context: f has no hedge group
    assert e.chain == ("ADD",) and e.selected == {} and str(e).endswith("f: ADD -> base")


def test_e35_a_remembered_activation_meets_a_rival_activated_globally_since() -> None:
    """Entering the same block again reuses its remembered transition (SD4), unless a
    global change has since made a rival active: then exclusion is judged again -- strict
    raises, weak replaces -- and the block never runs with both members active."""
    x, y = Layer("x"), Layer("y")
    LayerGroup("modes", [x, y])
    with activate(x):  # remembered: no layer -> x
        assert [la.name for la in current_layers()] == ["x"]
    activate_globally(y)
    try:
        with pytest.raises(ExclusionError), activate(x):
            pass
        assert [la.name for la in current_layers()] == ["y"]
    finally:
        deactivate_globally(y)
    with activate(x):  # no global rival any more: the remembered transition serves again
        assert [la.name for la in current_layers()] == ["x"]
    u, w = Layer("u"), Layer("w")
    LayerGroup("weak modes", [u, w], exclusion="weak")
    with activate(u):
        pass
    activate_globally(w)
    try:
        with activate(u):
            assert [la.name for la in current_layers()] == ["u"]  # w replaced, not both
        assert [la.name for la in current_layers()] == ["w"]
    finally:
        deactivate_globally(w)
