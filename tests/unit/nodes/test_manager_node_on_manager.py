"""The Manager node's ``on_manager`` hook: how the CLI attaches the live web view (``--web``)
to each Manager the node builds, since ``nodes`` names no view (issue 29, part 4).

The hook sees each Manager before it starts (a view attached there hears start's records);
what it returns is called before that Manager closes -- when the node closes, when a
lifecycle cleanup and configure replace it -- and at once when its start fails.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

import pytest

from cosleec.errors import UserError
from cosleec.nodes import LocalBus, ManagerNode
from cosleec.runtime import Manager, RuleSet

RS = RuleSet.from_text(
    "def_start event E event A def_end rule_start R1 when E then A within 10 seconds rule_end"
)


class Hook:
    """An ``on_manager`` that logs what it sees: each Manager, the records it hears, its release."""

    def __init__(self) -> None:
        self.log: list[str] = []
        self.managers: list[Manager] = []

    def __call__(self, manager: Manager) -> Callable[[], None]:
        n = len(self.managers)
        self.managers.append(manager)
        self.log.append(f"attached {n}")
        manager.subscribe(lambda ev: self.log.append(f"{n} heard {ev.kind}"))

        def release() -> None:
            closed = manager.core.steps.closed
            self.log.append(f"released {n}" + (" after its Manager closed" if closed else ""))

        return release


def test_the_hook_sees_the_manager_before_it_starts_and_lets_go_before_it_closes(bus: LocalBus) -> None:
    hook = Hook()
    node = ManagerNode(bus.transport(), RS, sim_time=True, on_manager=hook)
    assert hook.managers == [node.manager]
    assert hook.log[:2] == ["attached 0", "0 heard options"]  # start's first record: heard
    node.close()
    assert hook.log[-1] == "released 0"  # its Manager still open then
    assert node.manager.core.steps.closed


def test_a_reset_lets_go_of_the_old_manager_before_it_closes_and_hooks_the_new_one(bus: LocalBus) -> None:
    hook = Hook()
    node = ManagerNode(bus.transport(), RS, sim_time=True, on_manager=hook)
    node.reset(RS)  # a lifecycle cleanup, then configure
    events = [e for e in hook.log if "heard" not in e]
    assert events == ["attached 0", "released 0", "attached 1"]
    assert hook.managers == [hook.managers[0], node.manager] and hook.managers[0] is not node.manager
    node.close()
    assert [e for e in hook.log if "heard" not in e][-1] == "released 1"


def test_a_start_that_fails_lets_go_at_once(bus: LocalBus) -> None:
    hook = Hook()
    with pytest.raises(UserError, match="cannot write the audit log"):
        ManagerNode(bus.transport(), RS, sim_time=True, audit="/dev/full", on_manager=hook)  # a full disk
    assert [e for e in hook.log if "heard" not in e] == ["attached 0", "released 0"]
    with contextlib.suppress(OSError):  # the audit log cannot flush to /dev/full
        hook.managers[0].close()


def test_without_a_hook_the_node_starts_and_closes_as_before(bus: LocalBus) -> None:
    node = ManagerNode(bus.transport(), RS, sim_time=True)
    node.close()
    assert node.manager.core.steps.closed
