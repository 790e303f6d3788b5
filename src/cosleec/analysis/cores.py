"""Minimal unsatisfiable cores that do not depend on the solver's mood.

z3's own core is *a* core, not a minimal one, and which one it is can change with the
solver's version, seed or heuristics. :func:`minimal_core` starts from every candidate and
drops them one at a time in file order, keeping a candidate only when the question becomes
satisfiable without it. Each step depends only on whether a set of rules is satisfiable -- a
fact about the rules, not about the solver -- so the same input gives the same core every
run, and no rule of it can be dropped (it is minimal, though not necessarily the smallest).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import z3

from cosleec.analysis.encoding import Encoding


class Undecided(Exception):
    """The solver answered ``unknown`` (a timeout, or non-linear arithmetic it gave up on)."""


def minimal_core(
    enc: Encoding, fixed: Sequence[Any], candidates: Sequence[tuple[str, Any]]
) -> tuple[str, ...]:
    """The names of a minimal subset of ``candidates`` (name, literal) that, with every
    ``fixed`` literal, is unsatisfiable. The whole set must be unsatisfiable."""
    keep = list(candidates)
    for c in list(candidates):
        trial = [k for k in keep if k is not c]
        answer = enc.check([*fixed, *(lit for _, lit in trial)])
        if answer == z3.unsat:
            keep = trial
        elif answer == z3.unknown:
            raise Undecided(str(enc.solver.reason_unknown()))
    return tuple(name for name, _ in keep)
