"""Minimal cores: minimal, and the same whatever the order the solver would have preferred."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import z3
from hypothesis import given
from hypothesis import strategies as st

from cosleec.analysis import cores


class Oracle:
    """An encoding stand-in: a set of literals is unsatisfiable iff it contains a conflict."""

    def __init__(self, conflicts: list[frozenset[str]]) -> None:
        self.conflicts = conflicts
        self.asked = 0

    def check(self, lits: Sequence[Any]) -> Any:
        self.asked += 1
        names = set(lits)
        return z3.unsat if any(c <= names for c in self.conflicts) else z3.sat


NAMES = [f"R{i}" for i in range(9)]
conflict_sets = st.lists(
    st.frozensets(st.sampled_from(NAMES), min_size=1, max_size=3), min_size=1, max_size=4
)


@given(conflict_sets)
def test_the_core_is_a_conflict_and_no_member_can_be_dropped(conflicts: list[frozenset[str]]) -> None:
    core = set(cores.minimal_core(Oracle(conflicts), [], [(n, n) for n in NAMES]))  # type: ignore[arg-type]
    assert any(c <= core for c in conflicts)
    for name in core:
        assert not any(c <= core - {name} for c in conflicts)


@given(conflict_sets)
def test_the_core_is_the_one_preferred_in_file_order(conflicts: list[frozenset[str]]) -> None:
    """Deletion from the end keeps the earliest-ending conflict: QuickXplain must agree with it."""
    keep = list(NAMES)
    for name in reversed(NAMES):
        trial = [k for k in keep if k != name]
        if any(c <= set(trial) for c in conflicts):
            keep = trial
    core = cores.minimal_core(Oracle(conflicts), [], [(n, n) for n in NAMES])  # type: ignore[arg-type]
    assert list(core) == keep


def test_a_single_culprit_among_many_takes_few_questions() -> None:
    names = [f"R{i}" for i in range(64)]
    oracle = Oracle([frozenset({"R40"})])
    assert cores.minimal_core(oracle, [], [(n, n) for n in names]) == ("R40",)  # type: ignore[arg-type]
    assert oracle.asked <= 16  # deletion one at a time would ask 64 questions
