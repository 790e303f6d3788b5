"""How the web view tests reach a Manager's live web view, now that the runtime names no view
(issue 29): it is attached from :mod:`cosleec.views.registry` (an
:class:`~cosleec.views.registry.AttachedView`), and found again here by the Manager it serves,
so that the tests say ``web_url(m)`` where they said ``m.web_url``."""

from __future__ import annotations

import weakref
from typing import Any

from cosleec.runtime import Manager
from cosleec.views import AttachedView, View

_ATTACHED: weakref.WeakKeyDictionary[Manager, AttachedView] = weakref.WeakKeyDictionary()


def attach_web(m: Manager, options: Any = 0) -> AttachedView:
    """The web view of ``m`` with ``options``: found now, serving from ``.start(m)`` (what
    ``Manager(web=options)`` was)."""
    _ATTACHED[m] = AttachedView(options)
    return _ATTACHED[m]


def web_view(m: Manager) -> View | None:
    """The view serving ``m``: None before it started and after it closed (``m.view`` was)."""
    attached = _ATTACHED.get(m)
    return None if attached is None else attached.view


def web_url(m: Manager) -> str | None:
    """Where the view of ``m`` serves, or None (``m.web_url`` was)."""
    attached = _ATTACHED.get(m)
    return None if attached is None else attached.url


def close(m: Manager) -> None:
    """Close the view of ``m`` (its port is free again), then ``m`` (``m.close()`` did both)."""
    attached = _ATTACHED.get(m)
    try:
        if attached is not None:
            attached.close()
    finally:
        m.close()
