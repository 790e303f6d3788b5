"""Process environments for ROS nodes: loopback-only settings, own ROS_HOME, a master for ROS 1.

The ROS demo and the end-to-end tests start their nodes with these, so that their traffic
stays on this machine, parallel runs do not meet, and nothing is written to ``~/.ros``.
"""

from __future__ import annotations

import os
import random
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from typing import Any

# variables set by the ROS 2 wheels' bootstrap; they must not leak into a ROS 1 child process
ROS2_BOOTSTRAP = ("_ROS_WHEELS_BOOTSTRAP_COMPLETE", "LD_LIBRARY_PATH")


def ros2_env(base: dict[str, str] | None = None) -> dict[str, str]:
    """A copy of ``base`` (default ``os.environ``) for ROS 2 processes that keeps DDS on this machine.

    Fast DDS, discovery limited to localhost, no static peers; a random domain (1-100)
    unless ROS_DOMAIN_ID is set; ROS_HOME (and its log directory) in a new temporary
    directory unless ROS_HOME is set. ``base`` itself is not changed.
    """
    env = dict(base if base is not None else os.environ)
    env.pop("ROS_STATIC_PEERS", None)
    env["RMW_IMPLEMENTATION"] = "rmw_fastrtps_cpp"
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.setdefault("ROS_DOMAIN_ID", str(random.randint(1, 100)))
    home = env.get("ROS_HOME") or tempfile.mkdtemp(prefix="cosleec-ros2-")
    env["ROS_HOME"] = home
    env["ROS_LOG_DIR"] = os.path.join(home, "log")
    return env


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago, for a private rosmaster.

    Another process may take it before the master binds it.
    """
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def ros1_env(port: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """A copy of ``base`` (default ``os.environ``) for ROS 1 processes of a private master on ``port``.

    Master at 127.0.0.1, ROS_HOSTNAME=localhost, ROS_IP and the ROS 2 bootstrap variables
    removed, ROS_HOME in a new temporary directory unless set. Start the master with
    :func:`start_master`.
    """
    env = {
        k: v
        for k, v in (base if base is not None else os.environ).items()
        if k not in ("ROS_IP", *ROS2_BOOTSTRAP)
    }
    env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
    env["ROS_HOSTNAME"] = "localhost"
    env.setdefault("ROS_HOME", tempfile.mkdtemp(prefix="cosleec-ros1-"))
    return env


def start_master(env: dict[str, str], timeout: float = 15.0) -> subprocess.Popen[Any]:
    """A rosmaster on the port of ``env``'s ROS_MASTER_URI; waits until it answers.

    It listens on loopback only when ``env`` says ROS_HOSTNAME=localhost, as
    :func:`ros1_env` does. RuntimeError (and the process killed) if it does not answer
    within ``timeout`` seconds. Stop it with :func:`cosleec.ros.launch.stop`.
    """
    port = env["ROS_MASTER_URI"].rsplit(":", 1)[1]
    proc = subprocess.Popen(
        ["rosmaster", "--core", "-p", port], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + timeout
    while True:
        try:
            xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"]).getPid("/cosleec_probe")
            return proc
        except OSError:
            if proc.poll() is not None or time.monotonic() > deadline:
                proc.kill()
                proc.wait()
                raise RuntimeError("rosmaster did not start") from None
            time.sleep(0.05)
