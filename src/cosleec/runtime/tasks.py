"""Task nodes in the paper's style: a task binds to a rule; its ``default`` method implements
the default obligation and each hedge clause gets its own layer-bound implementation.

    class CurtainTask(Task):
        rule = "R1"

        def default(self, decision):            # OpenCurtains
            ...

        @hedge(1)                                # R1.1: unless userUndressed
        def refuse(self, decision):
            ...

The runtime composes these into a COP layered method whose variants are dispatched by the
rule's active layer. ``self.report(event)`` tells the runtime an event happened: deadlines
are judged against reports, never against a method returning.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from cosleec.runtime.decision import Decision
    from cosleec.runtime.manager import Manager

Impl = Callable[..., Any]


def hedge(clause: int | str) -> Callable[[Impl], Impl]:
    """Mark a task method as the implementation of a hedge clause: ``1`` or ``"R1.1"``."""

    def mark(fn: Impl) -> Impl:
        fn._cosleec_clause = clause  # type: ignore[attr-defined]
        return fn

    return mark


class Task:
    """Base class of tasks; set ``rule`` to the rule name the task implements."""

    rule: str = ""
    manager: Manager | None = None

    def default(self, decision: Decision) -> Any:
        raise NotImplementedError

    def clauses(self) -> dict[int, Callable[[Decision], Any]]:
        """clause number -> bound implementation, from the @hedge marks."""
        out: dict[int, Callable[[Decision], Any]] = {}
        for name in dir(type(self)):
            fn = getattr(type(self), name, None)
            mark = getattr(fn, "_cosleec_clause", None)
            if mark is None:
                continue
            if isinstance(mark, str):
                head, _, num = mark.rpartition(".")
                if head != self.rule or not num.isdigit():
                    raise ValueError(
                        f"{type(self).__name__}.{name}: @hedge({mark!r}) is not a clause of {self.rule}"
                    )
                mark = int(num)
            out[int(mark)] = getattr(self, name)
        return out

    def has_default(self) -> bool:
        return type(self).default is not Task.default

    def report(self, event: str) -> None:
        """The robot did ``event`` (a response the rules may be waiting for)."""
        if self.manager is None:
            raise RuntimeError(f"task {type(self).__name__} is not bound to a manager")
        self.manager.event(event)

    def request(self, event: str) -> bool:
        """May the robot do ``event`` now? False while a prohibition forbids it (the refusal is recorded)."""
        if self.manager is None:
            raise RuntimeError(f"task {type(self).__name__} is not bound to a manager")
        return self.manager.request(event)
