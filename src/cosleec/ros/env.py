"""Process environments for ROS nodes: loopback-only settings, own ROS_HOME, a master for ROS 1."""

from __future__ import annotations

import os
import random
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from typing import Any

# variables of the ROS 2 wheels' bootstrap that must not leak into a ROS 1 child (ros-setup.md §2.6)
ROS2_BOOTSTRAP = ("_ROS_WHEELS_BOOTSTRAP_COMPLETE", "LD_LIBRARY_PATH")


def ros2_env(base: dict[str, str] | None = None) -> dict[str, str]:
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
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def ros1_env(port: int, base: dict[str, str] | None = None) -> dict[str, str]:
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
    """A rosmaster on the port of ``env``'s ROS_MASTER_URI, bound to 127.0.0.1; waits until up."""
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
