"""``cosleec demo --web``: the scripted day, paced for someone watching the live web view.

The demo's Manager serves the web view (``Manager(web=...)``); :class:`Watch` gives
:func:`cosleec.demo.run` its hooks: say where the page is once the Manager started, wait
``pace`` seconds before each step so a watcher sees them one by one, and after the last
step keep serving until Ctrl-C, so the page can be looked at as long as wanted.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from cosleec.demo.player import Step
from cosleec.runtime import Manager

#: seconds between two steps of the web demo unless ``--pace`` says otherwise
PACE_S = 1.0


class Watch:
    """The hooks of a watched demo run; ``say`` prints a line (the page's address, how to stop).

    ``stop`` ends the serving after the last step (Ctrl-C does in the CLI).
    """

    def __init__(self, pace: float, say: Callable[[str], None]) -> None:
        self.pace = pace
        self.say = say
        self.stop = threading.Event()

    def started(self, manager: Manager) -> None:
        """``on_start``: say where the page is."""
        paced = f"  (a step every {self.pace:g} s)" if self.pace > 0 else ""
        self.say(f"live web view: {manager.web_url}{paced}")

    def step(self, _t: float, _step: Step) -> None:
        """``on_step``, after the display: let the watcher see one step at a time."""
        if self.pace > 0:
            time.sleep(self.pace)

    def linger(self, manager: Manager) -> None:
        """``before_close``: keep serving until Ctrl-C (or :attr:`stop`); Ctrl-C ends it normally."""
        self.say(f"the day is over; the live web view stays at {manager.web_url} -- press Ctrl-C to stop")
        try:
            while not self.stop.wait(0.5):
                pass
        except KeyboardInterrupt:
            self.say("stopped")
