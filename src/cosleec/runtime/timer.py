"""The deadline timer: a daemon thread that judges deadlines and stale values as time passes.

``Manager.start(timer=True)`` starts it; without it, the caller ticks (a test with a
VirtualClock). It sleeps until the earliest of: the next deadline, the next value to go
stale, the next conflict-aware cancellation, the next interval a held action waits for --
and at most half a second. A step that adds something due earlier than it sleeps until
pokes it (:meth:`Timer.notify`); a step that does not, does not wake it (on two cores,
waking a thread for nothing costs a trigger as much as publishing its decision).
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable

from cosleec.runtime.core import Core
from cosleec.runtime.enforcer import Enforcer
from cosleec.runtime.gate import Gate
from cosleec.runtime.journal import JournalError

log = logging.getLogger("cosleec.runtime")


class Timer:
    """Runs ``tick`` when something is due (see the module docstring)."""

    def __init__(self, core: Core, enforcer: Enforcer, gate: Gate, tick: Callable[[], object]) -> None:
        self.core = core
        self.enforcer = enforcer
        self.gate = gate
        self.tick = tick
        self.thread: threading.Thread | None = None
        self.wake = threading.Condition()
        # the timer's sleep (under wake): the clock time it wakes by (inf while awake, or when
        # nothing is due), and whether a step asked it to look again before sleeping
        self.due = math.inf
        self._poke = False
        self._stop = threading.Event()
        self._held: Callable[[], object] | None = None  # the strong tick, while the thread runs

    def start(self, tick: Callable[[], object] | None = None) -> None:
        """Start the thread (once). ``tick``, when given, is held strongly until :meth:`stop`:
        a running timer keeps what it judges for (its Manager) alive, as it always has --
        a Manager without a running timer is referred to only weakly (no cycle)."""
        if self.thread is None:
            self._held = tick
            self.thread = threading.Thread(target=self._run, name="cosleec-deadlines", daemon=True)
            self.thread.start()

    def stop(self, wait: float = 5.0) -> None:
        """Stop the thread, waiting up to ``wait`` seconds."""
        self._stop.set()
        with self.wake:
            self.wake.notify_all()
        if self.thread is not None:
            self.thread.join(wait)
        self._held = None

    def due_at(self) -> float | None:
        """(Under the lock, at the end of a step.) The earliest clock time the timer must judge
        at because of what is in force now: the next deadline; -inf (wake it whatever it sleeps
        until) while decisions are held or conflict-aware priorities may cut; None when nothing
        is due and nothing waits."""
        if self.thread is None:
            return None
        if self.gate.held or self.core.aware:
            return -math.inf
        return self.core.tracker.next_deadline()

    def notify(self, due: float | None = -math.inf) -> None:
        """Wake the timer when something is due before the time it sleeps until.

        Safe without the ``wake`` lock: the timer commits to a wake-up time only after reading
        what is in force (under the runtime's lock), so a deadline added since is either seen
        by that reading, or earlier than the committed time and wakes it.
        """
        if self.thread is None or due is None or due >= self.due:
            return
        with self.wake:
            self._poke = True
            self.wake.notify_all()

    def _next(self) -> float | None:
        """(Under the lock.) The earliest time anything is due, if anything is."""
        core = self.core
        nxt = core.tracker.next_deadline()
        exp = core.context.next_expiry()
        cut = self.enforcer.forced()
        opening = self.gate.opening
        times = [t for t in (nxt, exp, cut[0] if cut else None, opening) if t is not None]
        return min(times) if times else None

    def _run(self) -> None:
        while not self._stop.is_set():
            with self.core.steps.lock:
                first = self._next()
            wait = None if first is None else max(0.0, first - self.core.steps.clock.now() + 1e-3)
            with self.wake:
                # a step that changed what is due since the reading above has poked: read again
                if not self._poke and not self._stop.is_set():
                    self.due = math.inf if first is None else first
                    self.wake.wait(timeout=0.5 if wait is None else min(wait, 0.5))
                self._poke = False
                self.due = math.inf  # awake: every step that adds a deadline pokes
            if not self._stop.is_set():
                try:
                    (self._held or self.tick)()
                except JournalError:
                    return  # logged where it happened; the runtime refuses from now on
                except ReferenceError:
                    return  # its Manager is gone (dropped without close): nothing is left to judge
                except Exception:  # a bug must not stop deadlines from being judged
                    log.exception("judging deadlines failed; the timer goes on")
