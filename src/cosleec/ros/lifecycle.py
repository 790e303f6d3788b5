"""The Manager as a ROS 2 lifecycle (managed) node: configure, activate, deactivate, clean up.

A lifecycle manager (or the Manager itself, with autostart) drives the node through its
transitions. :func:`lifecycle_node` is the rclpy ``LifecycleNode`` whose transitions call
hooks, and refuses -- instead of raising into the executor -- a transition its state has
not; :class:`ManagedManager` gives the hooks that build, start and stop the
:class:`~cosleec.nodes.ManagerNode`. ROS 1 has no lifecycle nodes: its Manager enforces from
its start. rclpy is imported only when the node is made.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable
from typing import Any

from cosleec.errors import UserError
from cosleec.nodes import ManagerNode
from cosleec.runtime import RuleSet

log = logging.getLogger("cosleec.ros")


class ManagedManager:
    """The Manager node as a ROS 2 lifecycle node: configure, activate, deactivate, clean up.

    configure reads and checks the rule file (a broken file fails the transition and
    leaves the node unconfigured) and builds the Manager, inactive; a configure after a
    cleanup starts a new Manager from the file (nothing of the old one's state is kept,
    unless a journal holds it); activate starts enforcing; deactivate and cleanup stop
    it: every request is refused. With ``autostart`` (the default) it
    configures and activates itself at once, as a plain node would start.
    """

    def __init__(self, t: Any, build: Any, rules_path: str, *, autostart: bool = True) -> None:
        self.t = t
        self.build = build
        self.rules_path = rules_path
        self.node: ManagerNode | None = None
        t.managed(
            configure=self.configure,
            activate=self.activate,
            deactivate=self.deactivate,
            cleanup=self.cleanup,
            shutdown=self.shutdown,
        )
        if autostart and not (t.transition("configure") and t.transition("activate")):
            raise UserError("the Manager could not configure and activate itself (see the log above)")

    def configure(self) -> bool:
        """Load and check the rules; build the Manager (inactive), or start it afresh after a cleanup."""
        if self.node is None:
            self.node = self.build(False)
            return True
        try:
            self.node.reset(RuleSet.from_file(self.rules_path))  # a broken file fails the transition
        except UserError as e:
            print(f"cosleec: configure: {e.render()}", file=sys.stderr)
            return False
        return True

    def cleanup(self) -> bool:
        """Stop enforcing; the next configure starts from the rule file afresh."""
        return self.deactivate()

    def activate(self) -> bool:
        """Start enforcing."""
        assert self.node is not None
        self.node.activate()
        return True

    def deactivate(self) -> bool:
        """Stop enforcing: requests refused, events rejected."""
        if self.node is not None:
            self.node.deactivate()
        return True

    def shutdown(self) -> bool:
        """Stop enforcing before the node goes."""
        return self.deactivate()

    def status(self, **extra: Any) -> None:
        """The heartbeat: the Manager's status once configured (nothing before)."""
        if self.node is not None:
            self.node.status(**extra)

    def reload(
        self, path: str | None = None, *, via: str = "call", caller: str | None = None
    ) -> dict[str, Any]:
        """SIGHUP: as :meth:`ManagerNode.reload`, once configured."""
        if self.node is None:
            return {"success": False, "message": "not configured yet: nothing to reload"}
        return self.node.reload(path, via=via, caller=caller)

    def close(self) -> None:
        """Close the Manager, if it was ever configured."""
        if self.node is not None:
            self.node.close()


def lifecycle_node(name: str, args: list[str], hooks: dict[str, Callable[[], bool]]) -> Any:
    """A ``LifecycleNode`` whose transitions call ``hooks`` (filled in later by
    :meth:`~cosleec.ros.ros2.Ros2Transport.managed`: a :class:`ManagedManager` gives them)."""
    from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn

    def hook(which: str) -> Any:
        fn = hooks.get(which)
        if fn is None:
            return TransitionCallbackReturn.SUCCESS
        try:
            ok = fn()
        except Exception as e:
            log.error("lifecycle %s failed: %s: %s", which, type(e).__name__, e)
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS if ok else TransitionCallbackReturn.FAILURE

    class Managed(LifecycleNode):  # type: ignore[misc]
        def on_configure(self, state: Any) -> Any:
            return hook("configure")

        def on_activate(self, state: Any) -> Any:
            return hook("activate")

        def on_deactivate(self, state: Any) -> Any:
            return hook("deactivate")

        def on_cleanup(self, state: Any) -> Any:
            return hook("cleanup")

        def on_shutdown(self, state: Any) -> Any:
            return hook("shutdown")

        # rclpy's change_state service raises into the executor for a transition the current
        # state has not (configure while active): one such request from anyone on the graph
        # would end the node, and with it enforcement. Answered "no" instead.
        def _LifecycleNodeMixin__on_change_state(self, req: Any, resp: Any) -> Any:
            try:
                return LifecycleNode._LifecycleNodeMixin__on_change_state(self, req, resp)
            except Exception as e:
                log.warning(
                    "lifecycle: refused transition %s: %s", req.transition.id or req.transition.label, e
                )
                resp.success = False
                return resp

    return Managed(name, cli_args=args or None)
