"""Launch files: paths relative to the launch file, not to wherever the launcher was started;
each node runs in the launch file's directory; a node kind there is none of is a user error."""

from __future__ import annotations

import importlib
import os
from pathlib import Path
from typing import Any

import pytest

from cosleec.errors import UserError
from cosleec.ros.launch import KINDS, PATH_OPTIONS, child_env, load

# the module: the package's attribute `launch` is the function of that name
launcher = importlib.import_module("cosleec.ros.launch")


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The launch file's directory, ``robot``; the launcher runs from elsewhere (``elsewhere``)."""
    (tmp_path / "robot").mkdir()
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    return tmp_path / "robot"


def nodes(here: Path, *entries: str) -> list[list[str]]:
    f = here / "robot.launch.yaml"
    f.write_text("backend: ros2\nnodes:\n" + "".join(f"  - {e}\n" for e in entries))
    cfg = load(os.path.relpath(f))  # given relative to the launcher's directory, as on a command line
    assert cfg["cwd"] == str(here)
    return list(cfg["nodes"])


def test_a_path_option_is_relative_to_the_launch_file_whether_or_not_it_exists(here: Path) -> None:
    assert not (here / "out.jsonl").exists()
    assert nodes(here, "[manager, rules.sleec, --audit, out.jsonl]") == [
        ["manager", str(here / "rules.sleec"), "--audit", str(here / "out.jsonl")]
    ]


@pytest.mark.parametrize("option", sorted(PATH_OPTIONS))
def test_every_path_option_in_both_forms(here: Path, option: str) -> None:
    [[_, _, a, b, c]] = nodes(here, f"[task, rules.sleec, {option}, logs/x, '{option}=logs/y']")
    assert (a, b, c) == (option, str(here / "logs" / "x"), f"{option}={here / 'logs' / 'y'}")


def test_the_file_of_each_kind_that_takes_one_is_resolved(here: Path) -> None:
    got = nodes(
        here,
        "[manager, rules.sleec]",
        "[layers, ../shared/rules.sleec]",
        "[listener, mapping.yaml, --rules, rules.sleec]",
        "[task, rules.sleec, --path, lib]",
        "[guard, guards.yaml]",
    )
    assert got == [
        ["manager", str(here / "rules.sleec")],
        ["layers", str(here / "../shared/rules.sleec")],
        ["listener", str(here / "mapping.yaml"), "--rules", str(here / "rules.sleec")],
        ["task", str(here / "rules.sleec"), "--path", str(here / "lib")],
        ["guard", str(here / "guards.yaml")],
    ]


