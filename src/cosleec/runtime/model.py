"""A checked Specification, compiled for execution: rules, clauses, responses, obligations.

Table 1 of the CO-SLEEC paper, made concrete: each rule has a default response (the base
implementation) and one *clause* per ``unless`` (a layer named ``R1.1``, ``R1.2``, ...),
each with a compiled condition and the measures it reads (for the dependency index).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from cosleec.lang import ast as A
from cosleec.lang.checker import SymbolTable
from cosleec.runtime.compile import Compiler, Values, text
from cosleec.runtime.values import MeasureSpec

Seconds = Callable[[Values], float]


@dataclass(frozen=True, slots=True)
class Obligation:
    """What one decision requires: produce (or, negated, do not produce) ``event``.

    Windows are relative to the moment the obligation starts, in seconds: ``within_s``
    is the deadline (None: none), ``from_s`` the start of a LEGOS interval.
    """

    event: str
    negated: bool = False
    within_s: float | None = None
    from_s: float = 0.0
    eventually: bool = False
    alternatives: tuple[str, ...] = ()  # events of an `else` that also satisfy it
    otherwise: ResponseSpec | None = field(default=None, compare=False, repr=False)
    rule: str = ""

    def to_json(self) -> dict[str, Any]:
        return {
            "event": self.event,
            "negated": self.negated,
            "within_s": self.within_s,
            "otherwise": self.otherwise.first_json() if self.otherwise is not None else None,
        }

    def describe(self) -> str:
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


def _fmt_s(x: float) -> str:
    return f"{x:g} s"


@dataclass(frozen=True, slots=True)
class ItemSpec:
    event: str
    negated: bool
    lo: Seconds | None
    hi: Seconds | None
    eventually: bool
    otherwise: ResponseSpec | None
    alternative: ResponseSpec | None
    reads: frozenset[str]


@dataclass(frozen=True, slots=True)
class Clause:
    """A hedge clause: ``unless condition [then response]`` -- one layer."""

    index: int  # 1-based
    layer: str  # "R1.2"
    condition: Callable[[Values], Any]
    reads: frozenset[str]
    text: str
    response: ResponseSpec | None  # None: nothing is required
    source: str = "True"  # the compiled condition's Python source


@dataclass(frozen=True, slots=True)
class ResponseSpec:
    items: tuple[ItemSpec, ...]
    clauses: tuple[Clause, ...] = ()  # defeaters of a braced inner response
    reads: frozenset[str] = frozenset()

    def events(self) -> tuple[str, ...]:
        return tuple(i.event for i in self.items)

    def first_json(self) -> dict[str, Any] | None:
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


@dataclass(frozen=True, slots=True)
class CompiledRule:
    index: int
    name: str
    trigger: str
    condition: Callable[[Values], Any]
    trigger_reads: frozenset[str]
    trigger_text: str
    default: ResponseSpec
    clauses: tuple[Clause, ...]
    ast: A.Rule
    hedge_reads: frozenset[str] = frozenset()  # every measure a clause condition reads
    all_reads: tuple[str, ...] = ()  # trigger and clause measures, sorted (for decision records)
    clause_ids: tuple[int, ...] = ()
    clause_texts: tuple[str, ...] = ()
    evaluate_all: Callable[[Values], tuple[bool, ...]] | None = None  # every clause condition at once
    value_specs: tuple[tuple[str, tuple[str, ...] | None], ...] = ()  # (measure, scale literals)

    def response_of(self, clause: int) -> ResponseSpec | None:
        return self.default if clause == 0 else self.clauses[clause - 1].response

    def layer_of(self, clause: int) -> str | None:
        return None if clause == 0 else self.clauses[clause - 1].layer


@dataclass
class RuleSet:
    """Everything the runtime needs from a checked specification."""

    spec: A.Specification
    rules: tuple[CompiledRule, ...]
    measures: dict[str, MeasureSpec]
    events: frozenset[str]
    by_trigger: dict[str, tuple[CompiledRule, ...]]
    compiler: Compiler

    def rule(self, name: str) -> CompiledRule:
        for r in self.rules:
            if r.name == name:
                return r
        raise KeyError(name)


def _duration(c: Compiler, d: A.Duration, reads: set[str]) -> Seconds:
    unit = A.TIME_UNITS[d.unit]
    src = c.source(d.value, reads)
    fn: Seconds = eval(compile(f"lambda v: ({src}) * {unit}", "<sleec deadline>", "eval"))
    return fn


def compile_response(
    c: Compiler, r: A.Response, owner: str, untimed_otherwise_zero: bool = True
) -> ResponseSpec:
    items = []
    reads_all: set[str] = set()
    for it in r.items:
        occ = it.occurrence
        reads: set[str] = set()
        lo = hi = None
        if occ.limit is not None:
            hi = _duration(c, occ.limit.hi, reads)
            if occ.limit.lo is not None:
                lo = _duration(c, occ.limit.lo, reads)
        elif it.otherwise is not None and not occ.eventually and untimed_otherwise_zero:
            hi = _zero  # §10: `otherwise` after an untimed occurrence reads it as `within 0 seconds`
        items.append(
            ItemSpec(
                occ.event,
                occ.negated,
                lo,
                hi,
                occ.eventually,
                compile_response(c, it.otherwise, owner) if it.otherwise is not None else None,
                compile_response(c, it.alternative, owner) if it.alternative is not None else None,
                frozenset(reads),
            )
        )
        reads_all |= reads
    clauses = tuple(_clause(c, d, f"{owner}~{i}", i) for i, d in enumerate(r.defeaters, start=1))
    return ResponseSpec(tuple(items), clauses, frozenset(reads_all))


def _zero(v: Values) -> float:
    return 0.0


def _clause(c: Compiler, d: A.Defeater, layer: str, index: int) -> Clause:
    fn, reads, src = c.function(d.condition)
    resp = compile_response(c, d.response, layer) if d.response is not None else None
    return Clause(index, layer, fn, reads, text(d.condition), resp, src)


def _all_clauses(clauses: tuple[Clause, ...]) -> Callable[[Values], tuple[bool, ...]]:
    """One function that evaluates every clause condition of a rule in a single call."""
    body = ", ".join(f"bool({cl.source})" for cl in clauses)
    fn: Callable[[Values], tuple[bool, ...]] = eval(
        compile(f"lambda v: ({body},)", "<sleec clauses>", "eval")
    )
    return fn


def compile_rules(
    spec: A.Specification, symbols: SymbolTable, max_age: dict[str, float] | None = None
) -> RuleSet:
    c = Compiler(symbols)
    ages = max_age or {}
    measures = {m.name: MeasureSpec.of(m, ages.get(m.name)) for m in spec.measures}
    rules = []
    for i, r in enumerate(spec.rules):
        cond, treads, _ = c.function(r.trigger.condition)
        default = compile_response(c, A.Response(r.response.items, ()), r.name)
        clauses = tuple(
            _clause(c, d, f"{r.name}.{k}", k) for k, d in enumerate(r.response.defeaters, start=1)
        )
        hreads = frozenset().union(*(cl.reads for cl in clauses))
        rules.append(
            CompiledRule(
                i,
                r.name,
                r.trigger.event,
                cond,
                treads,
                text(r.trigger.condition),
                default,
                clauses,
                r,
                hreads,
                tuple(sorted(treads | hreads)),
                tuple(cl.index for cl in clauses),
                tuple(cl.text for cl in clauses),
                _all_clauses(clauses) if clauses else None,
                tuple((n, measures[n].literals or None) for n in sorted(treads | hreads)),
            )
        )
    by_trigger: dict[str, list[CompiledRule]] = {}
    for cr in rules:
        by_trigger.setdefault(cr.trigger, []).append(cr)
    return RuleSet(
        spec,
        tuple(rules),
        measures,
        frozenset(e.name for e in spec.events),
        {k: tuple(v) for k, v in by_trigger.items()},
        c,
    )
