"""Which clause of a rule applies: the one definition of hedge (``unless``) semantics.

A rule ``when T then R0 unless C1 then R1 unless C2 then R2`` has a default response
(clause 0) and one clause per ``unless``. Given the truth value of each clause
condition, :func:`choose` says which clause applies:

- :attr:`HedgeSemantics.LAST_WINS` (SLEEC-TK and LEGOS-SLEEC): the last clause whose
  condition holds; the default when none holds.
- :attr:`HedgeSemantics.NESTED` (the CO-SLEEC paper's formula): clause i iff conditions
  1..i all hold and condition i+1 does not; the default when condition 1 does not hold.

A condition whose value is unknown (a measure with no value) is ``None``; the
:class:`Unknowns` policy says how to read it. Under ``UNDETERMINED`` (the default, fail
closed) :func:`choose` answers ``None`` whenever the unknown values could change the
answer, and a definite clause whenever they could not (``last-wins`` with a later
condition that holds needs nothing before it).

Everything that chooses a clause calls :func:`choose`: the runtime's Layer Manager, a
braced inner response's own clauses, the checker's unreachable-clause lint
(:func:`reachable`), the explanation of a decision (:func:`decisive`), and the Layer
Manager node. The reference semantics states clause choice again, independently, on
purpose: a property test holds the two equal.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Sequence
from enum import StrEnum

from cosleec.errors import ConfigurationError

__all__ = ["HedgeSemantics", "Unknowns", "blockers", "candidates", "choose", "decisive", "reachable"]


class HedgeSemantics(StrEnum):
    """How the ``unless`` clauses of one rule combine (see the module docstring)."""

    LAST_WINS = "last-wins"  # SLEEC: the last clause whose condition holds
    NESTED = "nested"  # the paper: clause i iff conditions 1..i hold and i+1 does not


class Unknowns(StrEnum):
    """How a condition with an unknown value is read when choosing a clause."""

    UNDETERMINED = "undetermined"  # fail closed: no clause, the decision is undetermined
    FALSE = "false"  # read as false
    TRUE = "true"  # read as true


def choose(
    values: Sequence[bool | None],
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
    unknown: Unknowns = Unknowns.UNDETERMINED,
) -> int | None:
    """The clause that applies: 0 for the default, i for clause i, None if undetermined.

    ``values[i - 1]`` is the value of clause i's condition (``None``: unknown).

    Example::

        choose([True, False])                      # 1: the last clause that holds
        choose([True, None])                       # None: clause 2 might hold
        choose([None, True])                       # 2: whatever clause 1 is
        choose([True, True, False], HedgeSemantics.NESTED)  # 2
    """
    # == rather than `is`: the options are StrEnums, and a plain "nested" must mean the same
    values = _read(values, unknown)
    if semantics == HedgeSemantics.LAST_WINS:
        for i in range(len(values) - 1, -1, -1):
            v = values[i]
            if v is None:
                return None
            if v:
                return i + 1
        return 0
    if semantics == HedgeSemantics.NESTED:
        held = 0
        for v in values:
            if v is None:
                return None
            if not v:
                break
            held += 1
        return held
    raise ConfigurationError(
        f"unknown hedge semantics {semantics!r}; expected one of {', '.join(HedgeSemantics)}"
    )


def candidates(
    values: Sequence[bool | None], semantics: HedgeSemantics = HedgeSemantics.LAST_WINS
) -> frozenset[int]:
    """Every clause that :func:`choose` could select once the unknown values (``None``) are known.

    What an undetermined decision must allow for: the runtime enforces the prohibitions of
    every candidate, so not knowing a value never allows what one of its readings forbids.
    With more than :data:`MAX_FREE_CONDITIONS` unknown values every clause is a candidate.
    """
    free = [i for i, v in enumerate(values) if v is None]
    if len(free) > MAX_FREE_CONDITIONS:
        return frozenset(range(len(values) + 1))
    out: set[int] = set()
    filled = list(values)
    for bits in itertools.product((False, True), repeat=len(free)):
        for i, b in zip(free, bits):
            filled[i] = b
        chosen = choose(filled, semantics)
        assert chosen is not None
        out.add(chosen)
    return frozenset(out)


def decisive(
    values: Sequence[bool | None],
    clause: int | None,
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
    unknown: Unknowns = Unknowns.UNDETERMINED,
) -> tuple[int, ...]:
    """The clauses (1-based) whose condition values decided ``clause``, for explanations.

    A value is decisive when forgetting it would leave the choice undetermined; the result
    is found with :func:`choose` itself, so it follows whatever the semantics are. Under
    an ``unknown`` policy that reads unknown values as true or false, an unknown value
    that decided the choice is decisive like any other. For an undetermined choice: the
    clauses whose value is unknown.
    """
    if clause is None:
        return tuple(i + 1 for i, v in enumerate(values) if v is None)
    if semantics == HedgeSemantics.LAST_WINS and 0 <= clause <= len(values):
        # what the search below finds, without its n choices of n steps each: the clause
        # chosen and every later one (known false) decided it, the earlier ones did not;
        # with none chosen, every value did (a test checks this against the search)
        return tuple(range(clause or 1, len(values) + 1))
    return _decisive_by_search(values, clause, semantics, unknown)


def _decisive_by_search(
    values: Sequence[bool | None], clause: int, semantics: HedgeSemantics, unknown: Unknowns
) -> tuple[int, ...]:
    """:func:`decisive` for any semantics: forget each value in turn, keep it forgotten
    unless the choice changes."""
    known = list(_read(values, unknown))  # decide on the values as the policy read them
    for i in range(len(known)):
        kept = known[i]
        known[i] = None
        if choose(known, semantics) != clause:
            known[i] = kept
    return tuple(i + 1 for i, v in enumerate(known) if v is not None)


_UNKNOWNS = frozenset(Unknowns)


def _read(values: Sequence[bool | None], unknown: Unknowns) -> Sequence[bool | None]:
    """The values as the ``unknown`` policy reads them (unchanged under UNDETERMINED)."""
    if unknown == Unknowns.UNDETERMINED:
        return values
    if unknown not in _UNKNOWNS:
        raise ConfigurationError(
            f"unknown policy {unknown!r} for unknown values; expected one of {', '.join(Unknowns)}"
        )
    read = unknown == Unknowns.TRUE
    return [read if v is None else v for v in values]


# Enumerating every assignment costs 2**n calls of `choose`; past this many free conditions
# the lint stays silent rather than slow (rules that long are generated, not written).
MAX_FREE_CONDITIONS = 12


def reachable(
    n: int,
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
    *,
    fixed: dict[int, bool] | None = None,
    implies: Callable[[int, int], bool] | None = None,
) -> frozenset[int] | None:
    """The clauses (0 = default) that some situation selects, given what is known statically.

    ``fixed`` maps a clause (1-based) to the constant value of its condition (``false``,
    ``true``); ``implies(i, j)`` says that whenever condition i holds, condition j holds
    too. Every assignment consistent with those facts is tried with :func:`choose`. Returns
    None when there are more than :data:`MAX_FREE_CONDITIONS` free conditions.
    """
    fixed = fixed or {}
    free = [i for i in range(1, n + 1) if i not in fixed]
    if len(free) > MAX_FREE_CONDITIONS:
        return None
    pairs = [(i, j) for i in range(1, n + 1) for j in range(1, n + 1) if i != j and implies and implies(i, j)]
    if not fixed and not pairs:
        return _unconstrained(n, semantics)  # most rules: nothing known, the same answer for every n
    return _enumerate(n, semantics, fixed, free, pairs)


@functools.lru_cache(maxsize=64)
def _unconstrained(n: int, semantics: HedgeSemantics) -> frozenset[int]:
    return _enumerate(n, semantics, {}, list(range(1, n + 1)), [])


def _enumerate(
    n: int, semantics: HedgeSemantics, fixed: dict[int, bool], free: list[int], pairs: list[tuple[int, int]]
) -> frozenset[int]:
    """Every clause :func:`choose` selects over the assignments consistent with the facts."""
    out: set[int] = set()
    for bits in itertools.product((False, True), repeat=len(free)):
        value = dict(fixed)
        value.update(zip(free, bits))
        if any(value[i] and not value[j] for i, j in pairs):
            continue  # no situation makes condition i hold without condition j
        chosen = choose([value[i] for i in range(1, n + 1)], semantics)
        if chosen is not None:
            out.add(chosen)
    return frozenset(out)


def blockers(
    clause: int,
    n: int,
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
    *,
    fixed: dict[int, bool] | None = None,
    implies: Callable[[int, int], bool] | None = None,
) -> tuple[int, ...]:
    """The other clauses whose static facts keep ``clause`` from ever being chosen.

    Clause j is a blocker when forgetting every fact that involves j (its constant value,
    and the implications to or from it) makes ``clause`` reachable (:func:`reachable`).
    Used to say *why* a clause is dead without restating the semantics.
    """
    fixed = fixed or {}
    now = reachable(n, semantics, fixed=fixed, implies=implies)
    if now is None or clause in now:
        return ()  # not dead (or too many conditions to tell): nothing blocks it
    out = []
    for j in range(1, n + 1):
        if j == clause:
            continue
        without = {k: v for k, v in fixed.items() if k != j}

        def implies_without(a: int, b: int, j: int = j) -> bool:
            return j not in (a, b) and implies is not None and implies(a, b)

        chosen = reachable(n, semantics, fixed=without, implies=implies_without)
        if chosen is not None and clause in chosen:
            out.append(j)
    return tuple(out)