def test_an_absolute_path_is_kept_and_home_is_expanded(here: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HOME", "/home/robot")
    [node] = nodes(
        here,
        "[manager, /etc/cosleec/rules.sleec, --journal, /var/lib/j.db, --record, ~/r.mcap, '--audit=~/a.jsonl']",
    )
    assert node == ["manager", "/etc/cosleec/rules.sleec", "--journal", "/var/lib/j.db", "--record", "/home/robot/r.mcap", "--audit=/home/robot/a.jsonl"]  # fmt: skip


def test_a_module_name_and_other_arguments_are_left_alone(here: Path) -> None:
    (here / "tasks.py").write_text("")  # even one of a file next to the launch file: the node runs here
    [node, other] = nodes(
        here,
        "[task, rules.sleec, --module, tasks, --name, tasks.py, --only, 'R1,R2', --request-timeout, 2.5]",
        "[task, rules.sleec, --module, tasks.py, --status-each]",
    )
    assert node[2:] == [
        "--module",
        "tasks",
        "--name",
        "tasks.py",
        "--only",
        "R1,R2",
        "--request-timeout",
        "2.5",
    ]
    assert other[2:] == ["--module", "tasks.py", "--status-each"]


def test_an_option_first_is_not_taken_for_the_file_nor_an_option_for_a_value(here: Path) -> None:
    [node] = nodes(here, "[manager, --sim-time, --audit, --journal, j.db]")
    assert node == ["manager", "--sim-time", "--audit", "--journal", str(here / "j.db")]


def test_a_launch_file_reached_through_a_symlink_is_relative_to_the_real_file(
    here: Path, tmp_path: Path
) -> None:
    (here / "robot.launch.yaml").write_text("backend: ros1\nnodes:\n  - [layers, rules.sleec]\n")
    (tmp_path / "link.yaml").symlink_to(here / "robot.launch.yaml")
    cfg = load(str(tmp_path / "link.yaml"))
    assert cfg["cwd"] == str(here) and cfg["nodes"] == [["layers", str(here / "rules.sleec")]]


@pytest.mark.parametrize(
    ("entry", "message", "hint"),
    [
        ("[managr, rules.sleec]", "node 1: there is no node kind 'managr'; the kinds are manager, layers, listener, task, guard", "did you mean `manager`?"),
        ("[gaurd]", "there is no node kind 'gaurd'", "did you mean `guard`?"),
        ("[robot, x]", "there is no node kind 'robot'", "write [kind, args...] with a kind of manager, layers, listener, task, guard"),
        ("[]", "node 1: each node is [manager|layers|listener|task|guard, args...], not []", ""),
        ("manager", "each node is [", ""),
        ("[manager, rules.sleec, {--audit: x}]", "node 1 (manager): argument {'--audit': 'x'} is not a string or a number", "write each argument as its own list item"),
    ],
)  # fmt: skip
def test_a_bad_node_is_a_user_error_naming_the_file(here: Path, entry: str, message: str, hint: str) -> None:
    f = here / "bad.launch.yaml"
    f.write_text(f"backend: ros2\nnodes:\n  - {entry}\n")
    with pytest.raises(UserError) as info:
        load(str(f))
    assert message in str(info.value) and info.value.where == str(f)
    assert info.value.hint.startswith(hint)


def test_guard_is_a_kind() -> None:
    assert "guard" in KINDS


class FakeProcess:
    returncode = 0

    def poll(self) -> int:
        return 0

    def send_signal(self, sig: int) -> None:
        pass

    def wait(self, timeout: float | None = None) -> int:
        return 0


def test_launch_starts_every_node_in_the_launch_files_directory(
    here: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    f = here / "robot.launch.yaml"
    f.write_text(
        "backend: ros2\nnodes:\n  - [manager, rules.sleec]\n  - [task, rules.sleec, --module, tasks]\n"
    )
    started: list[tuple[list[str], Any, dict[str, Any]]] = []

    def start(cmd: list[str], env: Any = None, **kw: Any) -> FakeProcess:
        started.append((cmd, env, kw))
        return FakeProcess()

    monkeypatch.setattr(launcher, "start", start)
    monkeypatch.setattr(launcher.signal, "signal", lambda *a: None)  # leave pytest's handlers alone
    monkeypatch.setenv("PYTHONPATH", "src")
    assert launcher.launch(os.path.relpath(f)) == 1  # the fake nodes "exited" at once
    assert [kw for _, _, kw in started] == [{"cwd": str(here)}, {"cwd": str(here)}]
    assert [cmd[3:6] for cmd, _, _ in started] == [["ros2", "manager", str(here / "rules.sleec")], ["ros2", "task", str(here / "rules.sleec")]]  # fmt: skip
    assert all(env["PYTHONPATH"] == str(here.parent / "elsewhere" / "src") for _, env, _ in started)


def test_a_relative_pythonpath_keeps_meaning_the_launchers_directory(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(["src", "/opt/ros/lib", ""]))
    assert child_env()["PYTHONPATH"].split(os.pathsep) == [
        str(tmp_path / "src"),
        "/opt/ros/lib",
        f"{tmp_path}{os.sep}",
    ]
    monkeypatch.delenv("PYTHONPATH")
    assert "PYTHONPATH" not in child_env()
