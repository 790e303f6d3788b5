"""``cosleec ros2 demo`` / ``cosleec ros1 demo``: the assistive-care scenario over real
middleware, with the Manager, the Layer Manager and a task node in separate processes."""

from __future__ import annotations

import json
import os
import sys
from typing import Any

from cosleec.demo.assistive_care import scenario
from cosleec.demo.runner import rules_path
from cosleec.ros import env as rosenv
from cosleec.ros.launch import node_command, start, stop
from cosleec.runtime import RuntimeEvent

TASKS = "cosleec.demo.assistive_care.tasks"


class System:
    """The demo's processes; a context manager that always stops them (by PID)."""

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
        return [p.poll() for p in self.procs]


def transport(backend: str, name: str) -> Any:
    from cosleec.ros.run import transport as make

    return make(backend, name)


def main(backend: str, namespace: str = "/cosleec", as_json: bool = False) -> int:
    from rich.console import Console

    from cosleec.demo.runner import Display
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main(sys.argv[1]))
