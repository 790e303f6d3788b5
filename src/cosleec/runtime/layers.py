"""The COP Layer Manager: which hedge layer of each rule is active, kept up to date.

On every context change only the rules whose hedge conditions read a changed measure are
re-evaluated (a dependency index from measure to rules), so the cost of an update does
not depend on the rules it does not touch. Each rule's clauses form one exclusive group;
the active layer is chosen by the rule set's semantics:

- ``last-wins`` (default, SLEEC): the last clause whose condition holds;
- ``nested`` (the CO-SLEEC paper's formula): clause i iff conditions 1..i hold and i+1 not.

A clause whose condition cannot be evaluated (a measure is unknown) makes the selection
*undetermined* unless the ``unknown`` policy says to read unknown conditions as false or
true.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from cosleec.runtime.compile import Values
from cosleec.runtime.model import CompiledRule, RuleSet

Semantics = Literal["last-wins", "nested"]
UnknownPolicy = Literal["undetermined", "false", "true"]
SEMANTICS: tuple[str, ...] = ("last-wins", "nested")


@dataclass(frozen=True, slots=True)
class RuleStatus:
    """The layer state of one rule: every clause condition's value and the chosen clause."""

    values: tuple[bool | None, ...]  # None: unknown
    clause: int | None  # 0: default; i: clause i (layer R.i); None: undetermined
    missing: tuple[str, ...] = ()


def evaluate(conds: tuple[Any, ...], v: Values) -> tuple[tuple[bool | None, ...], tuple[str, ...]]:
    out: list[bool | None] = []
    missing: list[str] = []
    for c in conds:
        try:
            out.append(bool(c.condition(v)))
        except KeyError as e:
            out.append(None)
            name = e.args[0] if e.args else "?"
            if name not in missing:
                missing.append(name)
    return tuple(out), tuple(missing)


def layer_name(rule: CompiledRule, clause: int | None) -> str | None:
    """The rule's active layer: None for the default (base), "?" when undetermined."""
    return "?" if clause is None else rule.layer_of(clause)


def switch_records(
    switches: list[tuple[CompiledRule, int | None, int | None]],
) -> list[tuple[str, str | None, str | None]]:
    """Layer switches ``(rule, old clause, new clause)`` as ``(rule, old layer, new layer)`` names."""
    return [(r.name, layer_name(r, o), layer_name(r, n)) for r, o, n in switches]


def switches_json(records: list[tuple[str, str | None, str | None]]) -> list[dict[str, str | None]]:
    """The ``switches`` field of a ``layers`` message, the same from the Manager and the Layer Manager node."""
    return [{"rule": r, "from": a, "to": b} for r, a, b in records]


def select(values: tuple[bool | None, ...], semantics: str, unknown: str = "undetermined") -> int | None:
    """The active clause (0 = default) for these condition values, or None if undetermined."""
    if unknown != "undetermined":
        sub = unknown == "true"
        values = tuple(sub if x is None else x for x in values)
    if semantics == "last-wins":
        for i in range(len(values) - 1, -1, -1):
            x = values[i]
            if x is None:
                return None
            if x:
                return i + 1
        return 0
    k = 0
    for x in values:
        if x is None:
            return None
        if not x:
            break
        k += 1
    return k


class LayerManager:
    """Keeps every rule's active hedge layer in step with the context (see module doc)."""

    def __init__(self, ruleset: RuleSet, semantics: str = "last-wins", unknown: str = "undetermined") -> None:
        if semantics not in SEMANTICS:
            raise ValueError(f"semantics must be one of {SEMANTICS}, not {semantics!r}")
        self.ruleset = ruleset
        self.semantics = semantics
        self.unknown = unknown
        self.index: dict[str, list[CompiledRule]] = {}
        for r in ruleset.rules:
            for m in r.hedge_reads:
                self.index.setdefault(m, []).append(r)
        self.status: list[RuleStatus] = [self._compute(r, {}) for r in ruleset.rules]
        self.active: dict[int, str] = {}  # rule index -> active hedge layer (rules at default absent)

    def _compute(self, r: CompiledRule, v: Values) -> RuleStatus:
        if not r.clauses:
            return RuleStatus((), 0)
        if r.evaluate_all is not None:
            try:
                values: tuple[bool | None, ...] = r.evaluate_all(v)
                return RuleStatus(values, select(values, self.semantics, self.unknown))
            except KeyError:
                pass  # some measure is unknown: find out which, clause by clause
        values, missing = evaluate(r.clauses, v)
        return RuleStatus(values, select(values, self.semantics, self.unknown), missing)

    def update(
        self, changed: set[str] | frozenset[str], v: Values
    ) -> list[tuple[CompiledRule, int | None, int | None]]:
        """Re-evaluate the rules that read ``changed``; return (rule, old, new) layer switches."""
        touched: dict[int, CompiledRule] = {}
        index = self.index
        for m in changed:
            for r in index.get(m, ()):
                touched[r.index] = r
        switches = []
        status = self.status
        for i, r in touched.items():
            new = self._compute(r, v)
            old = status[i]
            status[i] = new
            if new.clause != old.clause:
                switches.append((r, old.clause, new.clause))
                if new.clause:
                    self.active[i] = r.clauses[new.clause - 1].layer
                else:
                    self.active.pop(i, None)
        return switches

    def recompute_all(self, v: Values) -> None:
        self.status = [self._compute(r, v) for r in self.ruleset.rules]
        self.active = {
            r.index: r.clauses[st.clause - 1].layer
            for r, st in zip(self.ruleset.rules, self.status)
            if st.clause
        }

    def active_layers(self) -> list[str]:
        """The active hedge layers, in rule order (a rule at its default contributes none)."""
        return [self.active[i] for i in sorted(self.active)]

    def set_semantics(self, semantics: str, v: Values) -> None:
        if semantics not in SEMANTICS:
            raise ValueError(f"semantics must be one of {SEMANTICS}, not {semantics!r}")
        self.semantics = semantics
        self.recompute_all(v)
