"""CO-SLEEC: SLEEC rules become COP layers; the context drives activation; triggers dispatch.

from cosleec.runtime import Manager, Task, hedge

m = Manager("rules.sleec")
m.update(userUndressed=True, userDistressed=False)
m.event("CurtainOpenRequest")     # -> [Decision(rule="R1", clause=1, layer="R1.1", ...)]
"""

from cosleec.runtime.audit import AuditLog
from cosleec.runtime.clock import Clock, MonotonicClock, VirtualClock
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError, ContextError, UnknownMeasureError
from cosleec.runtime.layers import LayerManager, select
from cosleec.runtime.manager import Manager, RuntimeEvent, load_rules
from cosleec.runtime.model import Obligation
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.tasks import Task, hedge

__all__ = [
    "AuditLog",
    "BindingError",
    "Clock",
    "ContextError",
    "Decision",
    "LayerManager",
    "Manager",
    "MonotonicClock",
    "Obligation",
    "RuntimeEvent",
    "Task",
    "Tracked",
    "UnknownMeasureError",
    "VirtualClock",
    "hedge",
    "load_rules",
    "select",
]
