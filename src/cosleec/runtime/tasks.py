"""Tasks in the paper's style: a task binds to a rule; its ``default`` method implements
the default obligation and each hedge clause gets its own layer-bound implementation.

Write a task when one rule's behaviour reads best as one class; register capabilities
(``Manager.capability``) instead when one action serves many rules. The same task runs in
the embedded Manager and in a ROS task node.

    class CurtainTask(Task):
        rule = "R1"

        def default(self, decision):            # OpenCurtains
            ...

        @hedge(1)                                # R1.1: unless userUndressed
        def refuse(self, decision):
            ...

The runtime composes these into a COP layered method whose variants are dispatched by the
rule's active layer. ``self.event(name)`` tells the runtime an event happened: deadlines
are judged against reports, never against a method returning.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError

Impl = Callable[..., Any]


class Reporter(Protocol):
    """What a task needs of whoever runs it: the embedded Manager or a ROS task node."""

    def event(self, name: str) -> object:
        """The robot did ``name``."""
        ...

    def request(self, name: str) -> object:
        """May the robot do ``name`` now? (True as a condition exactly when it may.)"""
        ...


def hedge(clause: int | str) -> Callable[[Impl], Impl]:
    """Mark a task method as the implementation of a hedge clause: ``1`` or ``"R1.1"``."""

    def mark(fn: Impl) -> Impl:
        fn._cosleec_clause = clause  # type: ignore[attr-defined]
        return fn

    return mark


class Task:
    """Base class of tasks in the paper's style: subclass it to implement one rule.

    Set ``rule`` to the rule's name, implement ``default`` (the default response) and mark
    one method per hedge clause with :func:`hedge`. Bind it with ``Manager.bind`` (or a
    task node's ``bind``), which sets ``manager``. An optional ``fallback(decision)``
    method runs the ``otherwise`` responses no capability handles.
    """

    rule: str = ""
    manager: Reporter | None = None

    def default(self, decision: Decision) -> Any:
        """Implement the rule's default response (clause 0)."""
        raise NotImplementedError

    def clauses(self) -> dict[int, Callable[[Decision], Any]]:
        """clause number -> bound implementation, from the @hedge marks."""
        out: dict[int, Callable[[Decision], Any]] = {}
        by: dict[int, str] = {}
        for name in dir(type(self)):
            fn = getattr(type(self), name, None)
            mark = getattr(fn, "_cosleec_clause", None)
            if mark is None:
                continue
            if isinstance(mark, str):
                head, _, num = mark.rpartition(".")
                if head != self.rule or not num.isdigit():
                    raise BindingError(
                        [f"{type(self).__name__}.{name}: @hedge({mark!r}) is not a clause of {self.rule}"]
                    )
                mark = int(num)
            clause = int(mark)
            if clause in by:  # two implementations of one clause: neither may silently win
                raise BindingError(
                    [f"{type(self).__name__}: clause {clause} is implemented twice ({by[clause]} and {name})"]
                )
            by[clause] = name
            out[clause] = getattr(self, name)
        return out

    def has_default(self) -> bool:
        """Does the subclass implement ``default``?"""
        return type(self).default is not Task.default

    def event(self, name: str) -> None:
        """The robot did ``name`` (a response the rules may be waiting for): tell the Manager.

        Deadlines are judged against these reports, never against a method returning.
        """
        if self.manager is None:
            raise BindingError([f"task {type(self).__name__} is not bound: call manager.bind(task) first"])
        self.manager.event(name)

    def request(self, name: str) -> bool:
        """May the robot do ``name`` now? False while a prohibition forbids it (the refusal is recorded)."""
        if self.manager is None:
            raise BindingError([f"task {type(self).__name__} is not bound: call manager.bind(task) first"])
        return bool(self.manager.request(name))
