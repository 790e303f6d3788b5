"""Behaviours that ask the Manager before the robot acts, and tell it when the robot did.

- :class:`Permitted` -- a condition: SUCCESS when the event is permitted now, FAILURE when
  a prohibition (or a Manager that cannot answer) forbids it; the Manager's reason is its
  ``feedback_message``, so a tree's display says why a branch was not taken. A question
  (:meth:`Manager.permission <cosleec.runtime.Manager.permission>`), asked every tick:
  embedded, it records nothing; put the action itself under :class:`Guarded`.
- :class:`Guarded` -- a decorator: asks before its child starts (FAILURE with the reason
  when refused: the child never runs) and reports the event when the child succeeds.
  That is the "real attempt" path of :meth:`Manager.request <cosleec.runtime.Manager.request>`
  and :meth:`Manager.event <cosleec.runtime.Manager.event>`: a refusal is a ``refused``
  record in the audit log, a success an ``occurrence`` that meets the obligations owed.
- :class:`Obligations` -- writes what the robot still owes to the blackboard under
  :data:`OBLIGATIONS_KEY`, for the branches that choose what to do next.
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
from py_trees.common import Access, Status

from cosleec.bt.link import Link, link_for
from cosleec.runtime import Manager

#: the blackboard key :class:`Obligations` writes: a list of dicts (``id``, ``rule``,
#: ``event``, ``deadline`` in the Manager's seconds or None, ``decision``, ``clause``),
#: soonest deadline first
OBLIGATIONS_KEY = "/cosleec/obligations"


class Permitted(py_trees.behaviour.Behaviour):
    """Is ``event`` permitted now? SUCCESS or FAILURE, the Manager's reason as feedback.

    Asks on every tick (a prohibition can begin or end between two ticks); a refusal is
    recorded by the Manager with this behaviour's name as its ``source``.
    """

    def __init__(self, event: str, manager: Link | Manager, name: str | None = None) -> None:
        super().__init__(name or f"{event}?")
        self.event = event
        self.link = link_for(manager)

    def update(self) -> Status:
        """Ask the Manager; the answer's reason becomes :attr:`feedback_message`."""
        answer = self.link.permission(self.event)
        self.feedback_message = answer.reason
        return Status.SUCCESS if answer.permitted else Status.FAILURE


class Guarded(py_trees.decorators.Decorator):
    """Run ``child`` only if ``event`` is permitted when it starts; report ``event`` when it succeeds.

    The question is asked once per run of the child, before its first tick (a child
    that is RUNNING is not interrupted by a prohibition that begins meanwhile: it was
    permitted when it started, as :meth:`Manager.request` is asked before acting). Refused:
    FAILURE, the reason as :attr:`feedback_message`, and the child is not ticked. The
    child's SUCCESS is reported to the Manager as an occurrence of ``event``; FAILURE
    reports nothing (the robot did not do it).
    """

    def __init__(
        self,
        event: str,
        child: py_trees.behaviour.Behaviour,
        manager: Link | Manager,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name or f"Guard {event}", child=child)
        self.event = event
        self.link = link_for(manager)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        """Ask before a new run of the child (refused: FAILURE, child untouched); else tick it."""
        if self.status != Status.RUNNING:
            answer = self.link.request(self.event, source=self.name)
            self.feedback_message = answer.reason
            if not answer.permitted:
                if self.decorated.status != Status.INVALID:
                    self.decorated.stop(Status.INVALID)
                self.stop(Status.FAILURE)
                yield self
                return
        yield from super().tick()

    def update(self) -> Status:
        """The child's status; its SUCCESS is reported to the Manager first."""
        status = self.decorated.status
        if status == Status.SUCCESS:
            self.link.event(self.event)
            self.feedback_message = f"{self.event} reported"
        return status


class Obligations(py_trees.behaviour.Behaviour):
    """Write the obligations the robot still owes to the blackboard (:data:`OBLIGATIONS_KEY`).

    Always SUCCESS: put it first in the root sequence (or in a parallel) so every tick
    sees what is owed now; an obligation met (its event reported) or missed is gone at
    the next tick. The feedback says how many are owed and the next deadline.
    """

    def __init__(
        self, manager: Link | Manager, name: str = "Obligations", key: str = OBLIGATIONS_KEY
    ) -> None:
        super().__init__(name)
        self.link = link_for(manager)
        self.key = key
        self.board = self.attach_blackboard_client(name=name)
        self.board.register_key(key=key, access=Access.WRITE)

    def update(self) -> Status:
        """Read what is owed and write it, soonest deadline first (no deadline last)."""
        owed = sorted(
            self.link.outstanding(),
            key=lambda o: (o["deadline"] is None, o["deadline"] or 0.0, o["id"]),
        )
        self.board.set(self.key, owed, overwrite=True)
        nxt = next((o for o in owed if o["deadline"] is not None), None)
        self.feedback_message = f"{len(owed)} owed" + (
            f", next {nxt['event']} by {nxt['deadline']:g} s ({nxt['rule']})" if nxt else ""
        )
        return Status.SUCCESS
