"""The COP Layer Manager: which layer of each rule is active, kept in step with the context.

Each rule's clauses are COP layers (``R1.1``, ``R1.2``, ...; see :mod:`cosleec.runtime.model`).
On every context change the Layer Manager re-evaluates only the rules whose clause
conditions read a changed measure (a dependency index from measure to rules), so the cost
of an update does not depend on the rules it does not touch, and activates, for each of
them, exactly the layer :func:`cosleec.lang.hedges.choose` selects -- none for the
default, none either when the choice is undetermined (a measure is unknown and the
``unknown`` policy does not say how to read it).

A trigger is decided against this state: the decision takes the rule's active clause,
and the rule's layered method is dispatched under that clause's composition, so COP runs
that clause's variant (see :mod:`cosleec.runtime.implementations`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from cosleec.cop import Snapshot
from cosleec.lang import HedgeSemantics, Unknowns, choose
from cosleec.runtime.compile import Values
from cosleec.runtime.model import Clause, CompiledRule
from cosleec.runtime.ruleset import RuleSet


class RuleStatus(NamedTuple):
    """The layer state of one rule: every clause condition's value and the chosen clause.

    A named tuple rather than a frozen dataclass: every update that touches a rule makes
    one, and a tuple is made in a fifth of the time.
    """

    values: tuple[bool | None, ...]  # None: unknown
    clause: int | None  # 0: default; i: clause i (layer R.i); None: undetermined
    missing: tuple[str, ...] = ()


class LayerSwitch(NamedTuple):
    """A rule's active layer changed: ``None`` is the base (default), ``"?"`` undetermined."""

    rule: str
    before: str | None
    after: str | None

    def to_json(self) -> dict[str, str | None]:
        """The form of one entry of a ``layers`` message's ``switches``."""
        return {"rule": self.rule, "from": self.before, "to": self.after}


@dataclass(frozen=True, kw_only=True)
class LayerState:
    """The ``layers`` record: the active layers after a change, and the switches that made it.

    The embedded Manager emits it as a ``layers`` runtime event; the Layer Manager node
    publishes it (latched). ``version`` counts the changes of one Layer Manager.
    """

    active: tuple[str, ...]
    switches: tuple[LayerSwitch, ...]
    semantics: HedgeSemantics
    version: int

    def to_json(self) -> dict[str, Any]:
        """The wire form; :meth:`from_json` reads it back."""
        return _state_json(list(self.active), self.switches, self.semantics, self.version)

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> LayerState:
        """A ``layers`` record read back from :meth:`to_json`."""
        return cls(
            active=tuple(d["active"]),
            switches=tuple(LayerSwitch(s["rule"], s["from"], s["to"]) for s in d["switches"]),
            semantics=HedgeSemantics(d["semantics"]),
            version=int(d["version"]),
        )


def _layers_record(
    active: dict[int, str], switches: tuple[LayerSwitch, ...], semantics: HedgeSemantics, version: int
) -> dict[str, Any]:
    """What :meth:`LayerManager.record_of` makes: :meth:`LayerState.to_json` of the state it kept."""
    return _state_json([active[i] for i in sorted(active)], switches, semantics, version)


def _state_json(
    active: list[str], switches: Iterable[LayerSwitch], semantics: HedgeSemantics, version: int
) -> dict[str, Any]:
    """A ``layers`` record (:meth:`LayerState.to_json`), made from its parts."""
    return {
        "active": active,
        "switches": [sw.to_json() for sw in switches],
        "semantics": str(semantics),
        "version": version,
    }


def evaluate(conds: Iterable[Clause], v: Values) -> tuple[tuple[bool | None, ...], tuple[str, ...]]:
    """Every condition's three-valued value (Kleene: None when unknown values decide it) and
    the measures without a value that the conditions read, in order."""
    out: list[bool | None] = []
    missing: list[str] = []
    for c in conds:
        x = c.value(v)
        out.append(x)
        for name in sorted(c.reads):
            if name not in v and name not in missing:
                missing.append(name)
    return tuple(out), tuple(missing)


_DEFAULT = RuleStatus((), 0)  # a rule without clauses
_tuple_new = tuple.__new__


