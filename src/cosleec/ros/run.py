"""Run one CO-SLEEC node on ROS 2 or ROS 1 until SIGINT/SIGTERM, then stop it cleanly.

Behind ``cosleec ros2 <node>`` and ``cosleec ros1 <node>``: it picks the transport,
turns a missing middleware into a user error, and keeps the node's heartbeat going.
"""

from __future__ import annotations

import contextlib
import importlib
import logging
import signal
import threading
from typing import Any

from cosleec.errors import UserError

log = logging.getLogger("cosleec.ros")


class MiddlewareMissingError(UserError):
    """The chosen middleware cannot be imported in this Python environment."""


def transport(backend: str, node_name: str) -> Any:
    """A transport for node ``node_name`` on ``backend`` (``"ros2"``; anything else is ROS 1).

    MiddlewareMissingError, with a hint, when rclpy or rospy cannot be imported here; on
    ROS 2, UnsafeNetworkError when discovery could leave this machine.
    """
    if backend == "ros2":
        try:
            from cosleec.ros.ros2 import Ros2Transport
        except ImportError as e:
            raise MiddlewareMissingError(
                f"ROS 2 (rclpy) is not available here: {e}", hint="use .venv-ros2 (bash scripts/setup-ros)"
            ) from None
        return Ros2Transport(node_name)
    try:
        from cosleec.ros.ros1 import Ros1Transport
    except ImportError as e:
        raise MiddlewareMissingError(
            f"ROS 1 (rospy) is not available here: {e}", hint="use .venv-ros1 (bash scripts/setup-ros)"
        ) from None
    return Ros1Transport(node_name)


def load_module(name: str) -> Any:
    """Import the task module given by ``--module``; UserError with a hint if it cannot be imported."""
    try:
        return importlib.import_module(name)
    except ImportError as e:
        raise UserError(
            f"cannot import task module {name!r}: {e}",
            hint="check --module and that the module is on PYTHONPATH",
        ) from None


def serve(backend: str, kind: str, make: Any, node_name: str) -> int:
    """Create the transport and node, then wait for SIGINT/SIGTERM; stop cleanly either way.

    The signal handlers come first, so that a stop requested while the node is still
    starting ends it cleanly (exit 0) instead of killing it half-initialised.

    ``make(transport)`` builds the node. Once it is up, ``ready`` is printed and the
    node's ``status()`` runs every 0.5 s as a heartbeat, so late joiners learn its state.
    Returns 0 after a requested stop. If the middleware stops under the node instead --
    the ROS 2 executor ended, rospy shut down (a node of the same name took over) -- the
    node would be deaf while its heartbeat said it was alive: the error is logged, a last
    status goes out (``executor_alive`` false) if it still can, and it returns 1. Call it
    from the main thread.
    """
    logging.basicConfig(level=logging.INFO, format=f"[{node_name}] %(levelname)s %(message)s")
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    t = transport(backend, node_name)
    node = None
    try:
        try:
            node = make(t)
        except Exception:
            if stop.is_set():
                return 0  # stopped while starting
            raise
        print(f"cosleec {backend} {kind}: ready", flush=True)
        beat = getattr(node, "status", None)
        while not stop.is_set() and t.ok():
            stop.wait(0.5)
            if beat is not None and not stop.is_set():
                beat()  # a heartbeat: late joiners learn the node's state
        if not stop.is_set():
            why = getattr(t, "spin_error", None)
            log.error(
                "the middleware stopped under the %s node%s; exiting",
                kind,
                f" ({type(why).__name__}: {why})" if why is not None else "",
            )
            if beat is not None:
                with contextlib.suppress(Exception):  # tell whoever still listens, if anyone can
                    beat()
                stop.wait(0.5)  # ...and give that last word time to leave before the node goes
            return 1
    finally:
        if node is not None and hasattr(node, "close"):
            node.close()
        t.close()
    return 0
