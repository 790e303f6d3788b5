"""Stats: typed counters that also read as the mapping they were before they had a type."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.runtime.stats import Stats

NAMES = (
    "updates",
    "rejected",
    "events",
    "decisions",
    "refused",
    "violations",
    "undetermined",
    "task_failures",
    "conflicts",
    "cancelled",
)


def test_every_counter_starts_at_zero_in_the_documented_order() -> None:
    s = Stats()
    assert s.keys() == NAMES
    assert list(s) == list(NAMES)
    assert s.to_json() == dict.fromkeys(NAMES, 0)


@given(st.fixed_dictionaries({n: st.integers(0, 10**9) for n in NAMES}))
def test_the_mapping_view_reads_what_the_attributes_hold(counts: dict[str, int]) -> None:
    s = Stats()
    for name, value in counts.items():
        setattr(s, name, value)  # as the runtime counts: one attribute at a time
    assert {n: s[n] for n in NAMES} == counts
    assert dict(s) == counts  # keys() and __getitem__: dict() reads it as a mapping
    assert s.to_json() == counts
    assert dataclasses.asdict(s) == counts


@given(st.sampled_from(NAMES), st.integers(1, 50))
def test_counting_one_counter_changes_only_it(name: str, times: int) -> None:
    s = Stats()
    for _ in range(times):
        setattr(s, name, getattr(s, name) + 1)
    assert dict(s) == {n: times if n == name else 0 for n in NAMES}


@pytest.mark.parametrize("name", ["keys", "to_json", "__slots__", "Updates", "", "updates "])
def test_a_name_that_is_no_counter_is_a_key_error_not_an_attribute(name: str) -> None:
    with pytest.raises(KeyError):
        Stats()[name]


def test_a_misspelt_counter_cannot_be_set() -> None:
    s = Stats()
    with pytest.raises(AttributeError):
        s.refusd = 1  # type: ignore[attr-defined]
