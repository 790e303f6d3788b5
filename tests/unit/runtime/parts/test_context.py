"""Context: the express lane's one-pass boolean update against validate-then-apply.

``Context.apply_booleans`` is the hot path's update of boolean measures; the general path
is ``validate`` then ``apply``. On generated contexts and updates (boolean, numeric and
scale measures; values of every kind, unknown names) the two must leave the same values,
stamps and version and agree on whether anything changed -- or ``apply_booleans`` must
decline, changing nothing, exactly when the update holds anything but boolean values of
boolean measures.
"""

from __future__ import annotations

import copy

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.runtime.context import Context
from cosleec.runtime.errors import ContextError
from cosleec.runtime.values import MeasureSpec

from ..lookalike import Lookalike

MEASURES = {
    "a": MeasureSpec("a", "boolean"),
    "b": MeasureSpec("b", "boolean"),
    "c": MeasureSpec("c", "boolean"),
    "n": MeasureSpec("n", "numeric"),
    "s": MeasureSpec("s", "scale", ("low", "high")),
}


NAMES = st.sampled_from([*MEASURES, "zz", Lookalike("b")])
VALUES = st.sampled_from([True, False, 0, 1, 1.0, 0.0, 2, "low", "x", None])
UPDATES = st.dictionaries(NAMES, VALUES, max_size=5)  # type: ignore[arg-type]


def general(ctx: Context, update: dict[str, object], now: float) -> set[str] | None:
    """validate then apply (None: rejected, nothing changed)."""
    try:
        stored = ctx.validate(update)
    except ContextError:
        return None
    return ctx.apply(stored, now)


def state(ctx: Context) -> tuple[object, ...]:
    return ({k: (type(v), v) for k, v in ctx.values.items()}, dict(ctx.stamps), ctx.version)


@given(st.lists(UPDATES, max_size=4), UPDATES)
def test_the_one_pass_update_agrees_with_validate_then_apply(
    before: list[dict[str, object]], update: dict[str, object]
) -> None:
    ctx = Context(MEASURES)
    for i, earlier in enumerate(before):
        general(ctx, earlier, float(i))
    other = copy.deepcopy(ctx)
    got = ctx.apply_booleans(update, 9.0)
    only_booleans = all(
        type(k) is str and MEASURES.get(k, MEASURES["n"]).kind == "boolean" and type(v) is bool
        for k, v in update.items()
    )
    if got is None:
        assert not only_booleans
        assert state(ctx) == state(other)  # declined: nothing changed
        return
    assert only_booleans
    want = general(other, update, 9.0)
    assert want is not None  # booleans of boolean measures are never rejected
    assert got == bool(want)
    assert state(ctx) == state(other)


def test_an_update_that_changes_nothing_stamps_but_keeps_the_version() -> None:
    ctx = Context(MEASURES)
    assert ctx.apply_booleans({"a": True, "b": False}, 1.0) is True
    assert ctx.version == 1
    assert ctx.apply_booleans({"a": True}, 2.0) is False
    assert (ctx.version, ctx.stamps["a"], ctx.stamps["b"]) == (1, 2.0, 1.0)
    assert ctx.apply_booleans({"a": 1}, 3.0) is None  # 1 is not a boolean value
    assert ctx.apply_booleans({"n": True}, 3.0) is None  # n is not a boolean measure


def test_a_key_that_only_compares_equal_to_a_name_names_no_measure() -> None:
    ctx = Context(MEASURES)
    assert ctx.apply_booleans({Lookalike("b"): True}, 1.0) is None  # type: ignore[dict-item]
    with pytest.raises(ContextError, match="named by a string"):
        ctx.validate({Lookalike("b"): True})  # type: ignore[dict-item]
    assert ctx.values == {} and ctx.version == 0


@given(st.lists(UPDATES, max_size=6))
def test_a_context_record_made_when_read_is_the_one_made_at_once(updates: list[dict[str, object]]) -> None:
    """``record_of`` keeps what a ``context`` record shows (the values just applied, scale
    literals by name, the version then) and makes, whenever it is called -- after later
    updates too -- what ``external`` showed at once."""
    ctx = Context(MEASURES)
    kept = []
    for i, update in enumerate(updates):
        try:
            stored = ctx.validate(update)
        except ContextError:
            continue
        changed = ctx.apply(stored, float(i))
        if changed:
            at_once = {"values": ctx.external(sorted(changed)), "version": ctx.version}
            kept.append((at_once, ctx.record_of(stored, changed)))
    for at_once, make in kept:
        assert make() == at_once
        assert make() == at_once  # (each call makes the same record)
