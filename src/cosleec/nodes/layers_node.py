"""The COP Layer Manager node: keeps each rule's active hedge layer and publishes them latched.

It follows the same ``context`` stream as the Manager and publishes ``layers`` as
transient-local (latched), so a node that joins late sees the current layers at once.
"""

from __future__ import annotations

from typing import Any

from cosleec.lang import clause_semantics_for
from cosleec.nodes.base import MessageError, Node, context_values
from cosleec.nodes.transport import DEFAULT_NAMESPACE, Transport
from cosleec.runtime import (
    Context,
    ContextError,
    HedgeSemantics,
    LayerManager,
    LayerSwitch,
    RuleSet,
    Unknowns,
)


class LayersNode(Node):
    """The Layer Manager as a node of its own: run it when other nodes want the active layers.

    It decides nothing: the Manager node keeps its own Layer Manager and stamps each
    decision with its clause. This node publishes the same layer state for everyone else
    (dashboards, the scenario driver), once at start and after every switch.
    """

    name = "layers"

    def __init__(
        self,
        transport: Transport,
        rules: RuleSet,
        *,
        namespace: str = DEFAULT_NAMESPACE,
        semantics: HedgeSemantics | None = None,
        unknown: Unknowns = Unknowns.UNDETERMINED,
    ) -> None:
        super().__init__(transport, namespace)
        self.ruleset = rules
        self.context = Context(rules.measures)
        # as the Manager node's (the option, else the rule file's block), or they disagree
        self.layer_manager = LayerManager(rules, clause_semantics_for(rules.spec, semantics), unknown)
        self.advertise("layers")
        self.on("context", self._context)
        self._publish([])

    def _context(self, msg: dict[str, Any]) -> None:
        try:
            stored = self.context.validate(context_values(msg))
        except ContextError as e:
            raise MessageError(str(e)) from e
        changed = self.context.apply(stored, 0.0)
        switches = self.layer_manager.update(changed, self.context.values)
        if switches:
            self._publish(switches)

    def _publish(self, switches: list[LayerSwitch]) -> None:
        self.publish("layers", self.layer_manager.state(switches).to_json())
