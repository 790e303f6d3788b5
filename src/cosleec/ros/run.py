"""Run one CO-SLEEC node on ROS 2 or ROS 1 until SIGINT/SIGTERM, then stop it cleanly.

Behind ``cosleec ros2 <node>`` and ``cosleec ros1 <node>``: it picks the transport,
turns a missing middleware into a user error, and keeps the node's heartbeat going.
"""

from __future__ import annotations

import contextlib
import importlib
import logging
import signal
import sys
import threading
from typing import Any

from cosleec.errors import UserError

log = logging.getLogger("cosleec.ros")


class MiddlewareMissingError(UserError):
    """The chosen middleware cannot be imported in this Python environment."""


def transport(
    backend: str,
    node_name: str,
    *,
    wire: str = "typed",
    ros_args: list[str] | None = None,
    lifecycle: bool = False,
) -> Any:
    """A transport for node ``node_name`` on ``backend`` (``"ros2"``; anything else is ROS 1).

    ``wire``: ``typed`` (``cosleec_interfaces``) or ``json``; ``ros_args``: the node's ROS
    arguments (parameters, remappings); ``lifecycle``: a ROS 2 lifecycle node (ROS 1 has
    none: UserError). MiddlewareMissingError, with a hint, when rclpy or rospy cannot be
    imported here; on ROS 2, UnsafeNetworkError when discovery could leave this machine.
    """
    if backend == "ros2":
        try:
            import rclpy  # noqa: F401  -- which import failed decides the hint

            from cosleec.ros.ros2 import Ros2Transport
        except ImportError as e:
            raise MiddlewareMissingError(
                f"ROS 2 (rclpy) is not available in this Python environment ({sys.executable}): {e}",
                hint="run ROS 2 nodes with .venv-ros2/bin/cosleec (set up by `bash scripts/setup-ros`)",
            ) from None
        return Ros2Transport(node_name, wire=wire, ros_args=ros_args, lifecycle=lifecycle)
    if lifecycle:
        raise UserError(
            "ROS 1 has no lifecycle nodes",
            hint="the lifecycle Manager is a ROS 2 node; on ROS 1 the Manager starts enforcing at once",
        )
    try:
        import rospy  # noqa: F401

        from cosleec.ros.ros1 import Ros1Transport
    except ImportError as e:
        raise MiddlewareMissingError(
            f"ROS 1 (rospy) is not available in this Python environment ({sys.executable}): {e}",
            hint="run ROS 1 nodes with .venv-ros1/bin/cosleec (set up by `bash scripts/setup-ros`)",
        ) from None
    return Ros1Transport(node_name, wire=wire, ros_args=ros_args)