class LayerManager:
    """Keeps every rule's active layer in step with the context (see the module docstring).

    Used by the embedded Manager and by the Layer Manager node; not thread-safe (its owner
    serialises access).
    """

    def __init__(
        self,
        ruleset: RuleSet,
        semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
        unknown: Unknowns = Unknowns.UNDETERMINED,
    ) -> None:
        self.ruleset = ruleset
        self.semantics = HedgeSemantics(semantics)
        self.unknown = Unknowns(unknown)
        self.index: dict[str, list[CompiledRule]] = {}
        for r in ruleset.rules:
            for m in r.hedge_reads:
                self.index.setdefault(m, []).append(r)
        # per rule, the measures it alone reads: an update of some of them touches that rule only
        alone: dict[int, set[str]] = {}
        for m, readers in self.index.items():
            if len(readers) == 1:
                alone.setdefault(readers[0].index, set()).add(m)
        self._alone = {i: frozenset(names) for i, names in alone.items()}
        self.status: list[RuleStatus] = []
        self._active: dict[int, str] = {}  # rule index -> active layer (rules at their default absent)
        # before any value is known (an `unknown` policy that reads unknown as true or false
        # can choose a clause already: its layer is active from the start)
        self.recompute_all({})
        self.version = 0  # of the last `layers` record (state()); a journal keeps it across restarts
        # each rule's COP composition: its active layer, none at the default, None undetermined

    def composition_of(self, rule: CompiledRule) -> Snapshot | None:
        """The rule's COP composition now: its active layer (empty at the default); None when
        the choice is undetermined. A trigger dispatches the rule's layered method under it."""
        clause = self.status[rule.index].clause
        return None if clause is None else rule.compositions[clause]

    def _compute(self, r: CompiledRule, v: Values) -> RuleStatus:
        if r.evaluate_all is None:
            return _DEFAULT
        try:
            values: tuple[bool | None, ...] = r.evaluate_all(v)
        except KeyError:
            pass  # some measure is unknown: find out which, clause by clause
        else:  # every value known (True or False): no ``unknown`` policy applies
            if self.semantics is HedgeSemantics.LAST_WINS:  # the last clause that holds
                # (what RuleStatus(values, k) makes, without the named tuple's Python frame)
                k = len(values) - values[::-1].index(True) if True in values else 0
                return _tuple_new(RuleStatus, (values, k, ()))
            return RuleStatus(values, choose(values, self.semantics, self.unknown))
        values, missing = evaluate(r.clauses, v)
        return RuleStatus(values, choose(values, self.semantics, self.unknown), missing)

    def update(self, changed: Collection[str], v: Values) -> list[LayerSwitch]:
        """Re-evaluate the rules that read a ``changed`` measure; return the layer switches."""
        index = self.index
        rules: Iterable[CompiledRule] = ()
        for first in changed:  # measures one rule alone reads (the usual update): that rule
            readers = index.get(first)
            if readers is not None and len(readers) == 1:
                only = self._alone.get(readers[0].index)
                if only is not None and only.issuperset(changed):
                    rules = readers
            break
        if not rules:
            touched: dict[int, CompiledRule] = {}
            for m in changed:
                for r in index.get(m, ()):
                    touched[r.index] = r
            rules = [touched[i] for i in sorted(touched)]  # rule order: the same switches every run
        switches: list[LayerSwitch] = []
        status = self.status
        for r in rules:
            i = r.index
            new = self._compute(r, v)
            old = status[i]
            status[i] = new
            if new.clause != old.clause:
                names = r.layer_names
                switches.append(
                    _tuple_new(
                        LayerSwitch,
                        (
                            r.name,
                            "?" if old.clause is None else names[old.clause],
                            "?" if new.clause is None else names[new.clause],
                        ),
                    )
                )
                if new.clause:
                    self._active[i] = r.clauses[new.clause - 1].layer
                else:
                    self._active.pop(i, None)
        return switches

    def recompute_all(self, v: Values) -> None:
        """Re-evaluate every rule (after a change of semantics)."""
        self.status = [self._compute(r, v) for r in self.ruleset.rules]
        self._active = {
            r.index: r.clauses[st.clause - 1].layer
            for r, st in zip(self.ruleset.rules, self.status)
            if st.clause
        }

    def state(self, switches: Iterable[LayerSwitch] = ()) -> LayerState:
        """The ``layers`` record now, after ``switches``; each call is a new version."""
        self.version += 1
        return LayerState(
            active=tuple(self.active_layers()),
            switches=tuple(switches),
            semantics=self.semantics,
            version=self.version,
        )

    def record_of(self, switches: Iterable[LayerSwitch]) -> Callable[[], dict[str, Any]]:
        """``state(switches).to_json`` -- the ``layers`` record now, a new version -- as a
        function that makes it when called (``Step.emit_later``: the hot path's record, which
        nobody may read): it keeps a copy of the active layers by rule, sorted when read."""
        self.version += 1
        return functools.partial(
            _layers_record, self._active.copy(), tuple(switches), self.semantics, self.version
        )

    def active_layers(self) -> list[str]:
        """The active layers, in rule order (a rule at its default or undetermined has none)."""
        return [self._active[i] for i in sorted(self._active)]

    def by_rule(self) -> dict[str, str | None]:
        """Every rule's layer, in rule order: its active layer, None at its default, ``"?"``
        undetermined (the names of a :class:`LayerSwitch`)."""
        return {
            r.name: "?" if st.clause is None else r.layer_names[st.clause]
            for r, st in zip(self.ruleset.rules, self.status)
        }

    def composition(self) -> Snapshot:
        """Every rule's active layer as one COP composition (for introspection with ``cosleec.cop``)."""
        rules = self.ruleset.rules
        return Snapshot(
            tuple(rules[i].layers[c - 1] for i in sorted(self._active) if (c := self.status[i].clause))
        )

    def set_semantics(self, semantics: HedgeSemantics, v: Values) -> None:
        """Switch between last-wins and nested clause choice, re-evaluating every rule."""
        self.semantics = HedgeSemantics(semantics)
        self.recompute_all(v)
