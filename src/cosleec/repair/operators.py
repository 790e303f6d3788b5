"""The repair operators: each makes one kind of edit to a rule file, as a :class:`Patch`.

At least SLEEC-PATCH's deterministic operators (rule removal, defeater introduction and
refinement, trigger strengthening, deadline refinement, rule merging and decomposition)
plus what cosleec's language adds (a priority between two rules). An operator knows how
to change the text; which change to try for which finding is candidates.py's business, and
whether a change repairs anything is verify.py's.
"""

from __future__ import annotations

import math
from dataclasses import replace

from cosleec.lang import ast as A
from cosleec.repair import deadlines
from cosleec.repair.patch import Patch
from cosleec.repair.writing import Writer


def conjoin(left: A.Expr | None, right: A.Expr) -> A.Expr:
    """``left and right`` (just ``right`` when there is no ``left``)."""
    return right if left is None else A.BinOp("and", left, right)


def disjoin(left: A.Expr | None, right: A.Expr | None) -> A.Expr | None:
    """``left or right``; None (always) when either is None."""
    return None if left is None or right is None else A.BinOp("or", left, right)


def negate(e: A.Expr) -> A.Expr:
    """``not e``, without a double negation."""
    return e.operand if isinstance(e, A.Not) else A.Not(e)


def opposite(o: A.Occurrence, untimed: float | None = None) -> A.Occurrence:
    """What rules out ``o`` over the same window: the prohibition of an event owed, the
    obligation of one forbidden. A window left unwritten is made explicit, as the analysis
    reads it (analysis/windows.py): a prohibition without a deadline covers its instant, so
    its opposite is due ``within 0 seconds``; an obligation without one has the reading's
    deadline (``untimed``: None, none at all), so its opposite forbids the event for as long."""
    if o.limit is not None or o.eventually:
        return A.Occurrence(o.event, negated=not o.negated, limit=o.limit, eventually=o.eventually)
    if o.negated:
        return A.Occurrence(o.event, limit=_within(0))
    if untimed is None:
        return A.Occurrence(o.event, negated=True, eventually=True)
    return A.Occurrence(o.event, negated=True, limit=_within(untimed))


def _within(seconds: float) -> A.TimeLimit:
    """``within N seconds`` (a whole number of seconds, rounded up: never a shorter window)."""
    return A.TimeLimit(A.Duration(A.IntLit(math.ceil(seconds)), "seconds"))


def only(o: A.Occurrence) -> A.Response:
    """A response of one item, ``o``."""
    return A.Response((A.ResponseItem(o),))


def requiring(response: A.Response, wanted: A.Occurrence) -> A.Response:
    """``response``'s items with ``wanted`` in place of any item about the same event (or
    added), without unless clauses: what a rule requires once it also requires ``wanted``."""
    kept = [it for it in response.items if it.occurrence.event != wanted.event]
    return A.Response((*kept, A.ResponseItem(wanted)))


