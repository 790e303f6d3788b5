"""Typed, immutable abstract syntax of SLEEC (both dialects and the paper notation).

Every node is a frozen, slotted dataclass. Source spans and purely syntactic hints (was a
measure written ``{m}``? was an expression parenthesised?) are excluded from equality, so
that *meaning* is what compares equal: a TK file and its LEGOS rendering have equal ASTs,
and parse -> print -> parse is the identity on ASTs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Literal, NamedTuple, TypeAlias

from cosleec.bulk import quick_init
from cosleec.lang.hedges import HedgeSemantics

_HEDGE_VALUES = frozenset(str(h) for h in HedgeSemantics)


class Span(NamedTuple):
    """Where a node came from: 1-based line and column, end exclusive.

    The file is not stored per node (one parser serves every file); the Specification and
    each Diagnostic carry the path. An immutable named tuple: every node has one, and a
    tuple is built at C speed (``tuple.__new__``), a frozen dataclass is not.
    """

    line: int
    col: int
    end_line: int
    end_col: int

    def __str__(self) -> str:
        return f"{self.line}:{self.col}"


NO_SPAN = Span(0, 0, 0, 0)


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False, kw_only=True)


class Dialect(StrEnum):
    """The concrete syntax a file was written in."""

    TK = "tk"
    LEGOS = "legos"
    PAPER = "paper"

    def __str__(self) -> str:
        return self.value


# ---------------------------------------------------------------------------- expressions


@dataclass(frozen=True, slots=True)
class BoolLit:
    """A boolean literal in a condition: ``true`` or ``false``."""

    value: bool
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class IntLit:
    """An integer literal, e.g. ``30`` in ``within 30 seconds``; a written ``-3`` is one literal.

    ``sign`` is the sign as written (``""``, ``"+"`` or ``"-"``, followed by a space when
    something separates it from the digits, as in ``- 3``): only the dialect checks read it.
    """

    value: int
    sign: str = field(default="", compare=False, kw_only=True)
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class DecimalLit:
    """A decimal literal: no SLEEC analyser accepts one, so the checker rejects it by name."""

    text: str
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Name:
    """An identifier in an expression: a measure, a constant or a scale literal.

    Which one is decided by the checker (names are resolved by kind, strictly). ``braced``
    (LEGOS ``{m}``) and ``arrow`` (LEGOS ``->C``) record how it was written; they do not
    take part in equality. On every expression node, ``parenthesized`` counts the pairs of
    parentheses written around it (0: none); it too is only a record of the text.
    """

    name: str
    braced: bool = field(default=False, compare=False, kw_only=True)
    arrow: bool = field(default=False, compare=False, kw_only=True)
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Not:
    """Boolean negation of a condition: ``not userUndressed``."""

    operand: Expr
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class BinOp:
    """``and``/``or`` (boolean) or ``+ - *`` (arithmetic)."""

    op: str
    left: Expr
    right: Expr
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Compare:
    """A comparison, ``op`` one of ``< <= > >= = <>``: ``temperature > 30``."""

    op: str
    left: Expr
    right: Expr
    parenthesized: int = field(default=0, compare=False, kw_only=True)
    span: Span = _span()


Expr: TypeAlias = BoolLit | IntLit | DecimalLit | Name | Not | BinOp | Compare

BOOL_OPS = frozenset({"and", "or"})
ARITH_OPS = frozenset({"+", "-", "*"})
REL_OPS = frozenset(
    {"<", "<=", ">", ">=", "=", "<>"}
)  # the grammar's `rel_op` (a parser test holds them equal)

# ---------------------------------------------------------------------------- responses

TIME_UNITS: dict[str, int] = {"seconds": 1, "minutes": 60, "hours": 3600, "days": 86400}


@dataclass(frozen=True, slots=True)
class Duration:
    """``value unit``; ``unit`` is the word as written (the checker rejects non-units)."""

    value: Expr
    unit: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class TimeLimit:
    """``within hi`` (``lo`` is None) or the LEGOS interval ``within [lo, hi]``."""

    hi: Duration
    lo: Duration | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Occurrence:
    """An event the robot must produce (or, when ``negated``, must not produce)."""

    event: str
    negated: bool = False
    limit: TimeLimit | None = None
    eventually: bool = False
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ResponseItem:
    """One obligation with its fallback (``otherwise``) and alternative (``else``)."""

    occurrence: Occurrence
    otherwise: Response | None = None
    alternative: Response | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Defeater:
    """A hedge clause: ``unless condition [then response]``.

    A clause without ``then`` has ``response is None``: the empty response, nothing is
    required for this trigger.
    """

    condition: Expr
    response: Response | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Response:
    """A conjunction of response items plus the hedge clauses that can defeat it.

    Standard SLEEC has exactly one item; more than one is cosleec's conjunction extension
    (``then A and B``), which the paper's ``(Refuse AND ExplainWhy)`` needs.
    """

    items: tuple[ResponseItem, ...]
    defeaters: tuple[Defeater, ...] = ()
    braced: bool = field(default=False, compare=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Trigger:
    """What a rule reacts to, an event and an optional condition: ``CurtainOpenRequest and userDistressed``."""

    event: str
    condition: Expr | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Rule:
    """A named rule of the rule block: ``R1 when CurtainOpenRequest then OpenCurtains``."""

    name: str
    trigger: Trigger
    response: Response
    span: Span = _span()


# ---------------------------------------------------------------------------- definitions


@dataclass(frozen=True, slots=True)
class BooleanType:
    """The type of a boolean measure: ``measure userUndressed : boolean``."""

    def __str__(self) -> str:
        return "boolean"


@dataclass(frozen=True, slots=True)
class NumericType:
    """The type of a numeric measure: ``measure temperature : numeric``."""

    def __str__(self) -> str:
        return "numeric"


@dataclass(frozen=True, slots=True)
class ScaleType:
    """An ordered scale; literals are listed lowest first and scoped to their measure."""

    literals: tuple[str, ...]
    literal_spans: tuple[Span, ...] = field(default=(), compare=False, repr=False, kw_only=True)

    def __str__(self) -> str:
        return f"scale({', '.join(self.literals)})"


MeasureType: TypeAlias = BooleanType | NumericType | ScaleType


@dataclass(frozen=True, slots=True)
class EventDecl:
    """An event declaration in the def block: ``event OpenCurtains``."""

    name: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class MeasureDecl:
    """A measure declaration in the def block: ``measure userUndressed : boolean``."""

    name: str
    type: MeasureType
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ConstantDecl:
    """``constant N = 5`` (value an int) or a reference ``constant B = A`` / ``= -> A``."""

    name: str
    value: int | str
    arrow: bool = field(default=False, compare=False, kw_only=True)
    sign: str = field(default="", compare=False, kw_only=True)  # as on IntLit
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class FluentDecl:
    """CPeluti's ``fluent F <{starts}, {ends}>``: an unsupported extension, kept for tools."""

    name: str
    initiating: tuple[str, ...]
    terminating: tuple[str, ...]
    span: Span = _span()


