"""The Manager as a ROS 2 lifecycle node (:class:`cosleec.ros.ManagedManager`), alone: a fake
transport drives the transitions, a fake Manager node records what it is told. Autostart,
a failed start, configure after a cleanup (and with a broken rule file), and what the
node says before it was ever configured."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from cosleec.errors import UserError
from cosleec.ros import ManagedManager
from cosleec.runtime import RuleSet

RULES = "def_start event E event F def_end rule_start R1 when E then F rule_end\n"


class Transport:
    """The lifecycle half of a ROS 2 transport: hooks set by ``managed``, run by ``transition``."""

    def __init__(self) -> None:
        self.hooks: dict[str, Callable[[], bool]] = {}
        self.transitions: list[str] = []

    def managed(self, **hooks: Callable[[], bool]) -> None:
        self.hooks.update(hooks)

    def transition(self, name: str) -> bool:
        self.transitions.append(name)
        try:
            return self.hooks[name]()
        except Exception:  # as the rclpy lifecycle node: a hook that raises fails the transition
            return False


class Node:
    """A Manager node stand-in: records every call."""

    def __init__(self, active: bool) -> None:
        self.calls: list[Any] = [("built", active)]

    def activate(self) -> None:
        self.calls.append("activate")

    def deactivate(self) -> None:
        self.calls.append("deactivate")

    def reset(self, rules: RuleSet) -> None:
        self.calls.append(("reset", sorted(rules.events)))

    def status(self, **extra: Any) -> None:
        self.calls.append(("status", extra))

    def reload(
        self, path: str | None = None, *, via: str = "call", caller: str | None = None
    ) -> dict[str, Any]:
        self.calls.append(("reload", path, via, caller))
        return {"success": True, "message": "reloaded"}

    def close(self) -> None:
        self.calls.append("close")


class Build:
    """``build(active)``: makes a :class:`Node`, or fails like a broken rule file."""

    def __init__(self, fails: bool = False) -> None:
        self.nodes: list[Node] = []
        self.fails = fails

    def __call__(self, active: bool) -> Node:
        if self.fails:
            raise UserError("rules.sleec:1:1: error: a broken rule file")
        self.nodes.append(Node(active))
        return self.nodes[-1]


@pytest.fixture
def rules(tmp_path: Path) -> Path:
    path = tmp_path / "rules.sleec"
    path.write_text(RULES)
    return path


def test_autostart_configures_an_inactive_manager_then_activates_it(rules: Path) -> None:
    t, build = Transport(), Build()
    ManagedManager(t, build, str(rules))
    assert set(t.hooks) == {"configure", "activate", "deactivate", "cleanup", "shutdown"}
    assert t.transitions == ["configure", "activate"]
    assert [n.calls for n in build.nodes] == [[("built", False), "activate"]]


def test_a_manager_that_cannot_start_itself_is_a_user_error(rules: Path) -> None:
    t = Transport()
    with pytest.raises(UserError) as info:
        ManagedManager(t, Build(fails=True), str(rules))
    assert str(info.value) == "the Manager could not configure and activate itself (see the log above)"
    assert t.transitions == ["configure"]  # a failed configure is not followed by activate


def test_without_autostart_nothing_is_built_until_configured(rules: Path) -> None:
    t, build = Transport(), Build()
    m = ManagedManager(t, build, str(rules), autostart=False)
    assert t.transitions == [] and build.nodes == [] and m.node is None
    assert m.reload() == {"success": False, "message": "not configured yet: nothing to reload"}
    m.status(extra=1)  # no heartbeat before there is a Manager
    m.close()
    assert m.deactivate() and m.cleanup() and m.shutdown()  # nothing to stop: still a success
    assert t.transition("configure") and build.nodes[0].calls == [("built", False)]


def test_configure_after_cleanup_starts_the_same_manager_afresh_from_the_file(rules: Path) -> None:
    t, build = Transport(), Build()
    m = ManagedManager(t, build, str(rules))
    assert t.transition("deactivate") and t.transition("cleanup")
    rules.write_text(RULES.replace("event F", "event F event G"))
    assert t.transition("configure") and t.transition("activate")
    (node,) = build.nodes  # not built again: reset, so that a journal it keeps goes on
    assert node.calls == [
        ("built", False),
        "activate",
        "deactivate",
        "deactivate",
        ("reset", ["E", "F", "G"]),
        "activate",
    ]
    held: Any = m.node
    assert held is node


def test_a_broken_rule_file_fails_configure_and_says_why(
    rules: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    t, build = Transport(), Build()
    ManagedManager(t, build, str(rules))
    t.transition("cleanup")
    rules.write_text("def_start event E def_end rule_start R1 when E then G rule_end\n")
    assert t.transition("configure") is False
    err = capsys.readouterr().err
    assert err.startswith(f"cosleec: configure: {rules}:1:") and err.endswith("\n"), err
    assert not any(isinstance(c, tuple) and c[0] == "reset" for c in build.nodes[0].calls)


def test_heartbeat_reload_and_close_reach_the_configured_manager(rules: Path) -> None:
    t, build = Transport(), Build()
    m = ManagedManager(t, build, str(rules))
    m.status(when=1)
    assert m.reload("other.sleec", via="signal", caller="/op") == {"success": True, "message": "reloaded"}
    m.close()
    assert build.nodes[0].calls[2:] == [
        ("status", {"when": 1}),
        ("reload", "other.sleec", "signal", "/op"),
        "close",
    ]
