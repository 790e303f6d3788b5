"""``cosleec demo --web``: the scripted day, paced for someone watching the live web view.

The CLI gives the demo the web view's factory (``demo`` sits beside ``views`` and names no
view); :class:`Watch` gives :func:`cosleec.demo.run` its hooks: attach the view to the
Manager before it starts, say where the page is once the Manager started, wait ``pace``
seconds before each step so a watcher sees them one by one, and after the last step keep
serving until Ctrl-C, so the page can be looked at as long as wanted.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Protocol

from cosleec.demo.player import Step
from cosleec.runtime import Manager

#: seconds between two steps of the web demo unless ``--pace`` says otherwise
PACE_S = 1.0


class Served(Protocol):
    """A live view of the demo's Manager, as its caller attached it (a
    :class:`cosleec.views.registry.View`): where it serves, and how to stop it."""

    @property
    def url(self) -> str:
        """Where the page is."""
        ...

    def close(self) -> None:
        """Stop serving (called before the Manager closes)."""
        ...


class Watch:
    """The hooks of a watched demo run; ``say`` prints a line (the page's address, how to stop).

    ``serve(manager)`` attaches the live view (the CLI gives the web view's factory);
    :attr:`view` is the view once attached. ``stop`` ends the serving after the last step
    (Ctrl-C does in the CLI).
    """

    def __init__(self, pace: float, say: Callable[[str], None], serve: Callable[[Manager], Served]) -> None:
        self.pace = pace
        self.say = say
        self.serve = serve
        self.view: Served | None = None
        self.stop = threading.Event()

    def attach(self, manager: Manager) -> Served:
        """``view``: attach the live view to the Manager, before it starts (it hears start's records)."""
        self.view = self.serve(manager)
        return self.view

    @property
    def url(self) -> str | None:
        """Where the page is, once the view is attached."""
        return None if self.view is None else self.view.url

    def started(self, _manager: Manager) -> None:
        """``on_start``: say where the page is."""
        paced = f"  (a step every {self.pace:g} s)" if self.pace > 0 else ""
        self.say(f"live web view: {self.url}{paced}")

    def step(self, _t: float, _step: Step) -> None:
        """``on_step``, after the display: let the watcher see one step at a time."""
        if self.pace > 0:
            time.sleep(self.pace)

    def linger(self, _manager: Manager) -> None:
        """``before_close``: keep serving until Ctrl-C (or :attr:`stop`); Ctrl-C ends it normally."""
        self.say(f"the day is over; the live web view stays at {self.url} -- press Ctrl-C to stop")
        try:
            while not self.stop.wait(0.5):
                pass
        except KeyboardInterrupt:
            self.say("stopped")
