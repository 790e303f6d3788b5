"""A checked rule compiled for execution: clauses, responses, obligations, COP layers.

Table 1 of the CO-SLEEC paper, made concrete. A rule becomes:

- a *default response* (clause 0): the base implementation of the rule's layered method;
- one *clause* per ``unless`` (clause i, a COP layer named ``R1.i``) with its compiled
  condition and the measures it reads (for the Layer Manager's dependency index);
- one composition per clause (:attr:`CompiledRule.compositions`): the empty composition
  for the default, ``(R1.i,)`` for clause i -- the Layer Manager activates a layer by
  making its composition the rule's current one (built once here, so a dispatch under
  it finds its chain in COP's memo);
- one exclusive COP :class:`~cosleec.cop.LayerGroup` holding the rule's layers, so that
  whoever composes them by hand (a test, a simulation, an operator forcing a clause with
  ``cosleec.cop.activate``) can never have two clauses of one rule active at once.

These records are immutable and hold no runtime state: one :class:`~cosleec.runtime.RuleSet`
may serve several Managers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from cosleec.bulk import quick_init
from cosleec.cop import Layer, LayerGroup, Snapshot
from cosleec.errors import ConfigurationError, clip
from cosleec.lang import ast as A
from cosleec.runtime.compile import Compiler, Values, text

Seconds = Callable[[Values], float]


Window = tuple[str, float, float | None]  # (event, from_s, within_s): one item of an `else` branch
Branch = tuple[Window, ...]


@quick_init
@dataclass(frozen=True, slots=True, kw_only=True)
class Obligation:
    """What one decision requires: produce (or, negated, do not produce) ``event``.

    Windows are relative to the moment the obligation starts, in seconds: ``within_s``
    is the deadline (None: none), ``from_s`` the start of a LEGOS interval.
    ``otherwise`` is the compiled fallback; it stays in this process (the wire form only
    describes its first item, and :meth:`from_json` leaves it ``None``).
    """

    event: str
    negated: bool = False
    within_s: float | None = None
    from_s: float = 0.0
    eventually: bool = False
    # an `else`: each branch is a list of (event, from_s, within_s) that together also satisfy it
    alternatives: tuple[Branch, ...] = ()
    otherwise: ResponseSpec | None = field(default=None, compare=False, repr=False)
    rule: str = ""
    item: str = field(default="", compare=False)  # the response item it came from (ItemSpec.key)

    def to_json(self) -> dict[str, Any]:
        """The wire and audit form (see :meth:`from_json`)."""
        return {
            "event": self.event,
            "negated": self.negated,
            "within_s": self.within_s,
            "from_s": self.from_s,
            "eventually": self.eventually,
            "alternatives": [[list(w) for w in b] for b in self.alternatives],
            "rule": self.rule,
            "item": self.item,
            "otherwise": self.otherwise.first_json() if self.otherwise is not None else None,
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Obligation:
        """An obligation read back from :meth:`to_json` (its ``otherwise`` is not carried)."""
        within = d.get("within_s")
        return cls(
            event=str(d["event"]),
            negated=bool(d.get("negated", False)),
            within_s=None if within is None else float(within),
            from_s=float(d.get("from_s", 0.0)),
            eventually=bool(d.get("eventually", False)),
            alternatives=tuple(_branch(b, d) for b in d.get("alternatives", ())),
            rule=str(d.get("rule", "")),
            item=str(d.get("item", "")),
        )

    def describe(self) -> str:
        """The obligation in SLEEC words: ``not RecordVideo within 600 s``."""
        s = ("not " if self.negated else "") + self.event
        if self.within_s is not None:
            s += (
                f" within {_fmt_s(self.within_s)}"
                if not self.from_s
                else f" within [{_fmt_s(self.from_s)}, {_fmt_s(self.within_s)}]"
            )
        elif self.eventually:
            s += " eventually"
        return s


def _branch(b: Any, d: Mapping[str, Any]) -> Branch:
    """An ``else`` branch read back; an older record's bare event name counts in the main window."""
    if isinstance(b, str):
        w = d.get("within_s")
        return ((b, float(d.get("from_s", 0.0)), None if w is None else float(w)),)
    return tuple((str(e), float(lo), None if hi is None else float(hi)) for e, lo, hi in b)


def _fmt_s(x: float) -> str:
    return f"{x:g} s"


@quick_init
@dataclass(frozen=True, slots=True, kw_only=True)
class ItemSpec:
    """One compiled response item: the event, its window as functions of the context.

    ``key`` names it within its rule set (``R1.2:0/o:1``: clause R1.2, item 0, its
    ``otherwise``, item 1); a journal restores an obligation's ``otherwise`` by it.
    """

    key: str
    event: str
    negated: bool
    lo: Seconds | None
    hi: Seconds | None
    eventually: bool
    otherwise: ResponseSpec | None
    alternative: ResponseSpec | None


