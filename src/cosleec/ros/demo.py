"""``cosleec ros2 demo`` / ``cosleec ros1 demo``: the assistive-care scenario over real
middleware, with the Manager, the Layer Manager and a task node in separate processes.

The run must have the outcome of the embedded demo: the Manager keeps an audit log, and
its normalised stream (:func:`cosleec.demo.outcomes`) must equal the embedded run's,
record by record. The end-to-end tests start their systems with :class:`System` too.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from typing import Any

from cosleec.demo import Display, expected, first_difference, outcomes, rules_path, scenario, summary
from cosleec.records import Kind
from cosleec.ros import env as rosenv
from cosleec.ros.launch import node_command, start, stop
from cosleec.runtime import RuntimeEvent, read_audit

TASKS = "cosleec.demo.assistive_care.tasks"


class System:
    """The demo's processes; a context manager that always stops them (by PID).

    Entering starts a private rosmaster (ROS 1, unless ``env`` is given), then ``nodes``
    (by default the Manager in simulated time, the Layer Manager and a task node running
    ``task_module``). It also copies the node environment into this process's
    ``os.environ``, so a driver created afterwards joins the same graph. ``audit`` gives
    that default Manager an audit log, which :meth:`records` reads: the run's outcome.
    """

    def __init__(
        self,
        backend: str,
        namespace: str = "/cosleec",
        extra_task_args: list[str] | None = None,
        task_module: str = TASKS,
        manager_args: list[str] | None = None,
        env: dict[str, str] | None = None,
        rules: str | None = None,
        nodes: list[list[str]] | None = None,
        audit: str | None = None,
        wire: str = "typed",
    ) -> None:
        if audit is not None and nodes is not None:
            raise ValueError("audit= is for the default nodes: give your Manager --audit yourself")
        self.backend = backend
        self.audit = audit
        self.wire = wire
        self.namespace = namespace
        self.procs: list[Any] = []
        self.master: Any = None
        self.own_master = env is None and backend == "ros1"
        if env is not None:
            self.env = dict(env)
        elif backend == "ros2":
            self.env = rosenv.ros2_env()
        else:
            self.env = rosenv.ros1_env(rosenv.free_port())
        self.rules = rules or rules_path()
        self.nodes = (
            nodes
            if nodes is not None
            else [
                [
                    "manager",
                    self.rules,
                    "--sim-time",
                    "--status-each",
                    *(["--audit", audit] if audit is not None else []),
                    *(manager_args or []),
                ],
                ["layers", self.rules],
                ["task", self.rules, "--module", task_module, "--status-each", *(extra_task_args or [])],
            ]
        )

    def __enter__(self) -> System:
        os.environ.update(self.env)  # this process's driver joins the same graph
        if self.own_master:
            self.master = rosenv.start_master(self.env)
        for n in self.nodes:
            args = n if self.wire == "typed" or "--wire" in n else [*n, "--wire", self.wire]
            self.procs.append(start(node_command(self.backend, args, self.namespace), env=self.env))
        return self

    def __exit__(self, *exc: object) -> None:
        for p in self.procs:
            stop(p)
        if self.master is not None:
            stop(self.master)

    def codes(self) -> list[int | None]:
        """Each node's exit code, None while it runs."""
        return [p.poll() for p in self.procs]

    def records(self) -> list[dict[str, Any]]:
        """The records of the Manager's audit log (``audit``), for :func:`cosleec.demo.outcomes`.

        Read them once the driver found the system quiet, or after the processes stopped;
        ValueError when the System has no audit log.
        """
        if self.audit is None:
            raise ValueError("this System has no audit log: give it audit=PATH")
        return read_audit(self.audit)


def transport(backend: str, name: str, wire: str = "typed") -> Any:
    """A transport for this process's driver: :func:`cosleec.ros.run.transport`."""
    from cosleec.ros.run import transport as make

    return make(backend, name, wire=wire)


def main(backend: str, namespace: str = "/cosleec", as_json: bool = False, wire: str = "typed") -> int:
    """Play the scripted day across processes on ``backend`` and show each decision and violation.

    ``as_json`` prints one JSON object per line instead. Then it checks the outcome, not
    only the decisions: the Manager's audit log, normalised, must equal the embedded run of
    the same scenario record by record (:func:`cosleec.demo.expected`). Returns 0 when it
    does and every decision matches ``scenario.EXPECTED``; otherwise prints the first
    difference on stderr and returns 1. The processes are stopped either way.
    """
    from rich.console import Console

    from cosleec.ros.driver import Driver

    console = Console(highlight=False)
    with tempfile.TemporaryDirectory(prefix="cosleec-demo-") as tmp:
        with System(backend, namespace, audit=os.path.join(tmp, "audit.jsonl"), wire=wire) as system:
            t = transport(backend, "cosleec_demo_driver", wire)
            try:
                driver = Driver(t, namespace)
                driver.ready()
                display = Display(console)
                seen = {"decisions": 0, "violations": 0}

                def on_step(now: float, step: Any) -> None:
                    flush()
                    if not as_json:
                        display.step(now, step)

                def flush() -> None:
                    for kind, src in (
                        (Kind.DECISION, driver.decisions),
                        (Kind.OBLIGATION, driver.violations),
                    ):
                        key = "decisions" if kind == Kind.DECISION else "violations"
                        for d in src[seen[key] :]:
                            if as_json:
                                print(json.dumps({"kind": kind, **d}))
                            else:
                                display.event(RuntimeEvent(kind, d.get("time", 0.0), d))
                        seen[key] = len(src)

                driver.run(scenario.STEPS, on_step)
                flush()
                codes = system.codes()
            finally:
                t.close()
        got = outcomes(system.records())  # read once every process stopped: nothing is still written
    want = expected(scenario.STEPS)
    difference = first_difference(want, got)
    decisions_ok = scenario.outcomes(driver.decisions) == scenario.EXPECTED
    ok = decisions_ok and difference is None
    if not as_json:
        s, e = summary(got), summary(want)
        console.print()
        console.print(
            f"{s['decisions']} decisions over {backend}, {s['violations']} violations, {s['refused']} refused actions "
            f"(embedded: {e['decisions']}, {e['violations']}, {e['refused']}); "
            + (
                f"outcomes identical to the embedded run, {len(got)} records"
                if ok
                else "UNEXPECTED " + ("outcomes" if difference else "decisions")
            )
            + f"; processes: {codes}"
        )
    if difference is not None:
        print(
            f"cosleec {backend} demo: the outcome differs from the embedded run: {difference}",
            file=sys.stderr,
        )
    return 0 if ok else 1
