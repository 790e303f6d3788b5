"""Fixtures for tests against real middleware. The backend comes from COSLEEC_ROS_BACKEND
(ros2 or ros1); tests skip when that backend is not importable in this interpreter.

Network safety (ros-setup.md §1) is enforced, not assumed: ROS 2 tests fail unless the only
network interface is loopback (run them inside `unshare --net` with lo up), and every node
gets ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and a random ROS_DOMAIN_ID; ROS 1 nodes use one
rosmaster on a free 127.0.0.1 port. Every process a test starts is stopped by PID. A test
process holds one middleware node (ROS 1 allows one per process) and every test uses a
namespace of its own.
"""

from __future__ import annotations

import importlib.util
import itertools
import os
import shutil
import socket
from collections.abc import Iterator
from typing import Any

import pytest

BACKEND = os.environ.get("COSLEEC_ROS_BACKEND", "ros2")
_ns = itertools.count(1)


def only_loopback() -> bool:
    return [name for _, name in socket.if_nameindex()] == ["lo"]


@pytest.fixture(scope="session")
def backend() -> str:
    module = "rclpy" if BACKEND == "ros2" else "rospy"
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{module} is not installed in this interpreter (use .venv-{BACKEND})")
    if BACKEND == "ros2" and not only_loopback():
        pytest.fail(
            "ROS 2/DDS tests must run in a private network namespace: "
            "unshare --net -- bash -c 'ip link set lo up && ...' (ros-setup.md §1)"
        )
    return BACKEND


@pytest.fixture(scope="session")
def graph(backend: str) -> Iterator[dict[str, str]]:
    """The environment every node of this session shares (and, for ROS 1, its master)."""
    from cosleec.ros import env as rosenv
    from cosleec.ros.launch import stop

    master = None
    env = rosenv.ros2_env() if backend == "ros2" else rosenv.ros1_env(rosenv.free_port())
    os.environ.update(env)
    if backend == "ros1":
        master = rosenv.start_master(env)
    yield env
    if master is not None:
        stop(master)
    shutil.rmtree(env["ROS_HOME"], ignore_errors=True)


@pytest.fixture(scope="session")
def transport(backend: str, graph: dict[str, str]) -> Iterator[Any]:
    from cosleec.ros.run import transport as make

    t = make(backend, "cosleec_test_driver")
    yield t
    t.close()


@pytest.fixture
def namespace() -> str:
    return f"/cosleec_t{os.getpid()}_{next(_ns)}"


@pytest.fixture
def json_wire(transport: Any) -> Iterator[str]:
    """This test speaks the JSON wire (JSON text in std_msgs/String): malformed payloads can
    only be sent there. Its nodes must be started with ``--wire json`` (``System(wire=...)``)."""
    transport.wire = "json"
    yield "json"
    transport.wire = "typed"
