"""What a behaviour tree needs of the Manager, and the embedded Manager behind it.

The behaviours of :mod:`cosleec.bt` talk to a :class:`Link`: ask whether an event is
permitted now, report an event the robot did, report a trigger and get the decisions it
made, and read what is still owed. :class:`EmbeddedLink` is the in-process
:class:`~cosleec.runtime.Manager`; :class:`cosleec.ros.bt_client.RosLink` is the ROS 2
Manager node over its services and topics. Every behaviour takes either a Link or a
Manager (:func:`link_for` wraps the Manager), so one tree runs embedded in a test and on
the robot.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from cosleec.errors import UserError
from cosleec.runtime import Decision, Manager, Permission


@runtime_checkable
class Link(Protocol):
    """The Manager as a tree sees it: what the behaviours ask and report.

    Implementations fail closed: a Manager that cannot be reached permits nothing
    (:class:`~cosleec.runtime.Permission` with ``permitted=False`` and the reason) and
    decides nothing (:class:`LinkError`, which the rule task turns into FAILURE).
    """

    def request(self, event: str, *, source: str = "") -> Permission:
        """The robot is about to do ``event``: may it, and if not, why not (a refusal is
        counted and recorded by the Manager, with ``source``)."""
        ...

    def permission(self, event: str) -> Permission:
        """Would ``event`` be permitted now: a question (a condition in the tree), not an attempt."""
        ...

    def event(self, name: str) -> object:
        """The robot did ``name``: the Manager records the occurrence and judges obligations."""
        ...

    def decide(self, trigger: str) -> list[Decision]:
        """``trigger`` occurred: the decisions of the rules it triggered (LinkError if none can be had)."""
        ...

    def outstanding(self) -> list[dict[str, Any]]:
        """What the robot still owes: one dict per pending obligation (see :func:`owed`)."""
        ...


class LinkError(UserError):
    """The Manager could not be asked (not reachable, a service turned off): nothing was decided."""


def owed(
    *, id: int, rule: str, event: str, deadline: float | None, decision: int, clause: int | None
) -> dict[str, Any]:
    """One outstanding obligation as the blackboard holds it: plain values, the same on every link.

    ``deadline`` is in the Manager's time (seconds; None: no deadline); ``decision`` the id
    of the decision that created it and ``clause`` its clause (0: the default response).
    """
    return {
        "id": id,
        "rule": rule,
        "event": event,
        "deadline": deadline,
        "decision": decision,
        "clause": clause,
    }


class EmbeddedLink:
    """A :class:`Link` to a Manager in this process: every answer is the Manager's own call.

    The Manager must be started; a tree that implements the rules binds no tasks, so start
    it with ``manager.start(check=False)`` (the completeness check asks for tasks).
    """

    def __init__(self, manager: Manager) -> None:
        self.manager = manager

    def request(self, event: str, *, source: str = "") -> Permission:
        """:meth:`Manager.request <cosleec.runtime.Manager.request>`: a refusal is recorded."""
        return self.manager.request(event, source=source)

    def permission(self, event: str) -> Permission:
        """:meth:`Manager.permission <cosleec.runtime.Manager.permission>`: nothing is recorded."""
        return self.manager.permission(event)

    def event(self, name: str) -> object:
        """:meth:`Manager.event <cosleec.runtime.Manager.event>`: an occurrence, in the audit trail."""
        return self.manager.event(name)

    def decide(self, trigger: str) -> list[Decision]:
        """Report ``trigger`` (:meth:`Manager.event <cosleec.runtime.Manager.event>`) and return its decisions."""
        return self.manager.event(trigger)

    def outstanding(self) -> list[dict[str, Any]]:
        """:meth:`Manager.outstanding <cosleec.runtime.Manager.outstanding>`, as plain dicts."""
        return [
            owed(id=t.id, rule=t.rule, event=t.event, deadline=t.hi, decision=t.decision_id, clause=t.clause)
            for t in self.manager.outstanding()
        ]


def link_for(target: Link | Manager) -> Link:
    """The :class:`Link` for ``target``: a Manager is wrapped in an :class:`EmbeddedLink`.

    TypeError, naming what was given, for anything else (a behaviour built with a wrong
    argument fails when the tree is built, not at its first tick).
    """
    if isinstance(target, Manager):
        return EmbeddedLink(target)
    if isinstance(target, Link):
        return target
    raise TypeError(f"a cosleec behaviour needs a Manager or a cosleec.bt.Link, not {type(target).__name__}")
