"""Two versions of a rule file in one specification, for the behavioural diff of a patch
(:mod:`cosleec.repair.behaviour`).

One encoding can answer questions about either version when it holds both: the union of
their declarations, every rule of ``before`` under its own name, and every rule of ``after``
that differs from ``before``'s rule of that name (edited or added) under the name with a
prime (``R3'``); a rule both versions share is encoded once. Which version a question asks
about is then a choice of assumption literals (:meth:`Encoding.rule_lit`), as the analysis
chooses "every rule but this one" for redundancy.

A constant whose value the patch changes is written into ``after``'s rules as its value,
so that one table of constants serves both (a rule that reads it differs then, even when
its text does not).

Declared priorities (the file's and those given besides) are each version's, closed: a
firing of a higher rule cancels a lower one whatever the question assumes of the higher
rule, so a rule that some version's priorities can cancel differently -- other rules above
it, or a rule above it that differs -- differs too, and each of its versions keeps its own
version's pairs. A pair whose lower rule both versions share is then the same in both.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TypeVar

from cosleec.lang import Specification, closure, pairs
from cosleec.lang import ast as A

PRIME = "'"
"""What ``after``'s version of a rule that differs is called by: its name and a prime."""

N = TypeVar("N")


@dataclass(frozen=True)
class Sides:
    """``before`` and ``after`` in one specification (``spec``, with ``constants``).

    ``before`` and ``after`` name the rules of each version (names in ``spec``);
    ``removed`` are ``before``'s rules that ``after`` removes or edits, ``added`` are
    ``after``'s rules that ``before`` does not have as they are (named with a prime);
    ``relations_before`` and ``relations_after`` index ``spec.relations``.
    """

    spec: Specification
    constants: dict[str, int]
    before: tuple[str, ...]
    after: tuple[str, ...]
    removed: tuple[A.Rule, ...]
    added: tuple[A.Rule, ...]
    relations_before: tuple[int, ...]
    relations_after: tuple[int, ...]

    def changed(self, event: str) -> tuple[tuple[A.Rule, ...], tuple[A.Rule, ...]]:
        """The rules triggered by ``event`` that differ: (``before``'s, ``after``'s)."""
        return (
            tuple(r for r in self.removed if r.trigger.event == event),
            tuple(r for r in self.added if r.trigger.event == event),
        )

    @property
    def events(self) -> tuple[str, ...]:
        """The trigger events of the rules that differ, each once, in file order."""
        return tuple(dict.fromkeys(r.trigger.event for r in (*self.removed, *self.added)))


def original(name: str) -> str:
    """A rule's name in its own file (without the prime :func:`merge` gives ``after``'s)."""
    return name.removesuffix(PRIME)


def merge(
    before: Specification,
    after: Specification,
    constants_before: dict[str, int],
    constants_after: dict[str, int],
    given: Iterable[tuple[str, str]] = (),
) -> Sides | str:
    """Both versions in one specification, or why they cannot be (a sentence): a measure
    whose type the patch changes. ``given``: priorities declared besides the files (both
    versions'), as ``(higher, lower)``."""
    kinds = {m.name: m.type for m in before.measures}
    for m in after.measures:
        if m.name in kinds and kinds[m.name] != m.type:
            return f"the patch changes the type of measure {m.name} ({kinds[m.name]} to {m.type})"
    moved = {n: v for n, v in constants_after.items() if n in constants_before and constants_before[n] != v}
    constants = {
        **{n: v for n, v in constants_after.items() if n not in constants_before},
        **constants_before,
    }
    theirs = [inline(r, moved) for r in after.rules]
    above_b, above_a = closure([*given, *pairs(before)]), closure([*given, *pairs(after)])
    differs = cancelled_differently(before.rules, theirs, above_b, above_a)
    removed = tuple(r for r in before.rules if r.name in differs)
    added = tuple(dataclasses.replace(r, name=r.name + PRIME) for r in theirs if r.name in differs)
    primed = {original(r.name) for r in added}
    ranks = dict.fromkeys(A.Priority(h, lo) for h, lo in sorted(above_b))
    for h, lo in sorted(above_a):
        ranks.setdefault(A.Priority(h + PRIME if h in primed else h, lo + PRIME if lo in primed else lo))
    relations = list(before.relations)
    for rel in (inline(x, moved) for x in after.relations):
        if rel not in relations:
            relations.append(rel)
    after_relations = [relations.index(inline(x, moved)) for x in after.relations]
    declared = {getattr(d, "name", None) for d in before.definitions}
    spec = Specification(
        (*before.definitions, *(d for d in after.definitions if getattr(d, "name", None) not in declared)),
        (*before.rules, *added),
        relations=tuple(relations),
        priorities=tuple(ranks),
        dialect=before.dialect,
        path=before.path,
    )
    return Sides(
        spec,
        constants,
        tuple(r.name for r in before.rules),
        tuple(r.name + PRIME if r.name in primed else r.name for r in theirs),
        removed,
        added,
        tuple(range(len(before.relations))),
        tuple(after_relations),
    )


def cancelled_differently(
    before: Sequence[A.Rule],
    after: Sequence[A.Rule],
    above_before: frozenset[tuple[str, str]],
    above_after: frozenset[tuple[str, str]],
) -> set[str]:
    """The names of the rules that differ between the versions, in their text or in what can
    cancel them: other rules above them, or a rule above them that differs."""
    theirs = {r.name: r for r in after}
    differs = {r.name for r in before if theirs.get(r.name) != r} | {r.name for r in after} - {
        r.name for r in before
    }
    names = {r.name for r in before} & set(theirs)

    def higher(above: frozenset[tuple[str, str]], name: str) -> set[str]:
        return {h for h, lo in above if lo == name}

    grew = True
    while grew:
        grew = False
        for name in sorted(names - differs):
            hb, ha = higher(above_before, name), higher(above_after, name)
            if hb != ha or (hb | ha) & differs:
                differs.add(name)
                grew = True
    return differs


def inline(node: N, values: dict[str, int]) -> N:
    """``node`` with every name of ``values`` (constants) written as its value."""
    if not values:
        return node
    if isinstance(node, A.Name):
        if node.name in values:
            return A.IntLit(values[node.name], span=node.span)  # type: ignore[return-value]
        return node
    if isinstance(node, tuple):
        return tuple(inline(x, values) for x in node)  # type: ignore[return-value]
    if not dataclasses.is_dataclass(node) or isinstance(node, type):
        return node
    fields = {f.name: getattr(node, f.name) for f in dataclasses.fields(node) if f.init}
    new = {k: inline(v, values) for k, v in fields.items()}
    if all(new[k] is fields[k] for k in fields):
        return node
    return type(node)(**new)


__all__ = ["PRIME", "Sides", "cancelled_differently", "inline", "merge", "original"]
