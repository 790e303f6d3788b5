"""Views of a running Manager, found by name and attached to it from outside the runtime.

The runtime draws nothing, serves nothing and names no view (it sits on floor 1; the views
live here, on floor 3). A view is installed as an entry point of the group
``cosleec.views`` and found by name (``web`` is declared by cosleec's own ``pyproject.toml``
as ``cosleec.views.web:serve``, installed with the ``web`` extra), so that this package does
not depend on the web packages either until a view is asked for.

A view factory is called with the Manager and the options it was given and returns a
:class:`View`; the view learns what happens as every observer does (:meth:`Manager.subscribe
<cosleec.runtime.Manager.subscribe>`) and reads the Manager's public, thread-safe state
(``values()``, ``rule_layers()``, ``outstanding()``, ``clock``); it must never block the
runtime's threads. The caller owns the order: attach the view *before*
:meth:`Manager.start <cosleec.runtime.Manager.start>` (it hears start's records), close it
*before* :meth:`Manager.close <cosleec.runtime.Manager.close>` (its port is free again,
and it no longer reads a closed Manager). :func:`attach` makes one view;
:class:`AttachedView` keeps that order for a caller that starts and closes Managers
(a ``with`` block, a lifecycle node that builds a new Manager on each configure).
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import metadata
from types import TracebackType
from typing import Any, Protocol

from cosleec.errors import ConfigurationError
from cosleec.runtime import Manager

#: the entry point group views are registered in (``[project.entry-points."cosleec.views"]``)
GROUP = "cosleec.views"


class View(Protocol):
    """What a caller keeps of a view it attached: where it is, and how to stop it."""

    @property
    def url(self) -> str:
        """Where to look at it (``http://127.0.0.1:8765/`` for the web view)."""
        ...

    def close(self) -> None:
        """Stop it and free what it holds (threads, ports); called before the Manager closes."""
        ...


#: a view factory: ``factory(manager, options) -> View``, called when the view is attached;
#: ``options`` is what :func:`attach` was given (for ``web``: ``8765``, or ``{"port": 0, ...}``)
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


def attach(manager: Manager, options: object = 0, *, name: str = "web") -> View:
    """Attach the view installed as ``name`` to ``manager``: it serves (and follows the
    Manager) from now until its ``close()``.

    Call it before ``manager.start()`` so that the view hears start's records, and close
    the view before ``manager.close()``. For ``web``, ``options`` is a port (0 takes a free
    one) or a mapping of options (:class:`~cosleec.views.web.WebOptions`); the view's
    ``url`` says where it serves. ConfigurationError as :func:`load_view` says, or when the
    options are wrong; UserError when the port is taken.
    """
    return load_view(name)(manager, options)


class AttachedView:
    """The view of one Manager at a time, for a caller that builds, starts and closes them.

    Made before any Manager: the view is found by name at once (a missing extra is said
    before a Manager opens its files). :meth:`attach` gives a Manager its view (call it
    before the Manager starts); :meth:`close` stops it (call it before the Manager closes):
    as a ``with`` block, the view is closed on the way out, so a start that fails inside it
    serves nothing. Attaching another Manager first closes the view of the previous one
    (its port is free for the next); attaching the same one again keeps its view.
    """

    def __init__(self, options: object = 0, *, name: str = "web") -> None:
        self.name = name
        self.options = options
        self._factory = load_view(name)
        self.view: View | None = None
        self._manager: Manager | None = None

    @property
    def url(self) -> str | None:
        """Where the view serves, while one is attached; None before :meth:`attach` and after :meth:`close`."""
        return None if self.view is None else self.view.url

    def attach(self, manager: Manager) -> View:
        """The view of ``manager``, made now unless it has one (see :func:`attach`)."""
        if self.view is not None and self._manager is manager:
            return self.view
        self.close()
        self.view = self._factory(manager, self.options)
        self._manager = manager
        return self.view

    def start(self, manager: Manager, *, check: bool = True, timer: bool = False) -> Manager:
        """Attach the view to ``manager``, then start it (``check`` and ``timer`` as for
        :meth:`Manager.start <cosleec.runtime.Manager.start>`). A start that fails serves
        nothing: the view is closed (its port free again) and the error raised. Returns ``manager``."""
        self.attach(manager)
        try:
            manager.start(check=check, timer=timer)
        except BaseException:
            self.close()
            raise
        return manager

    def close(self) -> None:
        """Stop the view, if one is attached (its port is free again); again, nothing more."""
        view, self.view, self._manager = self.view, None, None
        if view is not None:
            view.close()

    def __enter__(self) -> AttachedView:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()
