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

Paths in a launch file are relative to the launch file's directory, not to wherever the
launcher was started: a node's first argument unless it is an option (its rules, or the
listener's or guard's mapping) and the values of the path options (``--audit out.jsonl``, ``--rules``,
``--mapping``, ``--journal``, ``--record``, ``--path``, ``--params-file``, ``--reload-dir``) become absolute
paths there, whether the file exists yet or not (``~`` is expanded; absolute paths stay).
Each node also runs in that directory, so anything else relative -- a ``--module`` next to
the launch file -- behaves the same.
"""

from __future__ import annotations

import contextlib
import ctypes
import difflib
import os
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

#: the node kinds a launch file may start (``cosleec <backend> <kind>``)
KINDS = ("manager", "layers", "listener", "task", "guard")
#: the kinds whose first argument, unless it is an option, is a file: rules, or a mapping
FILE_FIRST = frozenset({"manager", "layers", "listener", "task", "guard"})
#: options whose value is a path, resolved against the launch file's directory
PATH_OPTIONS = frozenset(
    {"--audit", "--journal", "--record", "--rules", "--mapping", "--path", "--params-file", "--reload-dir"}
)


def _die_with_parent() -> None:  # runs in the child, before exec
    with contextlib.suppress(OSError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def node_command(backend: str, args: list[str], namespace: str | None) -> list[str]:
    """The command that runs one node: ``python -m cosleec.cli.main <backend> <kind> args...``.

    It uses this interpreter, so the node runs in the same environment; ``--namespace``
    is added unless ``args`` already give one.
    """
    args = [str(a) for a in args]
    if namespace and "--namespace" not in args:  # before the ROS arguments, which end the options
        at = args.index("--ros-args") if "--ros-args" in args else len(args)
        args = [*args[:at], "--namespace", namespace, *args[at:]]
    return [sys.executable, "-m", "cosleec.cli.main", backend, *args]


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


def resolve(base: Path, value: str) -> str:
    """``value``, a path in a launch file, as an absolute path: ``~`` expanded, then relative to ``base``.

    An absolute path is kept as it is; whether the file exists does not matter (an audit
    log or a journal is created by the node).
    """
    return str(base / Path(value).expanduser())  # base / an absolute path is that path


def node_args(kind: str, args: list[Any], base: Path) -> list[str]:
    """A node's arguments as the command line gets them, paths resolved against ``base``.

    The first argument of a node of :data:`FILE_FIRST` is its file (rules or mapping)
    unless it is an option; the value of every option in :data:`PATH_OPTIONS` is a
    path, in both forms ``--audit out.jsonl`` and ``--audit=out.jsonl``. Nothing else is
    touched: ``--module tasks`` names a module, not a file.
    """
    given = [str(a) for a in args]
    out = list(given)
    for i, a in enumerate(given):
        if a.startswith("-"):  # an option; perhaps with its value: --audit=out.jsonl
            option, eq, value = a.partition("=")
            if eq and option in PATH_OPTIONS:
                out[i] = f"{option}={resolve(base, value)}"
        elif (i == 0 and kind in FILE_FIRST) or (i > 0 and given[i - 1] in PATH_OPTIONS):
            out[i] = resolve(base, a)
    return out


def load(path: str) -> dict[str, Any]:
    """Read and check a launch file: ``{"backend", "namespace", "nodes", "cwd"}``.

    UserError naming the file when ``backend`` or ``nodes`` is wrong, or a node is of a
    kind there is none of (with the kinds, and the one probably meant). Relative paths in
    node arguments are resolved against the launch file's directory (:func:`node_args`),
    which is also ``cwd``, the directory every node runs in.
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
    base = Path(path).expanduser().resolve().parent
    nodes = []
    for i, n in enumerate(doc["nodes"], 1):
        if not isinstance(n, list) or not n:
            raise UserError(f"node {i}: each node is [{'|'.join(KINDS)}, args...], not {n!r}", where=path)
        if n[0] not in KINDS:
            close = difflib.get_close_matches(str(n[0]), KINDS, n=1)
            raise UserError(
                f"node {i}: there is no node kind {n[0]!r}; the kinds are {', '.join(KINDS)}",
                where=path,
                hint=f"did you mean `{close[0]}`?"
                if close
                else f"write [kind, args...] with a kind of {', '.join(KINDS)}",
            )
        bad = [a for a in n[1:] if not isinstance(a, str | int | float)]
        if bad:
            raise UserError(
                f"node {i} ({n[0]}): argument {bad[0]!r} is not a string or a number",
                where=path,
                hint="write each argument as its own list item: [manager, rules.sleec, --audit, out.jsonl]",
            )
        nodes.append([n[0], *node_args(n[0], n[1:], base)])
    return {"backend": doc["backend"], "namespace": doc.get("namespace"), "nodes": nodes, "cwd": str(base)}


def child_env() -> dict[str, str]:
    """This process's environment for a node that runs in another directory: ``PYTHONPATH`` made absolute.

    A relative entry (``PYTHONPATH=src``) meant the launcher's directory; in the node's
    own directory it would no longer find cosleec. An empty entry (the current directory)
    keeps meaning the launcher's.
    """
    env = dict(os.environ)
    if env.get("PYTHONPATH"):
        here = os.getcwd()
        env["PYTHONPATH"] = os.pathsep.join(
            os.path.join(here, p) for p in env["PYTHONPATH"].split(os.pathsep)
        )
    return env


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
    env = child_env()
    procs = [
        start(node_command(cfg["backend"], n, cfg["namespace"]), env, cwd=cfg["cwd"]) for n in cfg["nodes"]
    ]
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
