"""A generic context-oriented programming runtime (imports nothing of SLEEC).

Layers, their activation (scoped, global, by event), hedge groups selected by predicate,
and one dispatcher. In short::

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

Modules: ``layer`` (layers, groups, policies), ``state`` (the global configuration,
deferral), ``extent`` (scoped activation, capture and replay), ``dispatch`` (layered
functions and the reference dispatcher), ``fastpath`` (the generated dispatcher),
``decorate`` (``@layered``), ``introspect``, ``events``, ``generators``, ``errors``.
"""

from cosleec.cop.decorate import layered, on_dispatch, partial
from cosleec.cop.dispatch import DispatchRecord, LayeredFunction, current_context, using_context
from cosleec.cop.errors import (
    ActivationError,
    COPError,
    DefinitionError,
    ExclusionError,
    HedgeEvaluationError,
)
from cosleec.cop.events import Transitions
from cosleec.cop.extent import Snapshot, activate, activating, bind, deactivate, run_with, snapshot
from cosleec.cop.generators import layered_generator
from cosleec.cop.introspect import Explanation, current_layers, explain
from cosleec.cop.layer import POLICIES, HedgeGroup, Layer, LayerGroup, policy_first, policy_last
from cosleec.cop.state import (
    GlobalState,
    activate_globally,
    active_layers,
    add_activation_hook,
    at_safe_point,
    critical,
    deactivate_globally,
    global_count,
    global_state,
    is_active,
    restore_globally,
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
    "GlobalState",
    "HedgeEvaluationError",
    "HedgeGroup",
    "Layer",
    "LayerGroup",
    "LayeredFunction",
    "Snapshot",
    "Transitions",
    "activate",
    "activate_globally",
    "activating",
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
    "global_state",
    "is_active",
    "layered",
    "layered_generator",
    "on_dispatch",
    "partial",
    "policy_first",
    "policy_last",
    "restore_globally",
    "run_with",
    "snapshot",
    "swap_globally",
    "using_context",
]
