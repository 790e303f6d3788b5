"""Views of a running Manager, found by name: the extension point behind ``Manager(web=PORT)``.

The runtime draws nothing and serves nothing (it sits on floor 1; the views live on floor
3, :mod:`cosleec.views`). A view is installed as an entry point of the group
``cosleec.views``; the Manager loads it by name when it is asked for one (``web`` is
declared by cosleec's own ``pyproject.toml`` as ``cosleec.views.web:serve``, installed with
the ``web`` extra). A view factory is called once, when the Manager starts, with the
Manager and the options it was given, and returns a :class:`View`; the Manager closes the
view first thing in :meth:`~cosleec.runtime.Manager.close`.

A view learns what happens as every observer does (:meth:`Manager.subscribe
<cosleec.runtime.Manager.subscribe>`) and reads the Manager's public, thread-safe state
(``values()``, ``rule_layers()``, ``outstanding()``, ``clock``); it must never block the
runtime's threads.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import metadata
from typing import Any, Protocol

from cosleec.errors import ConfigurationError

#: the entry point group views are registered in (``[project.entry-points."cosleec.views"]``)
GROUP = "cosleec.views"


class View(Protocol):
    """What the Manager keeps of a view it started: where it is, and how to stop it."""

    @property
    def url(self) -> str:
        """Where to look at it (``http://127.0.0.1:8765/`` for the web view)."""
        ...

    def close(self) -> None:
        """Stop it and free what it holds (threads, ports); called once, by ``Manager.close()``."""
        ...


#: a view factory: ``factory(manager, options) -> View``, called when the Manager starts;
#: ``options`` is what the Manager was given (``web=8765`` or ``web={"port": 0, ...}``)
ViewFactory = Callable[[Any, Any], View]


def load_view(name: str) -> ViewFactory:
    """The factory of the view installed as ``name`` in the group ``cosleec.views``.

    ConfigurationError (a UserError) when no such view is installed, or when it cannot be
    imported (a dependency is missing): the hint says which extra to install.
    """
    hint = f"install it: pip install 'cosleec[{name}]'"
    found = metadata.entry_points(group=GROUP, name=name)
    if not found:
        raise ConfigurationError(f"the {name} view is not installed", hint=hint)
    point = next(iter(found))
    try:
        factory = point.load()
    except ImportError as e:
        raise ConfigurationError(
            f"the {name} view cannot be loaded: {e}", hint=f"{hint} (it needs {e.name or 'a module'})"
        ) from None
    if not callable(factory):
        raise ConfigurationError(f"the {name} view ({point.value}) is not a view factory")
    return factory  # type: ignore[no-any-return]