@quick_init
@dataclass(frozen=True, slots=True, kw_only=True)
class Clause:
    """A hedge clause: ``unless condition [then response]`` -- one COP layer."""

    index: int  # 1-based
    layer: str  # "R1.2"
    condition: Callable[[Values], Any]  # raises KeyError on an unknown measure (fast)
    kleene: Callable[[Values], Any]  # True, False or None (unknown): after that KeyError
    reads: frozenset[str]
    text: str
    response: ResponseSpec | None  # None: nothing is required
    source: str = "True"  # the compiled condition's Python source

    def value(self, v: Values) -> bool | None:
        """The condition's three-valued truth on ``v``: None when an unknown measure decides it."""
        try:
            return bool(self.condition(v))
        except KeyError:
            x = self.kleene(v)
            return None if x is None else bool(x)


@quick_init
@dataclass(frozen=True, slots=True)
class ResponseSpec:
    """A compiled response: its items and, for a braced inner response, its own clauses."""

    items: tuple[ItemSpec, ...]
    clauses: tuple[Clause, ...] = ()  # defeaters of a braced inner response
    # every item's window is a constant and none has an `else`: its obligations are the same
    # every time it starts (the Manager makes them once)
    fixed: bool = False

    def events(self) -> tuple[str, ...]:
        """The events its items name, in order."""
        return tuple(i.event for i in self.items)

    def walk(self) -> Iterator[ItemSpec]:
        """Every item of this response and, depth first, of its otherwise, else and inner clauses."""
        for it in self.items:
            yield it
            for sub in (it.otherwise, it.alternative):
                if sub is not None:
                    yield from sub.walk()
        for c in self.clauses:
            if c.response is not None:
                yield from c.response.walk()

    def first_json(self) -> dict[str, Any] | None:
        """A description of the first item, for records (deadlines known only if constant)."""
        if not self.items:
            return None
        it = self.items[0]
        return {
            "event": it.event,
            "negated": it.negated,
            "within_s": None if it.hi is None else _const(it.hi),
            "otherwise": it.otherwise.first_json() if it.otherwise is not None else None,
        }


def _const(fn: Seconds) -> float | None:
    try:
        return fn({})
    except KeyError:
        return None  # depends on a measure: known only when the response starts


@quick_init
@dataclass(frozen=True, slots=True, kw_only=True)
class CompiledRule:
    """One rule ready to run: trigger, default response, clauses and its COP layers."""

    index: int
    name: str
    trigger: str
    condition: Callable[[Values], Any]  # the trigger condition, fast form (KeyError when unknown)
    trigger_kleene: Callable[[Values], Any]  # its three-valued form
    trigger_reads: frozenset[str]
    trigger_text: str
    default: ResponseSpec
    clauses: tuple[Clause, ...]
    ast: A.Rule
    layers: tuple[Layer, ...]  # clause i's COP layer is layers[i - 1]
    layer_names: tuple[str | None, ...]  # [0]: None (the base); [i]: clause i's layer name
    compositions: tuple[Snapshot, ...]  # [0]: no layer (default); [i]: (layers[i - 1],)
    hedge_reads: frozenset[str]  # every measure a clause condition reads
    clause_ids: tuple[int, ...]  # 1..n, and each clause's condition text: zipped into decisions
    clause_texts: tuple[str, ...]
    value_names: tuple[str, ...]  # every measure it reads, sorted: the values a decision shows
    scale_values: tuple[tuple[str, tuple[str, ...]], ...]  # those of a scale, with its literals
    evaluate_all: Callable[[Values], tuple[bool, ...]] | None  # every clause condition at once
    # the end of a decision's explanation ("[clause k (unless ...)], because ..."), made once
    # per clause and clause values that decide it (``decision._because``): empty until then
    reasons: dict[tuple[int, tuple[bool | None, ...]], str] = field(compare=False, repr=False)

    def response_of(self, clause: int) -> ResponseSpec | None:
        """The response of clause ``clause`` (0: the default)."""
        return self.default if clause == 0 else self.clauses[clause - 1].response

    def responses(self) -> Iterator[ResponseSpec]:
        """The default response and each clause's response (clauses that require nothing left out)."""
        yield self.default
        for c in self.clauses:
            if c.response is not None:
                yield c.response

    def layer_of(self, clause: int) -> str | None:
        """The name of clause ``clause``'s layer; None for the default (the base)."""
        return self.layer_names[clause]


# The longest window the runtime keeps (about 317 years): past it a clock time in seconds
# loses its sub-millisecond precision, so a longer one is a mistake, not a norm.
MAX_WINDOW_S = 1e10


class DeadlineError(ConfigurationError):
    """A deadline written in the rules is beyond what the runtime can keep (:data:`MAX_WINDOW_S`)."""


