"""The deadline search: exact at its step, against a brute-force oracle, in few questions."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from cosleec.lang import analyse
from cosleec.lang import ast as A
from cosleec.repair import deadlines

thresholds = st.integers(min_value=0, max_value=300)
hints = st.integers(min_value=0, max_value=300)
ceilings = st.none() | st.integers(min_value=1, max_value=300)


def _top(hint: int, ceiling: int | None) -> int:
    return ceiling if ceiling is not None else max(hint, 1) << deadlines.DOUBLINGS


@given(thresholds, hints, ceilings)
def test_largest_is_the_largest_value_that_works(t: int, hint: int, ceiling: int | None) -> None:
    asked: list[int] = []

    def works(n: int) -> bool:
        asked.append(n)
        return n <= t

    top = _top(hint, ceiling)
    expected = max((n for n in range(1, top + 1) if n <= t), default=None)
    assert deadlines.largest(works, hint, ceiling) == expected
    assert all(1 <= n <= top for n in asked)  # never outside the range
    assert len(asked) <= 2 * top.bit_length() + 2


@given(thresholds, hints, ceilings)
def test_smallest_is_the_smallest_value_that_works(t: int, hint: int, ceiling: int | None) -> None:
    asked: list[int] = []

    def works(n: int) -> bool:
        asked.append(n)
        return n >= t

    top = _top(hint, ceiling)
    expected = min((n for n in range(1, top + 1) if n >= t), default=None)
    assert deadlines.smallest(works, hint, ceiling) == expected
    assert all(1 <= n <= top for n in asked)
    assert len(asked) <= 2 * top.bit_length() + 2


def rule(text: str) -> A.Rule:
    src = f"def_start event E event X event Y def_end rule_start {text} rule_end"
    r = analyse(src)
    assert r.spec is not None, r.render()
    return r.spec.rules[0]


def test_the_items_whose_deadline_can_move() -> None:
    r = rule("R1 when E then X and not X within 3 minutes and Y within 2 seconds and not Y")
    assert list(deadlines.timed(r, "X", False)) == [(0, None)]  # an obligation without a deadline
    assert list(deadlines.timed(r, "X", True)) == [(1, 180)]
    assert list(deadlines.timed(r, "Y", True)) == []  # a prohibition without a window: nothing to move
    assert list(deadlines.timed_obligations(r)) == [(2, 2)]


def test_a_moved_deadline_reads_back_as_written() -> None:
    r = rule("R1 when E then X eventually")
    moved = deadlines.with_deadline(r, 0, 7, "minutes")
    o = moved.response.items[0].occurrence
    assert o.limit is not None and deadlines.seconds(o.limit.hi) == 420 and not o.eventually
