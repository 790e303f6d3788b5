"""The package as a user gets it: a wheel and an sdist built by ``python -m build``, and the wheel
installed into a fresh virtual environment outside the repository.

Offline and quick: the build runs without isolation (``build``, ``setuptools`` and ``wheel``
come from the dev extra), and the fresh venv gets the wheel with ``--no-deps`` plus a view
of the dev venv's site-packages that holds only the distributions cosleec *declares*
(``dependencies`` and the ``lsp`` extra, with their own dependencies, resolved from the
installed metadata): a module cosleec imports but does not declare is missing there, as
it would be for a user. Under pytest-xdist the workers share one build and one venv (a
file lock in pytest's common temporary directory).
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import subprocess
import sys
import venv
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[2]
#: the extras whose dependencies the fresh venv sees (cosleec lsp is run there)
EXTRAS = ("lsp",)
PIP_QUIET = ("--no-cache-dir", "--disable-pip-version-check", "-q")


@dataclass(frozen=True)
class Dist:
    """The built distributions."""

    wheel: Path
    sdist: Path


@dataclass(frozen=True)
class Installed:
    """The fresh venv with the wheel installed: its Python, its ``cosleec`` and a clean environment."""

    root: Path
    python: Path
    cosleec: Path
    env: dict[str, str]
    cwd: Path

    def run(self, *args: str | Path, timeout: float = 120, **kw: object) -> subprocess.CompletedProcess[str]:
        """Run a command in the fresh venv's directory (outside the repository), capturing its text."""
        return subprocess.run(
            [str(a) for a in args],
            cwd=self.cwd,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
            **kw,  # type: ignore[call-overload]
        )

    def package_dir(self) -> Path:
        """The directory of the installed ``cosleec`` package, as the fresh venv's Python finds it."""
        p = self.run(self.python, "-c", "import cosleec, os; print(os.path.dirname(cosleec.__file__))")
        assert p.returncode == 0, p.stderr
        return Path(p.stdout.strip())


def _shared(factory: pytest.TempPathFactory, name: str, make: Callable[[Path], None]) -> Path:
    """``make(dir)`` once for every xdist worker of this run; the directory it filled."""
    base = factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's directory, common to the workers
    target = base / name
    with open(base / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = target / ".done"
        if not done.exists():
            shutil.rmtree(target, ignore_errors=True)
            target.mkdir()
            make(target)
            done.write_text("ok")
    return target


def _need(module: str) -> None:
    try:
        __import__(module)
    except ImportError:
        pytest.fail(f"{module} is not installed in the dev venv: bash scripts/setup --dev installs it")


@pytest.fixture(scope="session")
def dist(tmp_path_factory: pytest.TempPathFactory) -> Dist:
    """The sdist and the wheel, built from the repository (the wheel from the sdist, as ``build`` does)."""
    for m in ("build", "twine", "setuptools", "wheel"):
        _need(m)

    def make(out: Path) -> None:
        p = subprocess.run(
            [sys.executable, "-m", "build", "--no-isolation", "--outdir", str(out), str(ROOT)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert p.returncode == 0, f"python -m build failed:\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"

    out = _shared(tmp_path_factory, "dist", make)
    (wheel,) = out.glob("cosleec-*.whl")
    (sdist,) = out.glob("cosleec-*.tar.gz")
    return Dist(wheel, sdist)


def requirement_closure(extras: tuple[str, ...]) -> list[metadata.Distribution]:
    """The installed distributions cosleec needs with ``extras``: its requirements, theirs, and so on."""
    seen: dict[str, metadata.Distribution] = {}
    todo = [(r, extras) for r in metadata.requires("cosleec") or []]
    while todo:
        text, with_extras = todo.pop()
        req = Requirement(text)
        if req.marker and not any(req.marker.evaluate({"extra": e}) for e in ("", *with_extras)):
            continue
        name = canonicalize_name(req.name)
        if name == "cosleec":  # cosleec[x] inside an extra
            todo += [(r, tuple(req.extras)) for r in metadata.requires("cosleec") or []]
            continue
        if name in seen:
            continue
        d = metadata.distribution(name)
        assert d.version in req.specifier or not req.specifier, f"{req}: the dev venv has {d.version}"
        seen[name] = d
        todo += [(r, tuple(req.extras)) for r in d.requires or []]
    return list(seen.values())


def _top_level(d: metadata.Distribution) -> set[str]:
    """The top-level entries (packages, modules, extension files, dist-info) a distribution installed."""
    names = set()
    for f in d.files or []:
        first = f.parts[0]
        if first in ("..", "__pycache__") or first.endswith(".pth"):
            continue
        names.add(first)
    return names


def deps_view(into: Path) -> Path:
    """A directory of links to the dev venv's copies of cosleec's declared dependencies (see the module)."""
    into.mkdir()
    for d in requirement_closure(EXTRAS):
        for name in _top_level(d):
            src = Path(str(d.locate_file(name)))
            if src.exists() and not (into / name).exists():
                (into / name).symlink_to(src, target_is_directory=src.is_dir())
    return into


@pytest.fixture(scope="session")
def installed(dist: Dist, tmp_path_factory: pytest.TempPathFactory) -> Installed:
    """The wheel installed by pip into a new venv in a temporary directory, with the declared dependencies."""

    def make(where: Path) -> None:
        venv.EnvBuilder(with_pip=False).create(where / "venv")
        py = where / "venv" / "bin" / "python"
        pip = [sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index"]
        p = subprocess.run(
            [*pip, *PIP_QUIET, str(dist.wheel)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert p.returncode == 0, f"pip install of the wheel failed:\n{p.stdout}\n{p.stderr}"
        site = Path(
            subprocess.check_output([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"])
            .decode()
            .strip()
        )
        (site / "cosleec_test_deps.pth").write_text(f"{deps_view(where / 'deps')}\n")
        (where / "work").mkdir()

    root = _shared(tmp_path_factory, "installed", make)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV", "COSLEEC"))}
    env["PATH"] = f"{root / 'venv' / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return Installed(root, root / "venv/bin/python", root / "venv/bin/cosleec", env, root / "work")


def lsp_messages(*msgs: dict[str, object]) -> bytes:
    """JSON-RPC messages framed as the Language Server Protocol sends them over stdio."""
    out = b""
    for m in msgs:
        body = json.dumps(m).encode()
        out += f"Content-Length: {len(body)}\r\n\r\n".encode() + body
    return out


def read_lsp(data: bytes) -> Iterator[dict[str, object]]:
    """The messages in an LSP stdio stream (headers, blank line, body)."""
    while data:
        head, _, rest = data.partition(b"\r\n\r\n")
        length = next(
            int(line.split(b":")[1])
            for line in head.split(b"\r\n")
            if line.lower().startswith(b"content-length")
        )
        yield json.loads(rest[:length])
        data = rest[length:]
