"""g++ builds of the C++ users of ``cosleec_interfaces`` in ``tests/ros/cpp`` (one translation
unit per backend), against what ``scripts/build-interfaces`` generated:

- ROS 2: the headers of every package in ``.venv-ros2/include`` (the ros-jazzy-* wheels and
  the rosidl build of cosleec_interfaces) and the wheels' ``rcl``, ``rmw`` and type-support
  libraries. The wheels' ``librcl.so`` also needs the ``*__rosidl_generator_py`` libraries
  (they were built for rclpy), which call into libpython: a program over ``rcl`` links the
  venv Python's libpython too, or fails to load with ``undefined symbol: PyExc_RuntimeError``.
- ROS 1: Debian's roscpp headers and libraries and the gencpp headers in
  ``build/ros1_interfaces/include``.

Everything is written under the caller's temporary directory: nothing is cached.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SOURCES = Path(__file__).resolve().parent / "cpp"
ROS1_INCLUDE = ROOT / "build" / "ros1_interfaces" / "include"
REBUILD = "run 'bash scripts/build-interfaces' (bash scripts/setup-ros installs what it needs)"


def _libpython() -> list[str]:
    """Linker flags for the libpython of this interpreter (the one .venv-ros2 runs)."""
    version = sysconfig.get_config_var("VERSION")
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    candidates = [Path(libdir)]
    if sysconfig.get_config_var("MULTIARCH"):
        candidates.append(Path("/usr/lib") / sysconfig.get_config_var("MULTIARCH"))
    for where in candidates:
        if (where / f"libpython{version}.so").exists():
            return [f"-L{where}", f"-Wl,-rpath,{where}", "-Wl,--no-as-needed", f"-lpython{version}"]
    pytest.fail(
        f"no libpython{version}.so for {sys.executable} in {[str(c) for c in candidates]}: the "
        "wheels' librcl.so needs it; use a Python built with --enable-shared, or on Debian "
        f"apt-get install libpython{version}-dev"
    )


def _ros2_flags() -> tuple[list[str], dict[str, str]]:
    """Compiler and linker flags for a program over rcl and the C++ types, and its env."""
    prefix = Path(sys.prefix)
    header = prefix / "include" / "cosleec_interfaces" / "cosleec_interfaces" / "srv" / "ask_permission.hpp"
    if not header.exists():
        pytest.fail(f"{header} is missing: the C++ headers of cosleec_interfaces are not built; {REBUILD}")
    libpath = os.environ.get("LD_LIBRARY_PATH", "")
    if str(prefix / "lib") not in libpath.split(os.pathsep):
        pytest.fail(f"LD_LIBRARY_PATH lacks {prefix / 'lib'}: run this test with .venv-ros2/bin/python")
    includes = [f"-I{d}" for d in sorted((prefix / "include").iterdir()) if d.is_dir()]
    libs = [
        "rcl",
        "rmw_fastrtps_cpp",
        "rmw",
        "rcutils",
        "rosidl_runtime_c",
        "rosidl_typesupport_cpp",
        "cosleec_interfaces__rosidl_typesupport_cpp",
    ]
    flags = [*includes, f"-L{prefix / 'lib'}", f"-Wl,-rpath-link,{libpath}", *(f"-l{lib}" for lib in libs)]
    return [*flags, *_libpython()], {"LD_LIBRARY_PATH": libpath}


def _ros1_flags() -> tuple[list[str], dict[str, str]]:
    """Compiler and linker flags for a roscpp program with the gencpp headers, and its env."""
    if not (ROS1_INCLUDE / "cosleec_interfaces" / "AskPermission.h").exists():
        pytest.fail(f"the gencpp headers are missing in {ROS1_INCLUDE}; {REBUILD}")
    if not Path("/usr/include/ros/ros.h").exists():
        pytest.fail("Debian's roscpp headers are missing: apt-get install libroscpp-dev (scripts/setup-ros)")
    libs = ["roscpp", "rosconsole", "roscpp_serialization", "rostime", "cpp_common"]
    return [f"-I{ROS1_INCLUDE}", *(f"-l{lib}" for lib in libs)], {}


def build(backend: str, out: Path) -> tuple[Path, dict[str, str], float]:
    """Compile ``cpp/cosleec_<backend>.cpp`` to ``out``; the binary, the environment it runs
    with (on top of the ROS environment) and the seconds g++ took. A compile error fails the
    test with g++'s message."""
    gxx = shutil.which("g++")
    if gxx is None:
        pytest.fail("g++ is missing: apt-get install g++ (scripts/setup-ros installs it)")
    flags, env = _ros2_flags() if backend == "ros2" else _ros1_flags()
    source = SOURCES / f"cosleec_{backend}.cpp"
    cmd = [gxx, "-std=c++17", "-O0", "-Wall", "-Werror", str(source), "-o", str(out), *flags]
    start = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    took = time.monotonic() - start
    if done.returncode != 0:
        errors = "\n".join(line for line in done.stderr.splitlines() if "warning: lib" not in line)
        pytest.fail(f"g++ failed ({done.returncode}) on {source.name}:\n{errors[-4000:]}")
    return out, env, took
