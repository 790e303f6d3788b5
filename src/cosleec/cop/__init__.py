"""A generic context-oriented programming runtime (imports nothing of SLEEC).

Vocabulary and guarantees: ``../shared/reference/cop-runtime.md``. In short::

    from cosleec.cop import Layer, layered, activate

    loud = Layer("Loud")

    @layered
    def greet(name):
        return f"hello {name}"

    @greet.variant(loud)
    def _(name, *, proceed):
        return proceed().upper()

    with activate(loud):
        greet("ada")   # 'HELLO ADA'
"""

from cosleec.cop.dispatch import (
    DispatchRecord,
    LayeredFunction,
    current_context,
    layered,
    on_dispatch,
    partial,
    using_context,
)
from cosleec.cop.errors import (
    ActivationError,
    COPError,
    DefinitionError,
    ExclusionError,
    HedgeEvaluationError,
)
from cosleec.cop.events import Transitions
from cosleec.cop.generators import layered_generator
from cosleec.cop.introspect import Explanation, current_layers, explain
from cosleec.cop.layer import (
    POLICIES,
    HedgeGroup,
    Layer,
    LayerGroup,
    policy_first,
    policy_last,
    policy_nested,
)
from cosleec.cop.state import (
    Snapshot,
    activate,
    activate_globally,
    active_layers,
    add_activation_hook,
    at_safe_point,
    bind,
    critical,
    deactivate,
    deactivate_globally,
    global_count,
    is_active,
    run_with,
    snapshot,
    swap_globally,
)

__all__ = [
    "POLICIES",
    "ActivationError",
    "COPError",
    "DefinitionError",
    "DispatchRecord",
    "ExclusionError",
    "Explanation",
    "HedgeEvaluationError",
    "HedgeGroup",
    "Layer",
    "LayerGroup",
    "LayeredFunction",
    "Snapshot",
    "Transitions",
    "activate",
    "activate_globally",
    "active_layers",
    "add_activation_hook",
    "at_safe_point",
    "bind",
    "critical",
    "current_context",
    "current_layers",
    "deactivate",
    "deactivate_globally",
    "explain",
    "global_count",
    "is_active",
    "layered",
    "layered_generator",
    "on_dispatch",
    "partial",
    "policy_first",
    "policy_last",
    "policy_nested",
    "run_with",
    "snapshot",
    "swap_globally",
    "using_context",
]
