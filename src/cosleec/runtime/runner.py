"""The runner: decisions reach their implementations, outside the lock, and what they did is recorded.

Each job the gate lets through (:meth:`Gate.admit <cosleec.runtime.gate.Gate.admit>`) runs
its implementation once -- the task bound to its rule, under the COP composition it was
decided with, or the capability of each event it requires -- on the caller's thread, with
no lock held, so a slow or failing task never blocks a trigger or a request. Each outcome
is then recorded in a step of its own (``task-done``/``task-failed``, with the ``seq`` of
the last record before the start was admitted: what was in force when it started).

An implementation may trigger rules whose implementations trigger rules: ``max_depth``
stops that (a ``task-failed`` record) before Python's stack runs out.
"""

from __future__ import annotations

import functools
import logging
import sys
import threading
from collections.abc import Callable, Iterable
from typing import Any

from cosleec.records import Kind
from cosleec.runtime.core import Core
from cosleec.runtime.decision import Decision
from cosleec.runtime.gate import Gate
from cosleec.runtime.implementations import Ran
from cosleec.runtime.jobs import Job
from cosleec.runtime.model import CompiledRule

log = logging.getLogger("cosleec.runtime")

#: Python stack frames one level of "an implementation triggers a rule" takes (measured: about
#: 12 for a capability; a task's own calls add some), and the frames kept for the caller
FRAMES_PER_LEVEL = 16
_FRAMES_KEPT = 200


def deepest() -> int:
    """The largest ``max_depth`` the interpreter's recursion limit allows: deeper, a trigger
    loop would end in RecursionError instead of the runtime's own ``task-failed`` record."""
    return max(1, (sys.getrecursionlimit() - _FRAMES_KEPT) // FRAMES_PER_LEVEL)


class Runner:
    """Runs admitted jobs' implementations on ``core`` (see the module docstring)."""

    def __init__(self, core: Core, gate: Gate, max_depth: int = 16) -> None:
        self.core = core
        self.gate = gate
        self.max_depth = max_depth
        self.depth = threading.local()  # per thread: how many implementations deep it runs

    def dispatch(self, jobs: list[Job]) -> None:
        """Run each job's implementation (outside the lock), when the runtime dispatches.

        Each is admitted first (:meth:`Gate.admit`), under the lock ``request`` takes: a
        prohibition that took force since the decision stops the actions it forbids.
        """
        if not self.core.dispatch:
            return
        for given in jobs:
            admitted = self.gate.admit(given)
            if admitted is None:
                continue
            job, checked = admitted
            impl = job.implementations if job.implementations is not None else self.core.implementations
            actions = [t.id for t in given.items if not t.prohibition] if self.core.journal else ()
            call: Callable[..., list[Ran]]
            args: tuple[Any, ...]
            if job.composition is not None:
                call, args = impl.dispatch, (job.rule, job.decision, job.composition)
            else:
                call, args = impl.dispatch_fallback, (job.rule, job.decision)
            self.run(job.rule, job.decision, call, checked, actions, args)

    def run(
        self,
        rule: CompiledRule,
        d: Decision,
        run: Callable[..., list[Ran]],
        checked: int = 0,
        actions: Iterable[int] = (),
        args: tuple[Any, ...] = (),
    ) -> None:
        """Run a decision's implementation once, ``run(*args)``, then record each outcome in a
        step of its own.

        ``checked`` is the ``seq`` of the last record before the dispatch was admitted: the
        outcome records carry it, so a reader can tell what was in force when it started.
        ``actions``: the ids of the actions it was handed (they are no longer in flight).
        """
        local = self.depth  # one level deeper, or refused past max_depth
        depth = getattr(local, "n", 0)
        if depth >= self.max_depth:
            ran = self._too_deep(rule, depth)
        else:
            local.n = depth + 1
            try:
                ran = run(*args)
            finally:
                local.n = depth
        self.finished(rule, d, ran, checked, actions)

    def finished(
        self, rule: CompiledRule, d: Decision, ran: list[Ran], checked: int = 0, actions: Iterable[int] = ()
    ) -> None:
        """Count and record what a run of decision ``d``'s implementation did (``ran``): each
        outcome in a step of its own, when records are read (see :meth:`run`)."""
        core = self.core
        for r in ran:
            if not r.ok:
                core.stats.task_failures += 1
        if not core.steps.recording:
            return
        with core.steps.step() as step:
            for r in ran:  # (what the record shows no longer changes: it is made when read)
                step.emit_later(
                    Kind.TASK_DONE if r.ok else Kind.TASK_FAILED,
                    functools.partial(_outcome, rule.name, d.id, d.clause, r, checked),
                )
            if core.journal and core.dispatch:
                self.gate.landed(d.id, actions, step)  # (a decision with actions still held keeps its entry)

    def _too_deep(self, rule: CompiledRule, depth: int) -> list[Ran]:
        """The outcome of an implementation not run: ``depth`` levels of implementations
        triggering rules reached ``max_depth``."""
        ran = [
            Ran(
                "task",
                None,
                f"not run: implementations triggered rules {depth} deep (max_depth={self.max_depth}); "
                f"does an implementation of {rule.name} trigger {rule.trigger} again?",
            )
        ]
        log.error("%s: %s", rule.name, ran[0].error)
        return ran


def _outcome(rule: str, decision: int, clause: int | None, r: Ran, checked: int) -> dict[str, Any]:
    """The data of a ``task-done`` or ``task-failed`` record (see :meth:`Runner.finished`)."""
    return {"rule": rule, "decision": decision, "clause": clause, **r.to_json(), "checked": checked}
