"""cosleec: make robots behave according to SLEEC rules, with context-oriented programming.

The names a program embedding the runtime needs come from here::

    from cosleec import Manager, RuleSet, Task, hedge, VirtualClock

They are loaded on first use (``import cosleec`` alone stays light: the command line and
the ROS nodes import only what they run). Everything else lives in its package, one role
each:

- :mod:`cosleec.lang` -- the SLEEC language: parser (TK, LEGOS, paper notation), checker, printer;
- :mod:`cosleec.cop` -- a generic context-oriented programming runtime (knows nothing of SLEEC);
- :mod:`cosleec.runtime` -- CO-SLEEC: rules become layers, the context drives activation;
- :mod:`cosleec.ros` -- adapters for ROS 2 and ROS 1 (the core never imports them);
- :mod:`cosleec.cli` -- the ``cosleec`` command.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: what ``from cosleec import ...`` offers, and the module each name comes from
_EXPORTS = {
    "Manager": "cosleec.runtime",
    "RuleSet": "cosleec.runtime",
    "Task": "cosleec.runtime",
    "hedge": "cosleec.runtime",
    "Decision": "cosleec.runtime",
    "Permission": "cosleec.runtime",
    "VirtualClock": "cosleec.runtime",
    "MonotonicClock": "cosleec.runtime",
    "AuditLog": "cosleec.runtime",
    "ContextError": "cosleec.runtime",
    "BindingError": "cosleec.runtime",
    "JournalError": "cosleec.runtime",
    "CosleecError": "cosleec.errors",
}

__all__ = [  # the same names as _EXPORTS (tests/test_exports.py holds them to each other)
    "AuditLog",
    "BindingError",
    "ContextError",
    "CosleecError",
    "Decision",
    "JournalError",
    "Manager",
    "MonotonicClock",
    "Permission",
    "RuleSet",
    "Task",
    "VirtualClock",
    "__version__",
    "hedge",
]

if TYPE_CHECKING:  # what type checkers and editors see; at run time, __getattr__ loads them
    from cosleec.errors import CosleecError
    from cosleec.runtime import (
        AuditLog,
        BindingError,
        ContextError,
        Decision,
        JournalError,
        Manager,
        MonotonicClock,
        Permission,
        RuleSet,
        Task,
        VirtualClock,
        hedge,
    )


def __getattr__(name: str) -> Any:
    """Load an exported name on first use (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'cosleec' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # the next use is a plain lookup
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
