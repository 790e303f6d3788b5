"""``cosleec ros2 setup``, and what ``cosleec ros2|ros1 ...`` says when the middleware is not installed.

A user who installed cosleec with pip has no ``.venv-ros2``: ``pip install 'cosleec[ros2]'``
brings rclpy (the ``ros-jazzy-*`` wheels) and rosidl's build-time wheels, and ``cosleec
ros2 setup`` builds cosleec's messages and services (``cosleec_interfaces``) from the
definitions the package ships into the same environment (:mod:`cosleec.cli.ros_build`). A
node, demo or launch file started where rclpy, rospy or those messages are missing stops
before anything starts, with exit 1 and the command that fixes it.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import yaml

from cosleec.cli.ros_build import EXTRA_HINT, build
from cosleec.errors import UserError

_ROS2_FIX = (
    f"{EXTRA_HINT} (the ROS 2 Jazzy wheels), then `cosleec ros2 setup` (builds cosleec's messages; "
    "docs/install.md); in a clone of the repository, run ROS 2 nodes with .venv-ros2/bin/cosleec "
    "(set up by `bash scripts/setup-ros`)"
)
_ROS1_FIX = (
    "ROS 1 comes from Debian, not from pip: apt-get install python3-rospy python3-rosmaster "
    "python3-std-msgs, and a venv made with --system-site-packages (docs/install.md); in a clone of "
    "the repository, run ROS 1 nodes with .venv-ros1/bin/cosleec (set up by `bash scripts/setup-ros`)"
)


class MiddlewareNotInstalledError(UserError):
    """``cosleec ros2|ros1 ...`` was started in a Python environment without that middleware or cosleec's messages."""


def add_parser(nodes: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``cosleec ros2 setup`` under the ``ros2`` command's sub-commands."""
    s = nodes.add_parser(
        "setup",
        help="build cosleec's ROS 2 messages and services (cosleec_interfaces) into this environment",
        description="Build cosleec_interfaces from the definitions this package ships, with rosidl "
        f"and CMake, into this Python environment. Needs `{EXTRA_HINT}`, cmake, make, a C/C++ "
        "compiler and Python's headers; skipped when the installed build is up to date.",
    )
    s.add_argument(
        "--prefix",
        type=Path,
        default=Path(sys.prefix),
        help="the environment to install into (default: this one, %(default)s)",
    )
    s.add_argument("--no-cpp", action="store_true", help="leave out the C++ headers (rclcpp); faster")
    s.add_argument("--force", action="store_true", help="rebuild even when the installed build is up to date")
    s.set_defaults(run=run_setup, backend="ros2")


def run_setup(args: argparse.Namespace) -> int:
    """Build and install ``cosleec_interfaces``; 0 once it imports, 1 (a UserError) when it cannot be built."""
    n = build(args.prefix, cpp=not args.no_cpp, force=args.force, say=_say)
    if n:
        _say(f"installed cosleec_interfaces into {args.prefix.resolve()} ({n} files)")
    return 0


def _say(line: str) -> None:
    print(f"cosleec ros2 setup: {line}", file=sys.stderr, flush=True)


def require_launch_middleware(path: str) -> None:
    """:func:`require_middleware` for the backend a launch file names, before any of its nodes starts.

    A file that cannot be read, or names no backend, is left to the launcher, which says what is wrong with it.
    """
    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return
    backend = doc.get("backend") if isinstance(doc, dict) else None
    if backend in ("ros1", "ros2"):
        require_middleware(backend, None)


def require_middleware(backend: str, wire: str | None) -> None:
    """MiddlewareNotInstalledError, naming the fix, when ``backend``'s middleware (or, on the typed
    wire, ``cosleec_interfaces``) cannot be found in this Python environment.

    Only looked up, not imported: a middleware that is installed but fails to load is
    reported by the transport, with the import error.
    """
    module, name, fix = ("rclpy", "ROS 2", _ROS2_FIX) if backend == "ros2" else ("rospy", "ROS 1", _ROS1_FIX)
    if importlib.util.find_spec(module) is None:
        raise MiddlewareNotInstalledError(
            f"{name} ({module}) is not available in this Python environment ({sys.executable})", hint=fix
        )
    if wire == "typed" and importlib.util.find_spec("cosleec_interfaces") is None:
        raise MiddlewareNotInstalledError(
            f"cosleec's {name} messages (cosleec_interfaces) are not built in this Python environment "
            f"({sys.executable})",
            hint="`cosleec ros2 setup` builds them here from the definitions cosleec ships; or give "
            "`--wire json` (JSON text in std_msgs/String)"
            if backend == "ros2"
            else "in a clone of the repository, `bash scripts/setup-ros` builds them with genpy; or give "
            "`--wire json` (JSON text in std_msgs/String)",
        )