Definition: TypeAlias = EventDecl | MeasureDecl | ConstantDecl | FluentDecl

# ---------------------------------------------------------------------------- LEGOS blocks


@dataclass(frozen=True, slots=True)
class Situation:
    """A concern or purpose: ``name when|exists trigger [then|while R {while R}] [meanwhile (...)]``."""

    name: str
    kind: Literal["when", "exists"]
    trigger: Trigger
    responses: tuple[Response, ...] = ()
    meanwhile: Situation | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class EventRelation:
    """``witness|mutualExclusive|equal|happenBefore|isContradictoryWith A B``."""

    kind: str
    first: str
    second: str
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class MeasureRelation:
    """``measure imply|mutualExclusive|iff|opposite p q`` or ``measure invariant p``."""

    kind: str
    first: Expr
    second: Expr | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class EventMeasureRelation:
    """``causation|includes|forbid E p``."""

    kind: str
    event: str
    condition: Expr
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class UntilRelation:
    """``when A [and c] then p until B [and c2]``."""

    trigger: Trigger
    condition: Expr
    until_event: str
    until_condition: Expr | None = None
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class ForRelation:
    """``when A [and c] then p for T``."""

    trigger: Trigger
    condition: Expr
    duration: Duration
    span: Span = _span()


Relation: TypeAlias = EventRelation | MeasureRelation | EventMeasureRelation | UntilRelation | ForRelation

# ---------------------------------------------------------------------------- priorities


