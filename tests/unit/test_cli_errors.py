"""Clear errors everywhere: every user mistake in every command is one paragraph naming the
thing and the fix (``file:line:col`` where known), exit 1 (2 for usage, and for the input
errors of ``decide``, ``analyse`` and ``conforms``, as their contracts say), never a
traceback; ``internal error`` (exit 70) only for a bug of ours.

A few representative cases run the installed ``cosleec`` in a subprocess; the rest call
:func:`cosleec.cli.main.main`. No case starts any middleware: those that would are refused
first, and ``cosleec.ros.serve`` is replaced by a trap that fails the test if reached.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import types
from importlib import metadata
from pathlib import Path
from typing import Any

import pytest

import cosleec.cli.ros as cli_ros
from cosleec import ros
from cosleec.cli import check
from cosleec.cli.main import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
COSLEEC = str(Path(sys.executable).parent / "cosleec")
GOOD = (
    "def_start event E event F measure a : boolean measure n : numeric measure s : scale(low, mid, high) "
    "def_end rule_start R1 when E then F unless a rule_end\n"
)
BAD = "def_start event E def_end rule_start R1 when E then G rule_end\n"
BINARY = b"\x00\x01\xff\xfe"


@pytest.fixture
def d(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A working directory with a good and a bad rule file, a binary file and a directory."""
    (tmp_path / "good.sleec").write_text(GOOD)
    (tmp_path / "bad.sleec").write_text(BAD)
    (tmp_path / "bin.sleec").write_bytes(BINARY)
    (tmp_path / "bin.yaml").write_bytes(b"measures:\n  a: {topic: /a\xff}\n")
    (tmp_path / "adir").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture(autouse=True)
def no_middleware(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail any test that would reach the middleware: every mistake must be said before it."""

    def trap(*_: Any, **__: Any) -> int:
        raise AssertionError("the middleware would have started")

    monkeypatch.setattr(ros, "serve", trap)


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    rc = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err, err
    return rc, err


# ---------------------------------------------------------------- through the real executable


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([COSLEEC, *args], cwd=cwd, capture_output=True, text=True, timeout=120)


def test_subprocess_a_rule_error_in_a_node_is_said_at_its_place_before_any_middleware(d: Path) -> None:
    p = cli("ros2", "manager", "bad.sleec", cwd=d)
    assert p.returncode == 1, p.stderr
    assert "bad.sleec:1:53: error: response `G` is not declared as an event" in p.stderr
    assert "internal error" not in p.stderr and "Traceback" not in p.stderr


@pytest.mark.skipif(importlib.util.find_spec("rclpy") is not None, reason="this environment has rclpy")
def test_subprocess_the_wrong_environment_is_a_user_error(d: Path) -> None:
    p = cli("ros2", "manager", "good.sleec", cwd=d)
    assert p.returncode == 1
    assert "ROS 2 (rclpy) is not available in this Python environment" in p.stderr
    assert "pip install 'cosleec[ros2]'" in p.stderr and "cosleec ros2 setup" in p.stderr
    assert "Traceback" not in p.stderr


def test_subprocess_version() -> None:
    p = subprocess.run([COSLEEC, "--version"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and p.stdout.strip() == f"cosleec {metadata.version('cosleec')}"


def test_subprocess_demo_audit_in_a_missing_directory_creates_nothing(tmp_path: Path) -> None:
    target = tmp_path / "missing" / "deeper" / "a.jsonl"
    p = cli("demo", "--audit", str(target), cwd=tmp_path)
    assert p.returncode == 1 and p.stdout == ""  # refused before the demo prints anything
    assert f"{target}: cannot open the audit log: the directory {target.parent} does not exist" in p.stderr
    assert "mkdir -p" in p.stderr and not (tmp_path / "missing").exists()


def test_subprocess_a_misspelt_command_is_a_usage_error_with_a_suggestion(tmp_path: Path) -> None:
    p = cli("chekc", "x.sleec", cwd=tmp_path)
    assert (
        p.returncode == 2 and "invalid choice: 'chekc'" in p.stderr and "(did you mean 'check'?)" in p.stderr
    )


# ---------------------------------------------------------------- the cases of the issue


def test_ros_node_with_a_missing_rule_file(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = run(["ros2", "layers", "nope.sleec"], capsys)
    assert rc == 1 and "nope.sleec: error: cannot read file: No such file or directory" in err


def fake_std_msgs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make this environment look like one with the middleware and std_msgs (nothing is started)."""
    real = importlib.util.find_spec
    monkeypatch.setattr(
        cli_ros.importlib.util,
        "find_spec",
        lambda name, *a: types.SimpleNamespace() if name in ("rclpy", "rospy") else real(name, *a),
    )
    pkg, msg = types.ModuleType("std_msgs"), types.ModuleType("std_msgs.msg")
    msg.Bool = type("Bool", (), {})  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "std_msgs", pkg)
    monkeypatch.setitem(sys.modules, "std_msgs.msg", msg)


