"""CO-SLEEC: SLEEC rules become COP layers; the context drives activation; triggers dispatch.

The face of the runtime: other packages import only what is listed here. ::

    from cosleec.runtime import Manager

    m = Manager.from_file("rules.sleec")
    m.update(userUndressed=True, userDistressed="low")
    m.event("CurtainOpenRequest")     # -> [Decision(rule="R1", clause=1, layer="R1.1", ...)]

How a rule becomes layers: :mod:`cosleec.runtime.model`; how the context picks them:
:mod:`cosleec.runtime.layers`; how a trigger reaches its variant:
:mod:`cosleec.runtime.implementations`.
"""

from cosleec.lang import HedgeSemantics, Unknowns
from cosleec.records import RuntimeEvent
from cosleec.runtime.audit import AuditLog, read_audit
from cosleec.runtime.clock import Clock, MonotonicClock, VirtualClock
from cosleec.runtime.context import Context
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError, ConfigurationError, ContextError, ReloadError
from cosleec.runtime.implementations import Capability, Implementations, Ran
from cosleec.runtime.journal import Journal, JournalError
from cosleec.runtime.layers import LayerManager, LayerState, LayerSwitch
from cosleec.runtime.manager import Manager, Permission, Reloaded, UnknownEvents
from cosleec.runtime.model import MAX_WINDOW_S, CompiledRule, DeadlineError, Obligation
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.priorities import PossibleConflict, Priorities, possible_conflicts
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.scaffold import STYLES as SCAFFOLD_STYLES
from cosleec.runtime.scaffold import scaffold
from cosleec.runtime.tasks import Reporter, Task, hedge
from cosleec.runtime.values import MeasureSpec, Value
from cosleec.runtime.views import View, ViewFactory, load_view

__all__ = [
    "MAX_WINDOW_S",
    "SCAFFOLD_STYLES",
    "AuditLog",
    "BindingError",
    "Capability",
    "Clock",
    "CompiledRule",
    "ConfigurationError",
    "Context",
    "ContextError",
    "DeadlineError",
    "Decision",
    "HedgeSemantics",
    "Implementations",
    "Journal",
    "JournalError",
    "LayerManager",
    "LayerState",
    "LayerSwitch",
    "Manager",
    "MeasureSpec",
    "MonotonicClock",
    "Obligation",
    "Permission",
    "PossibleConflict",
    "Priorities",
    "Ran",
    "ReloadError",
    "Reloaded",
    "Reporter",
    "RuleSet",
    "RuntimeEvent",
    "Task",
    "Tracked",
    "UnknownEvents",
    "Unknowns",
    "Value",
    "View",
    "ViewFactory",
    "VirtualClock",
    "hedge",
    "load_view",
    "possible_conflicts",
    "read_audit",
    "scaffold",
]
