"""``cosleec ros2 demo`` / ``cosleec ros1 demo``: the assistive-care scenario over real
middleware, with the Manager, the Layer Manager and a task node in separate processes.

The end-to-end tests start their systems with :class:`System` too.
"""

from __future__ import annotations

import json
import os
from typing import Any

from cosleec.demo import Display, rules_path, scenario
from cosleec.ros import env as rosenv
from cosleec.ros.launch import node_command, start, stop
from cosleec.runtime import RuntimeEvent

TASKS = "cosleec.demo.assistive_care.tasks"


class System:
    """The demo's processes; a context manager that always stops them (by PID).

    Entering starts a private rosmaster (ROS 1, unless ``env`` is given), then ``nodes``
    (by default the Manager in simulated time, the Layer Manager and a task node running
    ``task_module``). It also copies the node environment into this process's
    ``os.environ``, so a driver created afterwards joins the same graph.
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
    ) -> None:
        self.backend = backend
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
                ["manager", self.rules, "--sim-time", "--status-each", *(manager_args or [])],
                ["layers", self.rules],
                ["task", self.rules, "--module", task_module, "--status-each", *(extra_task_args or [])],
            ]
        )

    def __enter__(self) -> System:
        os.environ.update(self.env)  # this process's driver joins the same graph
        if self.own_master:
            self.master = rosenv.start_master(self.env)
        for n in self.nodes:
            self.procs.append(start(node_command(self.backend, n, self.namespace), env=self.env))
        return self

    def __exit__(self, *exc: object) -> None:
        for p in self.procs:
            stop(p)
        if self.master is not None:
            stop(self.master)

    def codes(self) -> list[int | None]:
        """Each node's exit code, None while it runs."""
        return [p.poll() for p in self.procs]


def transport(backend: str, name: str) -> Any:
    """A transport for this process's driver: :func:`cosleec.ros.run.transport`."""
    from cosleec.ros.run import transport as make

    return make(backend, name)


def main(backend: str, namespace: str = "/cosleec", as_json: bool = False) -> int:
    """Play the scripted day across processes on ``backend`` and show each decision and violation.

    ``as_json`` prints one JSON object per line instead. Returns 0 when every decision
    matches ``scenario.EXPECTED``, 1 otherwise; the processes are stopped either way.
    """
    from rich.console import Console

    from cosleec.ros.driver import Driver

    console = Console(highlight=False)
    with System(backend, namespace) as system:
        t = transport(backend, "cosleec_demo_driver")
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
                for kind, src in (("decision", driver.decisions), ("obligation", driver.violations)):
                    key = "decisions" if kind == "decision" else "violations"
                    for d in src[seen[key] :]:
                        if as_json:
                            print(json.dumps({"kind": kind, **d}))
                        else:
                            display.event(RuntimeEvent(kind, d.get("time", 0.0), d))
                    seen[key] = len(src)

            driver.run(scenario.STEPS, on_step)
            flush()
            ok = scenario.outcomes(driver.decisions) == scenario.EXPECTED
            if not as_json:
                console.print()
                console.print(
                    f"{len(driver.decisions)} decisions over {backend}, {len(driver.violations)} violations; "
                    f"{'every decision as expected' if ok else 'UNEXPECTED decisions'}; "
                    f"processes: {system.codes()}"
                )
            return 0 if ok else 1
        finally:
            t.close()