def _duration(c: Compiler, d: A.Duration, where: str) -> Seconds:
    """The deadline as seconds; KeyError while a measure it reads is unknown.

    A deadline read from measures that comes out non-finite or longer than
    :data:`MAX_WINDOW_S` is unknown too (KeyError): the caller reads it fail-closed. A
    constant one that large is a :class:`DeadlineError` now, at compile time.
    """
    unit = A.TIME_UNITS[d.unit]
    reads: set[str] = set()
    src = c.source(d.value, reads)
    raw: Seconds = c.lambda_(f"({src}) * {unit}", "<sleec deadline>")

    def seconds(v: Values) -> float:
        try:
            x = float(raw(v))
        except OverflowError:
            x = math.inf
        if not -MAX_WINDOW_S <= x <= MAX_WINDOW_S:  # also false for NaN
            raise KeyError(f"deadline {text(d.value)} {d.unit} out of range")
        return x

    if not reads:
        try:
            value = seconds({})
        except KeyError:
            raise DeadlineError(
                f"the deadline {clip(text(d.value), 40)} {d.unit} is longer than the runtime can keep",
                where=f"{where}:{d.span}" if d.span.line else where,
                hint=f"write a deadline of at most {MAX_WINDOW_S:.0e} seconds",
            ) from None
        return Fixed(value)
    return seconds


class Fixed:
    """A deadline that reads no measure: the same seconds whatever the context."""

    __slots__ = ("value",)

    def __init__(self, value: float) -> None:
        self.value = value

    def __call__(self, v: Values) -> float:
        """The seconds, whatever ``v`` holds."""
        return self.value


_zero = Fixed(0.0)


def compile_response(c: Compiler, r: A.Response, key: str, where: str = "") -> ResponseSpec:
    """Compile a response; ``key`` prefixes its items' keys and names its inner clauses
    (``R1~1``); ``where`` is the rule file, for errors."""
    items = []
    for n, it in enumerate(r.items):
        k = f"{key}:{n}"
        occ = it.occurrence
        lo = hi = None
        if occ.limit is not None:
            hi = _duration(c, occ.limit.hi, where)
            if occ.limit.lo is not None:
                lo = _duration(c, occ.limit.lo, where)
        elif it.otherwise is not None and not occ.eventually:
            hi = _zero  # `otherwise` after an untimed occurrence reads it as `within 0 seconds`
        items.append(
            ItemSpec(
                key=k,
                event=occ.event,
                negated=occ.negated,
                lo=lo,
                hi=hi,
                eventually=occ.eventually,
                otherwise=compile_response(c, it.otherwise, f"{k}/o", where)
                if it.otherwise is not None
                else None,
                alternative=(
                    compile_response(c, it.alternative, f"{k}/e", where)
                    if it.alternative is not None
                    else None
                ),
            )
        )
    clauses = tuple(_clause(c, d, f"{key}~{i}", i, where) for i, d in enumerate(r.defeaters, start=1))
    fixed = not clauses and all(
        it.alternative is None and isinstance(it.hi, Fixed | None) and isinstance(it.lo, Fixed | None)
        for it in items
    )
    return ResponseSpec(tuple(items), clauses, fixed)


def _clause(c: Compiler, d: A.Defeater, layer: str, index: int, where: str) -> Clause:
    fn, reads, src = c.function(d.condition)
    resp = compile_response(c, d.response, layer, where) if d.response is not None else None
    return Clause(
        index=index,
        layer=layer,
        condition=fn,
        kleene=c.kleene(d.condition),
        reads=reads,
        text=text(d.condition),
        response=resp,
        source=src,
    )


def _all_clauses(c: Compiler, clauses: tuple[Clause, ...]) -> Callable[[Values], tuple[bool, ...]]:
    """One function that evaluates every clause condition of a rule in a single call."""
    body = ", ".join(f"bool({cl.source})" for cl in clauses)
    return c.lambda_(f"({body},)", "<sleec clauses>")


def compile_rule(
    c: Compiler, index: int, r: A.Rule, literals: Mapping[str, tuple[str, ...]], where: str = ""
) -> CompiledRule:
    """Compile one checked rule; ``literals`` gives each scale measure's literals, ``where``
    names the rule file in errors (DeadlineError)."""
    cond, trigger_reads, _ = c.function(r.trigger.condition)
    default = compile_response(c, A.Response(r.response.items, ()), r.name, where)
    clauses = tuple(
        _clause(c, d, f"{r.name}.{k}", k, where) for k, d in enumerate(r.response.defeaters, start=1)
    )
    hedge_reads = frozenset().union(*(cl.reads for cl in clauses))
    layers = tuple(Layer(cl.layer) for cl in clauses)
    if layers:
        LayerGroup(r.name, layers)  # a rule's layers exclude each other (one clause at a time)
    return CompiledRule(
        index=index,
        name=r.name,
        trigger=r.trigger.event,
        condition=cond,
        trigger_kleene=c.kleene(r.trigger.condition),
        trigger_reads=trigger_reads,
        trigger_text=text(r.trigger.condition),
        default=default,
        clauses=clauses,
        ast=r,
        layers=layers,
        layer_names=(None, *(cl.layer for cl in clauses)),
        compositions=(Snapshot(()), *(Snapshot((la,)) for la in layers)),
        hedge_reads=hedge_reads,
        clause_ids=tuple(cl.index for cl in clauses),
        clause_texts=tuple(cl.text for cl in clauses),
        value_names=tuple(sorted(trigger_reads | hedge_reads)),
        scale_values=tuple(
            (n, lits) for n in sorted(trigger_reads | hedge_reads) if (lits := literals.get(n))
        ),
        evaluate_all=_all_clauses(c, clauses) if clauses else None,
        reasons={},
    )