def load_module(name: str, path: list[str] | None = None) -> Any:
    """Import the task module of ``--module`` and check it has ``install(node)``; UserError if not.

    ``name`` is a module name (``tasks``, ``mypkg.tasks``) or a Python file (``tasks.py``,
    ``~/robot/tasks.py``; relative to the current directory). A module name is looked up
    in the ``path`` directories (``--path``, in their order), then the current directory,
    then the rest of ``sys.path``. A file is imported from the file itself, as the module
    of its name (``tasks``), with its own directory first. These directories stay at the
    front of ``sys.path``, so that the module's own imports -- at load time, or later from
    a task -- find its neighbours; the node runs nothing else.

    Each failure is a UserError, never a traceback, and says which it is, with its own
    hint: no such module or file; the module was found but failed to import (a syntax
    error in it, an ImportError of one of *its* imports, an exception in its top-level
    code), with the file and line; or it has no callable ``install``.
    """
    import os
    import traceback
    from importlib import util as import_util  # importlib itself: imported at the top
    from pathlib import Path

    here = os.getcwd()
    dirs = [os.path.abspath(os.path.expanduser(d)) for d in path or []]

    def to_front(entries: list[str]) -> None:
        for d in reversed(entries):
            while d in sys.path:
                sys.path.remove(d)
            sys.path.insert(0, d)

    def failed(e: BaseException) -> UserError:
        if isinstance(e, SyntaxError):  # in the module itself, or in a module it imports
            where = f"{e.filename}:{e.lineno}" + (f":{e.offset}" if e.offset else "")
            return UserError(
                f"task module {name!r} was found but cannot be imported: SyntaxError: {e.msg}",
                where=where,
                hint=f"fix the syntax at {where}",
            )
        ours = (__file__, importlib.__file__)  # frames of this loader and importlib's are not the module's
        frames = [
            f
            for f in traceback.extract_tb(e.__traceback__)
            if not f.filename.startswith("<frozen ") and f.filename not in ours
        ]
        where = f"{frames[0].filename}:{frames[0].lineno}" if frames else ""
        if isinstance(e, ImportError):
            return UserError(
                f"task module {name!r} was found, but one of its own imports failed: {type(e).__name__}: {e}",
                where=where,
                hint="install what it imports in this Python environment, add the directory it is in "
                "with --path, or fix the import",
            )
        return UserError(
            f"task module {name!r} was found, but raised {type(e).__name__} while being imported: {e}",
            where=where,
            hint="fix the module's top-level code (tasks and capabilities are bound in install(node))",
        )

    importlib.invalidate_caches()  # a module written since this process started is found too
    if name.endswith(".py") or os.sep in name or "/" in name:
        file = Path(os.path.abspath(os.path.expanduser(name)))
        if not file.is_file():
            raise UserError(
                f"no task module file {name!r} (looked for {file})",
                hint="give the file's path relative to the current directory, or a module name "
                "(found in the current directory and on --path)",
            )
        module_name = file.stem
        module = sys.modules.get(module_name)
        loaded = getattr(module, "__file__", None)
        if module is not None and (loaded is None or Path(loaded).resolve() != file.resolve()):
            raise UserError(
                f"task module file {name!r} would be the module {module_name!r}, "
                f"but a module of that name is already loaded{f' (from {loaded})' if loaded else ''}",
                hint=f"rename {file.name}",
            )
        if module is None:
            spec = import_util.spec_from_file_location(module_name, file)
            if spec is None or spec.loader is None:
                raise UserError(f"{name!r} cannot be loaded as a Python module", hint="give a .py file")
            to_front([str(file.parent), *dirs, here])
            module = import_util.module_from_spec(spec)
            sys.modules[module_name] = module  # as an import does: dataclasses and pickle look it up
            try:
                spec.loader.exec_module(module)
            except (Exception, SystemExit) as e:
                del sys.modules[module_name]
                raise failed(e) from None
    else:
        if not all(part.isidentifier() for part in name.split(".")):
            raise UserError(
                f"task module {name!r} is neither a module name (such as tasks or mypkg.tasks) nor a .py file",
                hint="give a module name, or the path of a .py file",
            )
        to_front([*dirs, here])
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as e:
            if e.name is not None and (name == e.name or name.startswith(e.name + ".")):
                raise UserError(
                    f"no task module {name!r}: {e}",
                    hint=f"looked in {', '.join([*dirs, here])} and on the Python path; "
                    "add the module's directory with --path, or give the file (tasks.py)",
                ) from None
            raise failed(e) from None
        except (Exception, SystemExit) as e:
            raise failed(e) from None
    install = getattr(module, "install", None)
    if not callable(install):
        raise UserError(
            f"task module {name!r} has no install(node) function",
            where=getattr(module, "__file__", None) or "",
            hint="define it at the module's top level: `def install(node: TaskNode) -> None:`, binding "
            "the node's tasks (`node.bind(MyTask())`) and capabilities (`node.capability('Event')(fn)`)"
            + (f"; `install` here is a {type(install).__name__}" if install is not None else ""),
        )
    return module


def serve(
    backend: str,
    kind: str,
    make: Any,
    node_name: str,
    *,
    wire: str = "typed",
    ros_args: list[str] | None = None,
    lifecycle: bool = False,
) -> int:
    """Create the transport and node, then wait for SIGINT/SIGTERM; stop cleanly either way.

    SIGHUP asks the node to reload (the Manager reads its rule file again; see
    :meth:`cosleec.nodes.ManagerNode.reload`); nodes without ``reload`` ignore it.

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
    hup = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    signal.signal(signal.SIGHUP, lambda *_: hup.set())
    t = transport(backend, node_name, wire=wire, ros_args=ros_args, lifecycle=lifecycle)
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
            if hup.is_set():  # a reload asked for by SIGHUP: done here, not in the signal handler
                hup.clear()
                reload = getattr(node, "reload", None)
                if reload is not None:
                    answer = reload(via="signal")  # recorded as such in the audit log
                    log.log(
                        logging.INFO if answer.get("success") else logging.ERROR,
                        "SIGHUP: %s",
                        answer.get("message", ""),
                    )
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
