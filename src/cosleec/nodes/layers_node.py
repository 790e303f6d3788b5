"""The COP Layer Manager node: keeps each rule's active hedge layer and publishes them latched.

It follows the same ``context`` stream as the Manager and publishes ``layers`` as
transient-local (latched), so a node that joins late sees the current layers at once.
"""

from __future__ import annotations

from typing import Any

from cosleec.nodes.base import Node, context_values
from cosleec.runtime import ContextError
from cosleec.runtime.context import Context
from cosleec.runtime.layers import LayerManager, switch_records, switches_json
from cosleec.runtime.manager import load_rules
from cosleec.runtime.model import compile_rules


class LayersNode(Node):
    name = "layers"

    def __init__(
        self, transport: Any, rules: str, *, namespace: str = "/cosleec", semantics: str = "last-wins"
    ) -> None:
        super().__init__(transport, namespace)
        spec, symbols = load_rules(rules)
        self.ruleset = compile_rules(spec, symbols)
        self.context = Context(self.ruleset.measures)
        self.layers = LayerManager(self.ruleset, semantics)
        self.version = 0
        self.advertise("layers")
        self.on("context", self._context)
        self._publish([])

    def _context(self, msg: dict[str, Any]) -> None:
        try:
            stored = self.context.validate(context_values(msg))
        except ContextError as e:
            raise ValueError(str(e)) from e
        changed = self.context.apply(stored, 0.0)
        switches = self.layers.update(changed, self.context.values)
        if switches:
            self._publish(switches_json(switch_records(switches)))

    def _publish(self, switches: list[dict[str, Any]]) -> None:
        self.version += 1
        self.publish(
            "layers",
            {
                "active": self.layers.active_layers(),
                "switches": switches,
                "version": self.version,
                "semantics": self.layers.semantics,
            },
        )
