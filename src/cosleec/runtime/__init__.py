"""CO-SLEEC: SLEEC rules become COP layers; the context drives activation; triggers dispatch.

The face of the runtime. Users need what :data:`__all__` lists (``from cosleec import
Manager`` gives the first few without loading anything else)::

    from cosleec.runtime import Manager

    m = Manager.from_file("rules.sleec")
    m.update(userUndressed=True, userDistressed="low")
    m.event("CurtainOpenRequest")     # -> [Decision(rule="R1", clause=1, layer="R1.1", ...)]

How the Manager is built from parts, each with one job: :mod:`cosleec.runtime.manager`.
How a rule becomes layers: :mod:`cosleec.runtime.model`; how the context picks them:
:mod:`cosleec.runtime.layers`; how a trigger reaches its variant:
:mod:`cosleec.runtime.implementations`.

The names imported below :data:`__all__`'s but not listed in it (``LayerManager``,
``Context``, ``Implementations``, ...) are for cosleec's own nodes and tools, which import
only from this face (tests/test_layering.py): internals, not API -- they may change.
"""

from cosleec.lang import HedgeSemantics, Unknowns
from cosleec.records import RuntimeEvent
from cosleec.runtime.audit import AuditLog, read_audit
from cosleec.runtime.clock import Clock, MonotonicClock, VirtualClock
from cosleec.runtime.context import Context as Context
from cosleec.runtime.decision import Decision, DecisionOrigin
from cosleec.runtime.decision import said_in as said_in
from cosleec.runtime.errors import BindingError, ConfigurationError, ContextError, ReloadError
from cosleec.runtime.explanations import Explanations, ExplanationsError
from cosleec.runtime.implementations import Capability
from cosleec.runtime.implementations import Implementations as Implementations
from cosleec.runtime.implementations import Ran as Ran
from cosleec.runtime.journal import Journal, JournalError
from cosleec.runtime.layers import LayerManager as LayerManager
from cosleec.runtime.layers import LayerState, LayerSwitch
from cosleec.runtime.manager import Manager
from cosleec.runtime.model import MAX_WINDOW_S, DeadlineError, Obligation
from cosleec.runtime.model import CompiledRule as CompiledRule
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.options import Options, UnknownEvents
from cosleec.runtime.permission import Permission
from cosleec.runtime.priorities import PossibleConflict
from cosleec.runtime.priorities import Priorities as Priorities
from cosleec.runtime.priorities import possible_conflicts as possible_conflicts
from cosleec.runtime.reload import Reloaded
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.scaffold import STYLES as SCAFFOLD_STYLES
from cosleec.runtime.scaffold import scaffold
from cosleec.runtime.stats import Stats
from cosleec.runtime.tasks import Reporter, Task, hedge
from cosleec.runtime.values import MeasureSpec as MeasureSpec
from cosleec.runtime.values import Value

#: the public API (tests/unit/runtime/test_face.py holds it to this list)
__all__ = [
    "MAX_WINDOW_S",
    "SCAFFOLD_STYLES",
    "AuditLog",
    "BindingError",
    "Capability",
    "Clock",
    "ConfigurationError",
    "ContextError",
    "DeadlineError",
    "Decision",
    "DecisionOrigin",
    "Explanations",
    "ExplanationsError",
    "HedgeSemantics",
    "Journal",
    "JournalError",
    "LayerState",
    "LayerSwitch",
    "Manager",
    "MonotonicClock",
    "Obligation",
    "Options",
    "Permission",
    "PossibleConflict",
    "ReloadError",
    "Reloaded",
    "Reporter",
    "RuleSet",
    "RuntimeEvent",
    "Stats",
    "Task",
    "Tracked",
    "UnknownEvents",
    "Unknowns",
    "Value",
    "VirtualClock",
    "hedge",
    "read_audit",
    "scaffold",
]

#: what cosleec's own packages import from this face besides the API: internals
INTERNALS = (
    "CompiledRule",
    "Context",
    "Implementations",
    "LayerManager",
    "MeasureSpec",
    "Priorities",
    "Ran",
    "possible_conflicts",
    "said_in",
)