@dataclass(frozen=True, slots=True)
class Priority:
    """One declared pair of the priority block: rule ``higher`` takes precedence over ``lower``.

    A cosleec extension (docs/reference/sleec-language.md §13.4): when an instance of
    ``higher`` and one of ``lower`` are active together, the runtime cancels the ``lower`` one
    (or, conflict-aware, only when keeping it would make ``higher`` impossible). A chain
    ``A > B > C`` in the file is read as two pairs, ``A > B`` and ``B > C``. ``span`` covers
    ``higher > lower``; ``higher_span`` and ``lower_span`` each name, for diagnostics.
    """

    higher: str
    lower: str
    span: Span = _span()
    higher_span: Span = _span()
    lower_span: Span = _span()


@dataclass(frozen=True, slots=True)
class SemanticsDecl:
    """One entry of the semantics block, as written: ``unless nested`` is aspect ``unless``,
    value ``nested``.

    A cosleec extension (docs/reference/sleec-language.md §7.4): the file says which clause
    semantics it is written for. The checker reports a value that is no
    :class:`~cosleec.lang.HedgeSemantics`; :attr:`Specification.clause_semantics` reads a valid one.
    """

    aspect: str
    value: str
    span: Span = _span()
    value_span: Span = _span()


BlockKind: TypeAlias = Literal["def", "rule", "concern", "purpose", "relation", "priority", "semantics"]


@dataclass(frozen=True, slots=True)
class BlockMark:
    """Where a block opened; used to check block order and duplicates. ``empty``: the
    block has nothing between its start and end words."""

    kind: BlockKind
    empty: bool = field(default=False, kw_only=True)
    span: Span = _span()


@dataclass(frozen=True, slots=True)
class Specification:
    """A whole SLEEC file."""

    definitions: tuple[Definition, ...]
    rules: tuple[Rule, ...]
    concerns: tuple[Situation, ...] = ()
    purposes: tuple[Situation, ...] = ()
    relations: tuple[Relation, ...] = ()
    priorities: tuple[Priority, ...] = ()  # cosleec's extension: pairs in file order, chains expanded
    semantics: tuple[SemanticsDecl, ...] = ()  # cosleec's extension: the semantics block's entries
    dialect: Dialect = field(default=Dialect.TK, compare=False)
    path: str = field(default="<string>", compare=False)
    blocks: tuple[BlockMark, ...] = field(default=(), compare=False, repr=False)

    @property
    def has_def_block(self) -> bool:
        """Whether the file opened a def block (even an empty one) or has any definitions."""
        return any(b.kind == "def" for b in self.blocks) or bool(self.definitions)

    @property
    def events(self) -> tuple[EventDecl, ...]:
        """The event declarations, in file order."""
        return tuple(d for d in self.definitions if isinstance(d, EventDecl))

    @property
    def measures(self) -> tuple[MeasureDecl, ...]:
        """The measure declarations, in file order."""
        return tuple(d for d in self.definitions if isinstance(d, MeasureDecl))

    @property
    def constants(self) -> tuple[ConstantDecl, ...]:
        """The constant declarations, in file order."""
        return tuple(d for d in self.definitions if isinstance(d, ConstantDecl))

    @property
    def clause_semantics(self) -> HedgeSemantics | None:
        """The clause semantics the file declares (its semantics block, ``unless nested``), or
        None when it declares none. Whoever reads the rules -- ``check``, ``analyse``, the
        runtime -- uses it when not told otherwise; see ``cosleec.lang.clause_semantics_for``."""
        for d in self.semantics:
            if d.aspect == "unless" and d.value in _HEDGE_VALUES:
                return HedgeSemantics(d.value)
        return None

    def rule(self, name: str) -> Rule:
        """The (first) rule called ``name``; raises KeyError if there is none."""
        for r in self.rules:
            if r.name == name:
                return r
        raise KeyError(name)


# ---------------------------------------------------------------------------- construction speed

# parsing builds a node per grammar reduction and the checker rebuilds some: every frozen,
# slotted node class gets the quicker __init__ of :func:`cosleec.bulk.quick_init`
for _cls in list(globals().values()):
    if (
        isinstance(_cls, type)
        and _cls.__module__ == __name__
        and dataclasses.is_dataclass(_cls)
        and "__slots__" in _cls.__dict__
        and _cls.__dataclass_params__.frozen  # type: ignore[attr-defined]
    ):
        quick_init(_cls)
del _cls
