"""What an encoding and its parts share (:mod:`cosleec.analysis.encoding`): the z3 context and
solver, the slots, the rule and relation literals, what is being encoded now, and the caches.

:class:`~cosleec.analysis.terms.Terms`, :class:`~cosleec.analysis.windows.Windows`,
:class:`~cosleec.analysis.relations.Relations`, :class:`~cosleec.analysis.refusals.Refusals`
and :class:`~cosleec.analysis.obligations.Obligations` each build one kind of formula; all of
them read and extend one :class:`State`, which holds every z3 object an encoding keeps.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any

import z3

from cosleec.analysis.deadline import Deadline
from cosleec.analysis.slots import Z3, Ban, Cut, Fallback, FallbackBan, Raised, Slot
from cosleec.lang import HedgeSemantics, Reading, Specification
from cosleec.lang import ast as A


@dataclass(eq=False, kw_only=True)
class State:
    """The z3 objects and the bookkeeping of one encoding, held in one place.

    The order of the fields is part of what the analysis answers, so keep it: when an
    encoding goes, its z3 terms are let go in this order, z3 gives the ids of the terms let
    go to the next terms it makes, and which model z3 finds -- a witness's times and values,
    which situations are tried first -- depends on those ids. It is the order the encoding's
    attributes have always had; the parts hold nothing of their own that z3 would let go.
    (An encoding that :func:`cosleec.analysis.cores.minimal_core` has seen goes only when
    Python's cycle collector runs: its recursive closure holds it. When that is, no order of
    code decides.)
    """

    ctx: z3.Context
    spec: Specification
    constants: dict[str, int]
    reading: Reading
    bound: int
    measures: dict[str, A.MeasureType]
    solver: z3.Solver
    timeout_ms: int
    deadline: Deadline | None  # the whole run's (--deadline): checked while building and asking
    slots: list[Slot] = field(default_factory=list)
    by_event: dict[str, list[Slot]] = field(default_factory=dict)
    fallbacks: list[Fallback] = field(default_factory=list)  # the otherwise snapshots (Obligations)
    bans: dict[str, list[Ban]] = field(default_factory=dict)  # the prohibitions slots can raise (Refusals)
    guard: Z3  # when what is being encoded is in force (Obligations)
    situation: bool = False  # encoding a concern's or purpose's response: nothing refuses it
    rules_by_event: dict[str, list[A.Rule]]
    rule_lit: dict[str, Z3]
    relation_lit: list[Z3]
    complete: bool  # the unfolding held every demand (Encoding.complete)
    refusers: dict[str, set[str]]  # event -> the triggers of rules that can forbid it
    extra: list[tuple[Slot, list[tuple[str, str]]]] = field(default_factory=list)  # what questions demand
    ids: itertools.count[int] = field(default_factory=itertools.count)  # slot numbers
    fresh: itertools.count[int] = field(default_factory=itertools.count)  # fresh names' numbers (Terms)
    unfolded: bool = False
    # (id(defeaters), id(snap), semantics) -> (defeaters, snap, choice), the keys' objects kept alive (Terms)
    choices: dict[tuple[int, int, HedgeSemantics], tuple[object, object, list[Z3]]] = field(
        default_factory=dict
    )
    # (id(condition), id(snap)) -> (condition, snap, term) (Terms)
    truths: dict[tuple[int, int], tuple[object, object, Z3]] = field(default_factory=dict)
    # declared priorities (Priorities): the pairs, closed; the firing being encoded (rule, slot id)
    # and its cut; each lower rule's firing's cut; what each ordered rule's firing raises
    above: frozenset[tuple[str, str]] = frozenset()
    rule: str | None = None
    firing: tuple[str, int] | None = None
    cut: Cut | None = None
    cuts: dict[tuple[str, int], Cut] = field(default_factory=dict)
    raised: dict[tuple[str, int], list[Raised]] = field(default_factory=dict)
    # prohibitions inside an otherwise (Refusals): the events some otherwise forbids, those
    # prohibitions, the refusals they may still complete, and while a rule is encoded
    # (``imposed``) the refusals of the fallbacks being encoded (None: a prohibition's fallback)
    deferred: frozenset[str] = frozenset()
    fallback_bans: dict[str, list[FallbackBan]] = field(default_factory=dict)
    owed: list[Any] = field(default_factory=list)
    within: list[Any] = field(default_factory=list)
    imposed: bool = False


__all__ = ["State"]