class Operators:
    """The edits of one checked file (``source`` parsed to ``spec``), one method per operator."""

    def __init__(self, source: str, spec: A.Specification) -> None:
        self.spec = spec
        self.writer = Writer(source, spec)
        self.rules = {r.name: r for r in spec.rules}

    def say(self, e: A.Expr) -> str:
        """A condition as the file writes it."""
        return self.writer.expr(e)

    def remove(self, rule: A.Rule, why: str) -> Patch:
        """remove-rule: delete ``rule``."""
        edit = self.writer.remove_rule(rule)
        return Patch("remove-rule", f"remove {rule.name} ({why})", (rule.name,), (edit,))

    def rewrite(self, operator: str, old: A.Rule, new: A.Rule, summary: str) -> Patch:
        """Any operator that rewrites one rule in place: ``old`` becomes ``new``."""
        return Patch(operator, summary, (old.name,), (self.writer.replace_rule(old, new),))

    def remove_clause(self, rule: A.Rule, k: int, why: str) -> Patch:
        """remove-clause: drop ``rule``'s unless clause ``k`` (1-based)."""
        kept = tuple(d for i, d in enumerate(rule.response.defeaters, 1) if i != k)
        new = replace(rule, response=replace(rule.response, defeaters=kept))
        return self.rewrite("remove-clause", rule, new, f"{rule.name}: remove clause {k} ({why})")

    def add_unless(self, rule: A.Rule, condition: A.Expr, response: A.Response | None, why: str) -> Patch:
        """add-unless: append ``unless condition [then response]`` to ``rule``: its last
        clause, so that it wins where it holds (last-wins; nested reads it inside the others)."""
        clause = A.Defeater(condition, response)
        new = replace(rule, response=replace(rule.response, defeaters=(*rule.response.defeaters, clause)))
        then = "" if response is None else f" then {self.writer.printer.response(response, False)}"
        summary = f"{rule.name}: add `unless {self.say(condition)}{then}` ({why})"
        return self.rewrite("add-unless", rule, new, summary)

    def refine_unless(self, rule: A.Rule, k: int, excluded: A.Expr, why: str) -> Patch:
        """refine-unless: narrow ``rule``'s clause ``k`` to where ``excluded`` does not hold."""
        clauses = list(rule.response.defeaters)
        clauses[k - 1] = replace(
            clauses[k - 1], condition=conjoin(clauses[k - 1].condition, negate(excluded))
        )
        new = replace(rule, response=replace(rule.response, defeaters=tuple(clauses)))
        summary = f"{rule.name}: clause {k} only when {self.say(negate(excluded))} ({why})"
        return self.rewrite("refine-unless", rule, new, summary)

    def refine_trigger(self, rule: A.Rule, excluded: A.Expr, why: str) -> Patch:
        """refine-trigger: strengthen ``rule``'s trigger with ``and not excluded``."""
        t = rule.trigger
        new = replace(rule, trigger=replace(t, condition=conjoin(t.condition, negate(excluded))))
        summary = f"{rule.name}: trigger only when {self.say(negate(excluded))} ({why})"
        return self.rewrite("refine-trigger", rule, new, summary)

    def strengthen(self, rule: A.Rule, wanted: A.Occurrence, why: str) -> Patch | None:
        """strengthen-response: ``rule`` requires ``wanted`` too, in its default response (None
        when it already says something about that event: adding would contradict or repeat it)."""
        resp = rule.response
        if any(it.occurrence.event == wanted.event for it in resp.items):
            return None
        new = replace(rule, response=replace(resp, items=(*resp.items, A.ResponseItem(wanted))))
        said = self.writer.printer.occurrence(wanted)
        return self.rewrite("strengthen-response", rule, new, f"{rule.name}: also `{said}` ({why})")

    def add_rule(self, name: str, trigger: A.Trigger, response: A.Response, why: str) -> Patch:
        """add-rule: a new rule ``name when trigger then response``, after the last rule."""
        rule = A.Rule(self.writer.fresh_name(name), trigger, response)
        text = self.writer.rule_text(rule, "")
        return Patch("add-rule", f"add `{text}` ({why})", (), (self.writer.add_rule(rule),))

    def split(self, rule: A.Rule, at: A.Expr, there: A.Response, why: str) -> Patch:
        """split-rule: ``rule`` keeps the situations where ``at`` does not hold; a new rule
        answers those where it does with ``there``."""
        t = rule.trigger
        kept = replace(rule, trigger=replace(t, condition=conjoin(t.condition, negate(at))))
        name = self.writer.fresh_name(f"{rule.name}_split")
        part = A.Rule(name, replace(t, condition=conjoin(t.condition, at)), there)
        edits = (self.writer.replace_rule(rule, kept), self.writer.add_rule(part))
        summary = f"split {rule.name} at {self.say(at)} into {rule.name} and {name} ({why})"
        return Patch("split-rule", summary, (rule.name,), edits)

    def merge(self, first: A.Rule, second: A.Rule, why: str) -> Patch | None:
        """merge-rules: two rules with one trigger event and one response become one, triggered
        where either was (None when they differ in event or response, or when ``first``
        already covers ``second``: that is removing ``second``)."""
        if first.trigger.event != second.trigger.event or first.response != second.response:
            return None
        either = disjoin(first.trigger.condition, second.trigger.condition)
        merged = replace(first, trigger=replace(first.trigger, condition=either))
        if merged == first:
            return None
        edits = (self.writer.replace_rule(first, merged), self.writer.remove_rule(second))
        summary = f"merge {second.name} into {first.name} ({why})"
        return Patch("merge-rules", summary, (first.name, second.name), edits)

    def priority(self, higher: str, lower: str, why: str) -> Patch:
        """declare-priority: ``higher > lower`` in the priority block."""
        edit = self.writer.add_priority(higher, lower)
        return Patch("declare-priority", f"declare {higher} > {lower} ({why})", (higher, lower), (edit,))

    def deadline(self, rule: A.Rule, i: int, n: int, unit: str, why: str) -> Patch:
        """change-deadline: ``rule``'s item ``i`` within ``n`` ``unit``."""
        new = deadlines.with_deadline(rule, i, n, unit)
        said = self.writer.printer.occurrence(new.response.items[i].occurrence)
        return self.rewrite("change-deadline", rule, new, f"{rule.name}: `{said}` ({why})")


__all__ = ["Operators", "conjoin", "disjoin", "negate", "only", "opposite", "requiring"]
