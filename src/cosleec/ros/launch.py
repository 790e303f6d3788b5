"""Our own launcher (the PyPI wheels have no ``ros2 launch``): start a set of nodes from one
YAML file, stop them all cleanly on SIGINT/SIGTERM, leave no orphans.

    backend: ros2            # or ros1
    namespace: /cosleec
    nodes:
      - [manager, rules.sleec, --sim-time]
      - [layers, rules.sleec]
      - [task, rules.sleec, --module, cosleec.demo.assistive_care.tasks]

Each node runs as ``cosleec <backend> <kind> ...`` in its own process. Children are told to
die with the launcher (Linux parent-death signal), so even a SIGKILL of the launcher leaves
none behind.
"""

from __future__ import annotations

import contextlib
import ctypes
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import yaml

from cosleec.errors import UserError

PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:  # runs in the child, before exec
    with contextlib.suppress(OSError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def node_command(backend: str, args: list[str], namespace: str | None) -> list[str]:
    """The command that runs one node: ``python -m cosleec.cli.main <backend> <kind> args...``.

    It uses this interpreter, so the node runs in the same environment; ``--namespace``
    is added unless ``args`` already give one.
    """
    cmd = [sys.executable, "-m", "cosleec.cli.main", backend, *[str(a) for a in args]]
    if namespace and "--namespace" not in args:
        cmd += ["--namespace", namespace]
    return cmd


def start(cmd: list[str], env: dict[str, str] | None = None, **kw: Any) -> subprocess.Popen[bytes]:
    """Start ``cmd`` as a child that gets SIGTERM when this process dies (Linux), so none is orphaned.

    ``env`` None inherits this process's environment; ``kw`` goes to :class:`subprocess.Popen`.
    """
    return subprocess.Popen(cmd, env=env, preexec_fn=_die_with_parent, **kw)


def stop(proc: subprocess.Popen[Any], grace: float = 5.0) -> int:
    """Stop exactly this process: SIGTERM, wait up to ``grace`` seconds, then SIGKILL.

    Returns its exit code (negative: the signal that ended it).
    """
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(grace)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return int(proc.returncode)


def load(path: str) -> dict[str, Any]:
    """Read and check a launch file: ``{"backend", "namespace", "nodes"}``.

    UserError naming the file when ``backend`` or ``nodes`` is wrong. A node argument that
    names a file next to the launch file becomes that file's absolute path.
    """
    try:
        doc = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as e:
        raise UserError(
            f"cannot read the launch file: {getattr(e, 'strerror', None) or e}", where=path
        ) from None
    except yaml.YAMLError as e:
        raise UserError(f"the launch file is not valid YAML: {e}", where=path) from None
    if (
        not isinstance(doc, dict)
        or doc.get("backend") not in ("ros1", "ros2")
        or not isinstance(doc.get("nodes"), list)
    ):
        raise UserError("expected `backend: ros1|ros2` and a list `nodes` of [kind, args...]", where=path)
    base = Path(path).resolve().parent
    nodes = []
    for n in doc["nodes"]:
        if not isinstance(n, list) or not n or n[0] not in ("manager", "layers", "listener", "task"):
            raise UserError(f"each node is [manager|layers|listener|task, args...], not {n!r}", where=path)
        # relative file arguments are relative to the launch file
        nodes.append(
            [n[0], *[str(base / a) if isinstance(a, str) and (base / a).exists() else str(a) for a in n[1:]]]
        )
    return {"backend": doc["backend"], "namespace": doc.get("namespace"), "nodes": nodes}


def launch(path: str) -> int:
    """Start the nodes of the launch file ``path`` and supervise them until SIGINT/SIGTERM or a node exits.

    Then every node is stopped. Returns 0 after a clean stop, 1 when a node exited on its
    own or did not stop cleanly. Installs signal handlers, so call it from the main thread.
    """
    cfg = load(path)
    stopping = threading.Event()

    def on_signal(*_: Any) -> None:
        stopping.set()

    for sig in (signal.SIGINT, signal.SIGTERM):  # before any child exists: no window to be killed in
        signal.signal(sig, on_signal)
    procs = [start(node_command(cfg["backend"], n, cfg["namespace"])) for n in cfg["nodes"]]
    failed = False
    while not stopping.is_set():
        for p, n in zip(procs, cfg["nodes"]):
            if p.poll() is not None:
                print(
                    f"cosleec launch: node {n[0]} exited with {p.returncode}; stopping the others",
                    file=sys.stderr,
                )
                failed = True
                stopping.set()
        stopping.wait(0.2)
    codes = [stop(p) for p in procs]
    for p in procs:  # nothing left behind
        assert p.poll() is not None
    time.sleep(0)
    return 1 if failed else (0 if all(c in (0, -signal.SIGTERM) for c in codes) else 1)
