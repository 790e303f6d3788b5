"""The decider: a trigger (or a missed deadline) becomes a :class:`~cosleec.runtime.decision.Decision`.

At a trigger, the rule's condition is read on the context (three-valued: an unknown
measure leaves it undetermined unless the ``unknown`` policy reads it), the Layer
Manager's status says which clause is active, and the issuer turns that clause's response
into obligations -- or, undetermined, into the prohibitions of every clause that could
apply (fail closed). At a missed deadline, the obligation's ``otherwise`` is decided the
same way (an ``otherwise`` decision).

The decider makes decisions; it does not record them or put them in force (the Manager
and the enforcer do).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from cosleec.lang import Unknowns
from cosleec.runtime.context import Context
from cosleec.runtime.decision import OTHERWISE, Decision, DecisionOrigin
from cosleec.runtime.explanations import Explanations
from cosleec.runtime.issuer import Issuer
from cosleec.runtime.layers import LayerManager
from cosleec.runtime.model import CompiledRule, Obligation
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.stats import Stats
from cosleec.runtime.values import Value

id_of = id  # (the builtin: ``id`` is a decision's number here)
_FIELDS_KEPT = 1 << 16  # rule clauses whose common decision fields are kept


class Decider:
    """Decides on ``context`` as ``layers`` reads it, numbering decisions with ``next_id``."""

    def __init__(
        self, context: Context, layers: LayerManager, issuer: Issuer, next_id: Callable[[], int], stats: Stats
    ) -> None:
        self.context = context
        self.layers = layers
        self.issuer = issuer
        self.next_id = next_id
        self.stats = stats
        self.explanations: Explanations | None = None
        self._reads: dict[str, tuple[str, ...]] = {}  # rule -> the measures its sentences name
        # (id of a rule, clause) -> (the rule, semantics, unknown, explanations it was made
        # under, the fields every decision of that clause has in common)
        self._fields: dict[tuple[int, int | None], tuple[Any, ...]] = {}

    def explain_with(self, explanations: Explanations | None, rules: Iterable[CompiledRule]) -> None:
        """Give every decision from now on ``explanations`` (None: sentences in plain words only),
        and keep the values of the measures its sentences name (``{name}``) in decisions."""
        self.explanations = explanations
        self._reads = {}
        if explanations is not None:
            self._reads = {r.name: n for r in rules if (n := explanations.reads(r.name))}

    @property
    def speaks(self) -> bool:
        """Do decisions keep the values their sentences for people name (beyond what they read)?"""
        return bool(self._reads)

    def decide(self, rule: CompiledRule, event: str, now: float) -> Decision | None:
        """``rule``'s decision at its trigger ``event``: None when its condition is false."""
        v = self.context.values
        fired, missing = self._fired(rule, v)
        if fired is False:
            return None
        status = self.layers.status[rule.index]
        clause = status.clause if fired else None
        if fired and clause is None:
            missing = status.missing
        if clause is not None:
            issued = self.issuer.issue(rule.response_of(clause), rule.name)
            if not issued.determined:  # an inner response's own `unless` is unknown
                clause, missing = None, issued.missing
        else:
            issued = self.issuer.undetermined(rule, status.values)
        if clause is None:
            self.stats.undetermined += 1
        if not self._reads:  # values and conditions made when first read
            return self.at_trigger(
                self.next_id(), rule, event, now, clause, fired, status.values, issued.obligations, missing
            )
        conds = ((0, rule.trigger_text, fired), *zip(rule.clause_ids, rule.clause_texts, status.values))
        names = rule.value_names
        values = dict(zip(names, map(v.get, names)))
        for n, lits in rule.scale_values:  # scale positions back to their literals
            x = values[n]
            if x is not None:
                values[n] = lits[x]
        self._spoken(rule.name, values)  # the values its sentences for people name too
        return Decision.made(
            id=self.next_id(),
            time=now,
            event=event,
            rule=rule.name,
            clause=clause,
            layer=rule.layer_of(clause) if clause else None,
            semantics=self.layers.semantics,
            values=values,
            conditions=conds,
            obligations=issued.obligations,
            missing=missing,
            context_version=self.context.version,
            unknown=self.layers.unknown,
            explanations=self.explanations,
        )

    def at_trigger(
        self,
        id: int,
        rule: CompiledRule,
        event: str,
        now: float,
        clause: int | None,
        fired: bool | None,
        status: tuple[bool | None, ...],
        obligations: tuple[Obligation, ...],
        missing: tuple[str, ...],
    ) -> Decision:
        """Decision ``id`` of ``rule`` at its trigger ``event``, as the context and the Layer
        Manager read now: what it read kept, its values and conditions made when first read
        (what :meth:`Decision.at_trigger` makes, with the fields common to the rule's clause
        made once and kept here). For :meth:`decide` and the express lane alike; not for a
        decider whose explanations name more values (:attr:`speaks`)."""
        v = self.context.values
        layers, explanations = self.layers, self.explanations
        kept = self._fields.get((id_of(rule), clause))  # made once per rule and clause, as read now
        if (
            kept is None
            or kept[0] is not rule
            or kept[1] is not layers.semantics
            or kept[2] is not layers.unknown
            or kept[3] is not explanations
        ):
            if len(self._fields) > _FIELDS_KEPT:  # (a bound, in defence: a reload makes a new decider)
                self._fields.clear()
            fields = Decision.trigger_fields(
                rule, clause, semantics=layers.semantics, unknown=layers.unknown, explanations=explanations
            )
            kept = self._fields[id_of(rule), clause] = (
                rule,
                layers.semantics,
                layers.unknown,
                explanations,
                fields,
            )
        return Decision.from_trigger_fields(
            kept[4],
            id,
            now,
            event,
            obligations,
            missing,
            self.context.version,
            (rule, tuple(map(v.get, rule.value_names)), fired, status),
        )

    def _spoken(self, rule: str, values: dict[str, Value | None]) -> None:
        """Add the values the sentences of ``rule`` name and the decision did not read."""
        more = [n for n in self._reads.get(rule, ()) if n not in values and n in self.context.measures]
        if more:
            values.update(self.context.external(more))

    def _fired(self, rule: CompiledRule, v: dict[str, object]) -> tuple[bool | None, tuple[str, ...]]:
        """Did the trigger condition hold (None: unknown), and the measures it lacked."""
        try:
            return bool(rule.condition(v)), ()
        except KeyError:
            x = rule.trigger_kleene(v)
            fired = None if x is None else bool(x)
            unknown = self.layers.unknown
            if fired is None and unknown != Unknowns.UNDETERMINED:
                fired = unknown == Unknowns.TRUE  # the policy reads it so
            if fired is None:
                return None, tuple(sorted(n for n in rule.trigger_reads if n not in v))
            return fired, ()

    def fallback(self, rule: CompiledRule, t: Tracked, start: float) -> tuple[Decision, bool]:
        """The ``otherwise`` decision of ``t``, violated at ``start``, of ``rule``, and whether it
        is determined (an inner choice an unknown value leaves open: only prohibitions, nothing runs)."""
        ob = t.obligation
        assert ob.otherwise is not None
        issued = self.issuer.issue(ob.otherwise, rule.name)
        what = " and ".join(o.describe() for o in issued.obligations) or "nothing is required"
        if not issued.determined:
            what = f"undetermined (no value for {', '.join(issued.missing)}); meanwhile {what}"
        why = f"{rule.name}: {ob.describe()} was violated; otherwise {what}"
        values: dict[str, Value | None] = {}
        if self._reads:
            self._spoken(rule.name, values)
        d = Decision.made(
            id=self.next_id(),
            time=start,
            event=OTHERWISE,
            rule=rule.name,
            clause=t.clause if issued.determined else None,
            layer=None,
            semantics=self.layers.semantics,
            values=values,
            conditions=(),
            obligations=issued.obligations,
            missing=issued.missing,
            reason=why,
            context_version=self.context.version,
            violated=t.id,
            origin=DecisionOrigin.OTHERWISE,
            missed=ob,
            explanations=self.explanations,
        )
        return d, issued.determined
