"""A rule as a subtree: the paper's COP mapping (a task per rule, a layer per clause) as a tree.

CO-SLEEC maps a rule's trigger to a layered method's dispatch, the default response to
its base implementation and each ``unless`` clause to a layer-bound variant (the paper's
Table 1). :class:`RuleTask` is that method in a behaviour tree: its children are the
default subtree and one subtree per clause, in the rule's order; when the tree ticks it
(the trigger happened), it reports the trigger, takes the Manager's :class:`Decision`
for its rule and runs the child of the layer the decision names: ``R1.2`` runs the
third child, the default the first. Which layer is active is the Manager's answer, never
the tree's own reading of the context.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import py_trees
from py_trees.common import Access, Status

from cosleec.bt.link import Link, link_for
from cosleec.errors import CosleecError
from cosleec.runtime import Decision, Manager

#: the blackboard key (``.../R1``) where a rule task leaves the decision it ran, for its
#: subtree (an ``ExplainWhy`` says ``decision.explanation``)
DECISION_KEY = "/cosleec/decision"


class RuleTask(py_trees.composites.Composite):
    """Run the subtree of the layer the Manager chooses when ``trigger`` occurs (see the module).

    ``default`` implements the default response; ``clauses[i - 1]`` implements clause i
    (layer ``rule.i``). On a new run (a tick when not RUNNING) it reports ``trigger``
    through the link and takes the decision for ``rule``; then it ticks the chosen child
    until that child finishes, and ends with the child's status. FAILURE, with the reason
    as :attr:`feedback_message`, when nothing can be run: the Manager cannot decide, the
    decision is undetermined (a measure has no value), or it names a clause the tree has
    no subtree for. SUCCESS with nothing run when the trigger did not fire the rule (a
    trigger condition that does not hold: nothing is owed).
    """

    def __init__(
        self,
        rule: str,
        trigger: str,
        manager: Link | Manager,
        default: py_trees.behaviour.Behaviour,
        clauses: Sequence[py_trees.behaviour.Behaviour] = (),
        name: str | None = None,
    ) -> None:
        super().__init__(name or f"{rule} on {trigger}", [default, *clauses])
        self.rule, self.trigger = rule, trigger
        self.link = link_for(manager)
        self.decision: Decision | None = None
        self.key = f"{DECISION_KEY}/{rule}"
        self.board = self.attach_blackboard_client(name=self.name)
        self.board.register_key(key=self.key, access=Access.WRITE)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Decide on a new run, then tick the chosen child; this composite ends with it."""
        if self.status != Status.RUNNING:
            for old in self.children:
                if old.status != Status.INVALID:
                    old.stop(Status.INVALID)
            self.current_child = None
            chosen, why = self._choose()
            self.feedback_message = why
            if isinstance(chosen, Status):  # nothing to run: this run ends now
                self.stop(chosen)
                yield self
                return
            self.current_child = chosen
        child = self.current_child
        if child is None:  # RUNNING with no child: only a subclass that set the status could
            raise RuntimeError(f"{self.name} is running but chose no subtree")
        yield from child.tick()
        if child.status == Status.RUNNING:
            self.status = Status.RUNNING
        else:
            self.stop(child.status)
        yield self

    def _choose(self) -> tuple[py_trees.behaviour.Behaviour | Status, str]:
        """Report the trigger and pick the child of the decision's layer: (the child, or the
        status this run ends with when there is none to run; why)."""
        self.decision = None
        try:
            decisions = self.link.decide(self.trigger)
        except CosleecError as e:  # LinkError, a refused Decide, an undeclared trigger (ContextError)
            return Status.FAILURE, f"{self.rule}: the Manager could not decide on {self.trigger}: {e}"
        mine = [d for d in decisions if d.rule == self.rule and not d.fallback]
        if not mine:
            return (
                Status.SUCCESS,
                f"{self.trigger} did not trigger {self.rule} (its trigger condition is false): nothing owed",
            )
        d = self.decision = mine[-1]
        self.board.set(self.key, d, overwrite=True)
        if d.clause is None:  # undetermined: nothing is done, and the tree hears it failed
            return Status.FAILURE, d.explanation
        if d.clause >= len(self.children):
            have = f"a default and {len(self.children) - 1} clause subtree(s)"
            return Status.FAILURE, f"{self.rule} chose layer {d.layer} but this rule task has only {have}"
        layer = d.layer or "default"
        return self.children[d.clause], f"{layer}: {d.explanation}"
