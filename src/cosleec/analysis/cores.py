"""Minimal unsatisfiable cores that do not depend on the solver's mood.

z3's own core is *a* core, not a minimal one, and which one it is can change with the
solver's version, seed or heuristics. :func:`minimal_core` never reads it: it asks only
whether sets of candidates (in file order) are satisfiable -- a fact about the rules, not
about the solver -- so the same input gives the same core every
run, and no rule of it can be dropped (it is minimal, though not necessarily the smallest).
The search is QuickXplain's, which asks far fewer questions than dropping one at a time.
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
    ``fixed`` literal, is unsatisfiable. The whole set must be unsatisfiable.

    QuickXplain (Junker, 2004): the core preferred in file order -- the one whose latest
    member is as early as possible, and so on -- found by halving, in about ``2 k log(n/k)``
    questions for a core of ``k`` among ``n`` candidates. Which core it returns depends only
    on which subsets are satisfiable.
    """

    def unsat(lits: Sequence[tuple[str, Any]]) -> bool:
        answer = enc.check([*fixed, *(lit for _, lit in lits)])
        if answer == z3.unknown:
            raise Undecided(str(enc.solver.reason_unknown()))
        return bool(answer == z3.unsat)

    def explain(
        background: list[tuple[str, Any]], added: bool, cands: list[tuple[str, Any]]
    ) -> list[tuple[str, Any]]:
        if added and unsat(background):
            return []
        if len(cands) == 1:
            return cands
        half = len(cands) // 2
        first, second = cands[:half], cands[half:]
        d2 = explain(background + first, bool(first), second)
        d1 = explain(background + d2, bool(d2), first)
        return d1 + d2

    cands = list(candidates)
    if not cands or unsat([]):
        return ()
    core = explain([], False, cands)
    order = {id(c): i for i, c in enumerate(cands)}
    return tuple(name for name, _ in sorted(core, key=lambda c: order[id(c)]))