@pytest.mark.parametrize(
    ("type_name", "message"),
    [
        ("std_msgs/Int23", "measures.a: no message type 'std_msgs/Int23' in package 'std_msgs'"),
        ("nopkg_cosleec_xyz/Foo", "measures.a: message package 'nopkg_cosleec_xyz' is not installed here"),
    ],
)
@pytest.mark.parametrize("backend", ["ros2", "ros1"])
def test_a_mapping_with_an_unknown_message_type_is_refused_before_the_middleware(
    d: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    type_name: str,
    message: str,
    backend: str,
) -> None:
    fake_std_msgs(monkeypatch)
    (d / "map.yaml").write_text(f"measures:\n  a: {{topic: /a, type: {type_name}}}\n")
    rc, err = run([backend, "listener", "map.yaml", "--rules", "good.sleec"], capsys)
    assert rc == 1 and err.startswith(f"cosleec: map.yaml:2:3: {message}") and "hint:" in err


def test_a_guard_with_an_unknown_message_type_is_refused_before_the_middleware(
    d: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    fake_std_msgs(monkeypatch)
    argv = ["ros2", "guard", "--from", "/a", "--to", "/b", "--type", "std_msgs/Int23", "--event", "E"]
    rc, err = run(argv, capsys)
    assert rc == 1 and "--type: the guard of /a: no message type 'std_msgs/Int23'" in err
    (d / "guards.yaml").write_text("guards:\n  /a: {to: /b, type: std_msgs/Int23, event: E}\n")
    rc, err = run(["ros2", "guard", "guards.yaml"], capsys)
    assert rc == 1 and "guards.yaml: guards./a: no message type 'std_msgs/Int23'" in err


def test_a_task_module_without_install_is_refused_before_the_middleware(
    d: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(["ros2", "task", "good.sleec", "--module", "json"], capsys)
    assert rc == 1 and "task module 'json' has no install(node) function" in err and "hint: define it" in err
    rc, err = run(["ros2", "task", "good.sleec", "--module", "no_such_module_cosleec"], capsys)
    assert rc == 1 and "no task module 'no_such_module_cosleec'" in err


def test_a_missing_launch_file(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = run(["ros2", "launch", "nope.yaml"], capsys)
    assert rc == 1 and "cosleec: nope.yaml: cannot read the launch file: No such file or directory" in err


def test_the_manager_node_creates_no_directory_for_its_files(
    d: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for option in ("--audit", "--journal", "--record"):
        rc, err = run(["ros2", "manager", "good.sleec", option, "missing/x"], capsys)
        assert rc == 1 and "the directory missing does not exist" in err and f"give {option} a path" in err
        rc, err = run(["ros2", "manager", "good.sleec", option, "adir"], capsys)
        assert rc == 1 and f"{option} names a directory" in err
    assert not (d / "missing").exists()


def test_the_manager_node_resets_a_journal_only_when_given_one(
    d: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(["ros2", "manager", "good.sleec", "--reset-journal"], capsys)
    assert rc == 1 and "--reset-journal needs --journal" in err


# ---------------------------------------------------------------- demo --audit / --journal


def test_demo_audit_refuses_a_missing_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = run(["demo", "--audit", "/proc/nope/a.jsonl"], capsys)
    assert rc == 1 and "cannot open the audit log: the directory /proc/nope does not exist" in err
    rc, err = run(["demo", "--journal", str(tmp_path / "missing" / "j.db")], capsys)
    assert rc == 1 and "cannot open the journal: the directory" in err and not (tmp_path / "missing").exists()
    (tmp_path / "file.txt").write_text("")
    rc, err = run(["demo", "--audit", str(tmp_path / "file.txt" / "a.jsonl")], capsys)
    assert rc == 1 and "file.txt is a file, not a directory" in err


def test_demo_refuses_a_damaged_journal_and_reset_journal_starts_afresh(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    journal, log = tmp_path / "state.db", tmp_path / "a.jsonl"
    assert main(["demo", "--json", "--journal", str(journal), "--audit", str(log)]) == 0
    capsys.readouterr()
    journal.write_bytes(b"")  # the database truncated to 0 bytes beside a journaled audit trail
    rc, err = run(["demo", "--json", "--journal", str(journal), "--audit", str(log), "--append"], capsys)
    assert rc == 1 and str(journal) in err and "--reset-journal" in err
    rc = main(
        ["demo", "--json", "--journal", str(journal), "--audit", str(log), "--append", "--reset-journal"]
    )
    assert rc == 0 and '"kind":"journal-reset"' in log.read_text()
    rc, err = run(["demo", "--reset-journal"], capsys)
    assert rc == 1 and "--reset-journal needs --journal" in err


def test_demo_audit_refuses_to_mix_two_runs_unless_append(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "a.jsonl"
    assert main(["demo", "--json", "--audit", str(log)]) == 0
    first = log.read_text().count("\n")
    capsys.readouterr()
    rc, err = run(["demo", "--json", "--audit", str(log)], capsys)
    assert rc == 1 and "the file exists, and an audit trail must not mix two runs" in err
    assert "remove it, give --audit a new file name, or add --append" in err
    assert log.read_text().count("\n") == first  # untouched
    assert main(["demo", "--json", "--audit", str(log), "--append"]) == 0
    assert log.read_text().count("\n") == 2 * first
    capsys.readouterr()
    rc, err = run(["demo", "--append"], capsys)
    assert rc == 1 and "--append needs --audit FILE" in err
    rc, err = run(["demo", "--audit", str(tmp_path)], capsys)
    assert rc == 1 and "--audit names a directory" in err


# ---------------------------------------------------------------- every command's input files


RULE_COMMANDS = [
    ["check"],
    ["fmt"],
    ["decide", "--event", "E", "--"],
    ["analyse"],
    ["ros2", "manager"],
    ["ros2", "layers"],
    ["ros2", "task", "--module", "json"],
    ["ros1", "manager"],
]


@pytest.mark.parametrize("command", RULE_COMMANDS, ids=lambda c: " ".join(c[:2]))
@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("nope.sleec", "nope.sleec: error: cannot read file: No such file or directory"),
        ("bin.sleec", "bin.sleec:1:3: error: file is not UTF-8 text"),
    ],
)
def test_a_rule_file_that_cannot_be_read(
    d: Path, capsys: pytest.CaptureFixture[str], command: list[str], name: str, message: str
) -> None:
    rc = main([*command, name])
    captured = capsys.readouterr()
    said = captured.out + captured.err
    assert rc == (2 if command[0] == "analyse" else 1), said
    assert message in said and "internal error" not in said and "Traceback" not in said


@pytest.mark.parametrize("command", [["fmt"], ["decide", "--event", "E", "--"], ["ros2", "layers"]])
def test_a_directory_given_for_a_rule_file(
    d: Path, capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    rc, err = run([*command, "adir"], capsys)
    assert rc == 1 and "adir: error: cannot read file: Is a directory" in err


@pytest.mark.parametrize("command", [["check"], ["analyse"]])
def test_a_directory_without_rule_files(
    d: Path, capsys: pytest.CaptureFixture[str], command: list[str]
) -> None:
    rc, err = run([*command, "adir"], capsys)
    assert rc == 1 and "adir: no .sleec file in this directory" in err


@pytest.mark.parametrize(
    ("argv", "rc", "message"),
    [
        (
            ["ros2", "listener", "nope.yaml"],
            1,
            "nope.yaml: cannot read the mapping: No such file or directory",
        ),
        (["ros2", "listener", "adir"], 1, "adir: cannot read the mapping: it is a directory"),
        (["ros2", "listener", "bin.yaml"], 1, "bin.yaml:2:16: cannot read the mapping: it is not UTF-8 text"),
        (["ros1", "guard", "nope.yaml"], 1, "nope.yaml: cannot read the mapping: No such file or directory"),
        (["ros2", "guard", "bin.yaml"], 1, "bin.yaml:2:16: cannot read the mapping: it is not UTF-8 text"),
        (["ros2", "launch", "adir"], 1, "adir: cannot read the launch file: it is a directory"),
        (
            ["ros2", "launch", "bin.yaml"],
            1,
            "bin.yaml:2:16: cannot read the launch file: it is not UTF-8 text",
        ),
        (
            ["analyse", "good.sleec", "--mapping", "nope.yaml"],
            2,
            "nope.yaml: cannot read the mapping: No such",
        ),
        (["analyse", "good.sleec", "--mapping", "bin.yaml"], 2, "bin.yaml:2:16: cannot read the mapping"),
        (["analyse", "good.sleec", "--tasks", "nope.py"], 2, "cannot import the task module 'nope.py'"),
        (["analyse", "good.sleec", "--sarif", "missing/x.sarif"], 2, "cannot write the SARIF file"),
        (["analyse", "good.sleec", "--witnesses", "good.sleec"], 2, "cannot write the witnesses"),
        (["conforms", "good.sleec", "nope.jsonl"], 2, "nope.jsonl: cannot read the trace: No such file"),
        (["conforms", "good.sleec", "adir"], 2, "adir: cannot read the trace: Is a directory"),
        (["conforms", "good.sleec", "bin.sleec"], 2, "bin.sleec:1: the trace is not UTF-8 text"),
        (["conforms", "nope.sleec", "bin.sleec"], 2, "nope.sleec: error: cannot read file"),
    ],
)
def test_other_input_and_output_files(
    d: Path, capsys: pytest.CaptureFixture[str], argv: list[str], rc: int, message: str
) -> None:
    got, err = run(argv, capsys)
    assert got == rc and message in err, err


def test_conforms_with_a_bad_trace_says_where(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (d / "t.jsonl").write_text('{"t": 0, "event": "E"}\nnot json\n')
    rc, err = run(["conforms", "good.sleec", "t.jsonl"], capsys)
    assert rc == 2 and "t.jsonl:2:1: not valid JSON" in err and "hint: each line is one JSON object" in err
    (d / "t.jsonl").write_text('{"t": 0, "event": "Ee"}\n')
    rc, err = run(["conforms", "good.sleec", "t.jsonl"], capsys)
    assert rc == 2 and "t.jsonl:1" in err and "Ee" in err
    (d / "t.jsonl").write_text("")
    rc, err = run(["conforms", "good.sleec", "t.jsonl"], capsys)
    assert rc == 2 and "the trace is empty" in err


def test_fmt_on_a_broken_file_says_where(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["fmt", "bad.sleec"])
    captured = capsys.readouterr()
    assert rc == 1 and captured.out == ""
    assert "bad.sleec:1:53: error: response `G` is not declared as an event" in captured.err


# ---------------------------------------------------------------- the command line itself


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["chekc", "x"], "invalid choice: 'chekc' (choose from 'check', "),
        (["chekc", "x"], "(did you mean 'check'?)\n  hint: `cosleec --help` lists what it takes"),
        (["ros2", "manger"], "(did you mean 'manager'?)"),
        (["check", "--jsn", "x"], "unrecognized argument: --jsn (did you mean '--json'?)"),
        (
            ["check", "--jsn", "--strct", "x"],
            "--jsn (did you mean '--json'?), --strct (did you mean '--strict'?)",
        ),
        (["check", "--jsn", "x"], "hint: `cosleec check --help` lists what it takes"),
        (["ros2", "manager", "--semantcs", "nested"], "--semantcs (did you mean '--semantics'"),
        (["ros2", "task", "--moduel=tasks", "r.sleec"], "--moduel=tasks (did you mean '--module'?)"),
        (["decide", "r", "--event", "E", "--semantics", "nestd"], "(did you mean 'nested'?)"),
        (["decide", "r"], "the following arguments are required: --event"),
        (["check", "x", "--frobnicate"], "unrecognized argument: --frobnicate\n"),
        ([], "the following arguments are required: COMMAND"),
    ],
)
def test_usage_errors_exit_2_and_suggest(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = run(argv, capsys)
    assert rc == 2 and err.startswith("usage: cosleec") and said in err, err


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"cosleec {metadata.version('cosleec')}\n"


def test_every_option_of_every_command_has_a_help_text() -> None:
    def walk(p: argparse.ArgumentParser) -> list[str]:
        missing = []
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub in a.choices.values():
                    missing += walk(sub)
            elif not a.help:
                missing.append(f"{p.prog} {a.option_strings or a.dest}")
        return missing

    assert walk(build_parser()) == []


# ---------------------------------------------------------------- decide


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--event", "Ee"], "--event Ee: the rules declare no event 'Ee'\n  hint: did you mean 'E'?"),
        (["--event", "f"], "hint: did you mean 'F'?"),
        (["--event", "Zzz"], "hint: the rules declare the events E, F"),
        (
            ["--event", "E", "--set", "aa=true"],
            "--set aa: the rules declare no measure 'aa'\n  hint: did you mean 'a'?",
        ),
        (["--event", "E", "--set", "a=maybe"], "hint: a is boolean: --set a=true or --set a=false"),
        (["--event", "E", "--set", "n=abc"], "'abc' is not a number\n  hint: n is numeric: a finite number"),
        (
            ["--event", "E", "--set", "s=hgh"],
            "hint: did you mean 'high'? s is a scale: one of its literals, low, mid, high",
        ),
        (["--event", "E", "--set", "a"], "--set 'a': expected NAME=VALUE\n  hint: e.g. --set a=true"),
    ],
)
def test_decide_names_the_unknown_name_or_the_value_it_cannot_use(
    d: Path, capsys: pytest.CaptureFixture[str], extra: list[str], said: str
) -> None:
    rc, err = run(["decide", "good.sleec", *extra], capsys)
    assert rc == 2 and said in err, err


def test_decide_without_a_needed_value_says_which(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = run(["decide", "good.sleec", "--event", "E"], capsys)
    assert rc == 2 and "no value for a" in err and "give it with --set" in err


def test_analyse_an_unknown_check_suggests(d: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = run(["analyse", "good.sleec", "--check", "redundnt"], capsys)
    assert (
        rc == 2 and "unknown check 'redundnt' (did you mean redundant?)" in err and "one or more of:" in err
    )
    rc, err = run(["analyse", "good.sleec", "--check", "conflcit"], capsys)
    assert rc == 2 and "(did you mean vacuous-conflict or situational-conflict?)" in err


# ---------------------------------------------------------------- internal errors are only bugs


@pytest.mark.parametrize(
    ("error", "rc", "said"),
    [
        (KeyError("x"), 70, "cosleec: internal error: KeyError: 'x' (please report this)"),
        (ValueError("boom"), 70, "cosleec: internal error: ValueError: boom"),
        (OSError(5, "I/O error"), 70, "cosleec: internal error: OSError"),
        (PermissionError(13, "Permission denied", "/some/file"), 1, "cosleec: /some/file: Permission denied"),
    ],
)
def test_only_a_bug_is_an_internal_error(
    d: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    error: Exception,
    rc: int,
    said: str,
) -> None:
    def broken(_: argparse.Namespace) -> int:
        raise error

    monkeypatch.setattr(check, "run", broken)
    assert main(["check", "good.sleec"]) == rc
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err


# ---------------------------------------------------------------- did you mean, everywhere


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--event", "E", "--set", "s=HIGH"], "hint: did you mean 'high'? s is a scale"),
        (["--event", "E", "--set", "s=3"], "hint: s is a scale: one of its literals, low, mid, high"),
        (["--event", "E", "--set", "a="], "a is boolean: write true or false, not ''"),
        (["--event", "E", "--set", "n=inf"], "hint: n is numeric: a finite number"),
        (["--event", "E", "--set", "zzz=1"], "hint: the rules declare the measures a, n, s"),
        (["--event", "E", "--set", "F=true"], "hint: F is an event: give it with --event F"),
        (["--event", "a"], "hint: a is a measure: give its value with --set a=VALUE"),
    ],
)
def test_decide_suggests_in_any_case_and_tells_events_from_measures(
    d: Path, capsys: pytest.CaptureFixture[str], extra: list[str], said: str
) -> None:
    rc, err = run(["decide", "good.sleec", *extra], capsys)
    assert rc == 2 and said in err, err


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        (
            "measures:\n  a: {topc: /a, type: std_msgs/Bool}\n",
            "unknown key(s) ['topc'] (did you mean 'topic'?)",
        ),
        ("measures:\n  aa: {topic: /a, type: std_msgs/Bool}\n", "no measure 'aa' (did you mean 'a'?)"),
        (
            "measures:\n  zzz: {topic: /a, type: std_msgs/Bool}\n",
            "no measure 'zzz'; the rules declare the measures a, n, s",
        ),
        (
            "measures:\n  E: {topic: /a, type: std_msgs/Bool}\n",
            "it is an event of the rules: list it under `events`",
        ),
        (
            "events:\n  e: {topic: /a, type: std_msgs/Bool, equals: true}\n",
            "no event 'e' (did you mean 'E'?)",
        ),
        (
            "events:\n  a: {topic: /a, type: std_msgs/Bool, equals: true}\n",
            "it is a measure of the rules: list it under `measures`",
        ),
        (
            "events:\n  E: {topic: /a, type: std_msgs/Bool, equals: true, qos: reliabel}\n",
            "no QoS profile 'reliabel'; profiles: sensor_data, reliable, latched (did you mean 'reliable'?)",
        ),
        (
            "events:\n  E: {topic: /a, type: std_msgs/Bool, equals: true, qos: {reliabilty: reliable}}\n",
            "unknown qos key(s) ['reliabilty'] (did you mean 'reliability'?)",
        ),
        (
            "events:\n  E: {topic: /a, type: std_msgs/Bool, equals: true, qos: {durability: transient}}\n",
            "durability 'transient' is not one of volatile, transient_local (did you mean 'transient_local'?)",
        ),
        (
            "events:\n  E: {topic: /a, type: std_msgs/Bool, equals: true, fire: eahc}\n",
            "not 'eahc' (did you mean 'each'?)",
        ),
        (
            "measures:\n  s: {topic: /a, type: std_msgs/Float64, bands: [[1, low], [2, meid], [hihg]]}\n",
            "['meid', 'hihg'] not in the scale of s (low, mid, high) (did you mean 'mid' for 'meid', 'high' for 'hihg'?)",
        ),
    ],
)
def test_a_listener_mapping_suggests_keys_names_and_values(
    d: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    entry: str,
    message: str,
) -> None:
    fake_std_msgs(monkeypatch)
    (d / "map.yaml").write_text(entry)
    rc, err = run(["ros2", "listener", "map.yaml", "--rules", "good.sleec"], capsys)
    assert rc == 1 and err.startswith("cosleec: map.yaml:2:") and message in err, err


def test_check_suggests_a_declared_name_or_literal_in_another_case(
    d: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (d / "case.sleec").write_text(
        GOOD.replace("when E then F unless a", "when e and s > HIGH then F unless A")
    )
    rc = main(["check", "case.sleec"])
    out = capsys.readouterr().out
    assert rc == 1
    assert out.count("hint: did you mean") == 3, out
    for name in ("`E`", "`high`", "`a`"):
        assert f"hint: did you mean {name}?" in out, out
