"""``cosleec ros2 setup``: building ``cosleec_interfaces`` from the shipped definitions.

In CI: its pieces on real files (the definitions the package ships, a CMake export as the
``ros-jazzy-*`` wheels ship it) and its refusals. On demand (``COSLEEC_PACKAGE_ROS2=1``,
about 2-3 minutes, needs PyPI or a pip cache with the wheels): the whole story of a wheel
user, in a fresh venv outside the repository: ``pip install 'cosleec[ros2]'`` from the
built wheel, ``cosleec ros2 setup``, the messages imported, and ``cosleec ros2 demo`` in a
private network namespace.
"""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

from cosleec.cli import ros_build as build
from tests.package.conftest import ROOT, Dist

INTERFACES = ROOT / "interfaces" / "cosleec_interfaces"
ON_DEMAND = os.environ.get("COSLEEC_PACKAGE_ROS2") == "1"


def test_the_shipped_definitions_are_the_interface_package() -> None:
    pkg = build.definitions()
    assert (pkg / "package.xml").read_bytes() == (INTERFACES / "package.xml").read_bytes()
    listed = build.interface_files(pkg)
    assert listed == build.interface_files(INTERFACES) and any(f.startswith("srv/") for f in listed)
    cmake = (INTERFACES / "CMakeLists.txt").read_text(encoding="utf-8")
    assert all(f'"{f}"' in cmake for f in listed), "CMakeLists.txt must list every interface file"


def test_the_wheels_cmake_exports_are_repointed_at_this_python(tmp_path: Path) -> None:
    share = tmp_path / "share" / "std_msgs" / "cmake"
    share.mkdir(parents=True)
    exported = (  # as the ros-jazzy-std-msgs wheel ships it
        'INTERFACE_INCLUDE_DIRECTORIES "/opt/python/cp311-cp311/include/python3.11;'
        '/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"\n'
    )
    (share / "export_std_msgs__rosidl_generator_pyExport.cmake").write_text(exported)
    (share / "other.cmake").write_text("set(X 1)\n")
    assert build.repoint_cmake_exports(tmp_path, "/venv/include/python3.11", "/venv/numpy/include") == 1
    assert (share / "export_std_msgs__rosidl_generator_pyExport.cmake").read_text() == (
        'INTERFACE_INCLUDE_DIRECTORIES "/venv/include/python3.11;/venv/numpy/include"\n'
    )
    assert build.repoint_cmake_exports(tmp_path, "/a", "/b") == 0  # done once


def test_the_inputs_digest_changes_with_the_definitions_and_options(tmp_path: Path) -> None:
    pkg = tmp_path / "cosleec_interfaces"
    shutil.copytree(INTERFACES, pkg)
    first = build.inputs_digest(pkg, tmp_path, ["-DCOSLEEC_INTERFACES_CPP=ON"])
    assert first == build.inputs_digest(pkg, tmp_path, ["-DCOSLEEC_INTERFACES_CPP=ON"])
    assert first != build.inputs_digest(pkg, tmp_path, ["-DCOSLEEC_INTERFACES_CPP=OFF"])
    (pkg / "msg" / "Counter.msg").write_text("int64 n\n")
    assert first != build.inputs_digest(pkg, tmp_path, ["-DCOSLEEC_INTERFACES_CPP=ON"])


def test_uninstall_removes_only_what_the_manifest_lists_under_the_prefix(tmp_path: Path) -> None:
    share = tmp_path / "share" / "cosleec_interfaces"
    share.mkdir(parents=True)
    mine, outside, kept = tmp_path / "lib" / "libx.so", tmp_path.parent / "elsewhere.txt", tmp_path / "keep"
    mine.parent.mkdir()
    for f in (mine, outside, kept):
        f.write_text("x")
    (share / build.MANIFEST).write_text(f"{mine}\n{outside}\n")
    (share / build.STAMP).write_text("old\n")
    assert build.uninstall(tmp_path) == 1
    assert not mine.exists() and outside.exists() and kept.exists() and not (share / build.STAMP).exists()
    outside.unlink()


def test_setup_without_the_ros2_wheels_names_the_extra(tmp_path: Path) -> None:
    p = subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", "ros2", "setup", "--prefix", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert f"the ROS 2 wheels and rosidl's build-time wheels are not installed in {tmp_path}" in p.stderr
    assert "hint: pip install 'cosleec[ros2]'" in p.stderr


def test_setup_is_a_ros2_command_only() -> None:
    p = subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", "ros1", "setup"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert p.returncode == 2 and "invalid choice: 'setup'" in p.stderr


def _isolated(*cmd: str | Path) -> list[str]:
    """``cmd`` in a new network namespace with only loopback up (ros-setup.md §1)."""
    unshare = ["unshare", "--net"] if subprocess.run(["unshare", "--net", "true"]).returncode == 0 else None
    unshare = unshare or ["unshare", "--map-root-user", "--net"]
    return [*unshare, "--", "bash", "-c", 'ip link set lo up && exec "$@"', "isolated", *map(str, cmd)]


@pytest.mark.skipif(not ON_DEMAND, reason="on demand: COSLEEC_PACKAGE_ROS2=1 (pip installs the ROS 2 wheels)")
def test_a_wheel_user_installs_the_ros2_extra_builds_the_messages_and_runs_the_demo(
    dist: Dist, tmp_path: Path
) -> None:
    venv.EnvBuilder(with_pip=True).create(tmp_path / "venv")
    bin_ = tmp_path / "venv" / "bin"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV", "_ROS", "LD_"))}
    env["PATH"] = f"{bin_}{os.pathsep}{env['PATH']}"
    p = subprocess.run(
        [bin_ / "pip", "install", "-q", f"{dist.wheel}[ros2]"],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    p = subprocess.run(
        [bin_ / "cosleec", "ros2", "setup"], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr
    assert "installed cosleec_interfaces into" in p.stderr
    p = subprocess.run(
        [bin_ / "cosleec", "ros2", "setup"], env=env, cwd=tmp_path, capture_output=True, text=True
    )
    assert p.returncode == 0 and "is up to date" in p.stderr, p.stderr
    code = "from cosleec_interfaces.msg import Decision; from cosleec_interfaces.srv import AskPermission; Decision()"
    p = subprocess.run([bin_ / "python", "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(random.randint(1, 100)))
    env.update(ROS_HOME=str(tmp_path / "ros"), ROS_LOG_DIR=str(tmp_path / "ros" / "log"))
    p = subprocess.run(
        _isolated(bin_ / "cosleec", "ros2", "demo"),
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    assert "decisions" in p.stdout
