"""``cosleec analyse``: exit codes, text and JSON output, options."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cosleec.analysis import CHECKS
from cosleec.cli.main import main

from .support import sleec, write

CONFLICT = "R1 when A then B within 5 seconds\nR2 when A then not B within 10 seconds"
CLEAN = "R1 when A then B within 5 seconds\nR2 when C then D within 3 seconds"


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    rc = main(["analyse", *args])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err and "internal error" not in out + err
    return rc, out, err


def test_exit_0_when_nothing_is_found_and_1_when_something_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    clean = write(tmp_path, CLEAN, name="clean.sleec")
    conflict = write(tmp_path, CONFLICT, name="conflict.sleec")
    rc, out, _ = _run(capsys, str(clean))
    assert rc == 0 and f"{clean}: no findings" in out
    rc, out, _ = _run(capsys, str(conflict))
    assert rc == 1 and f"{conflict}: " in out
    rc, _, _ = _run(capsys, str(clean), str(conflict))
    assert rc == 1
    # checks that find nothing in the file: 0
    rc, _, _ = _run(capsys, "--check", "redundant,negative-deadline", str(conflict))
    assert rc == 0


def test_a_missing_or_broken_file_is_an_input_error_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "missing.sleec"
    rc, out, err = _run(capsys, str(missing))
    assert rc == 2 and "cannot read file" in out + err and "not analysed" in out
    broken = tmp_path / "broken.sleec"
    broken.write_text("def_start event A def_end rule_start R1 when A then G rule_end\n")
    rc, out, _ = _run(capsys, str(broken), str(write(tmp_path, CLEAN)))
    assert rc == 2 and "`G` is not declared" in out and "not analysed" in out
    rc, out, _ = _run(capsys, "--json", str(missing))
    (doc,) = json.loads(out)["files"]
    assert rc == 2 and doc["ok"] is False and doc["findings"] == [] and doc["diagnostics"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--check", "vacuous-conflit"], "did you mean vacuous-conflict?"),
        (["--check", "redundant,situationl-conflict"], "did you mean situational-conflict?"),
        (["--check", "nothing-like-it"], "unknown check"),
        (["--bound", "0"], "--bound"),
        (["--bound", "1001"], "--bound"),
        (["--bound", "two"], "--bound"),
        (["--timeout", "0"], "--timeout"),
        (["--timeout", "nan"], "--timeout"),
        (["--untimed", "-1"], "--untimed"),
        (["--untimed", "soon"], "--untimed"),
        (["--semantics", "nestd"], "--semantics"),
        (["--priority", "R1 >"], "priority"),
        (["--priority", "R1 > R2", "--priority", "R2 > R1"], "cycle"),
    ],
)
def test_usage_errors_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    path = write(tmp_path, CONFLICT)
    rc, out, err = _run(capsys, *args, str(path))
    assert rc == 2 and message in err
    assert out == ""  # nothing analysed


def test_no_file_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse"]) == 2
    capsys.readouterr()


def test_text_output_is_compiler_style(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, CONFLICT)
    rc, out, _ = _run(capsys, "--check", "vacuous-conflict", str(path))
    assert rc == 1
    lines = out.splitlines()
    head = next(
        i for i, line in enumerate(lines) if line.startswith(f"{path}:3:1: error: [vacuous-conflict]")
    )
    assert lines[head].endswith("because of R2 [proved]")
    assert lines[head + 1].strip() == "R1 when A then B within 5 seconds"
    assert re.fullmatch(r" *\^~*", lines[head + 2])
    assert lines[head + 2].index("^") == lines[head + 1].index("R1")
    assert f"{path}:4:1: note: R2 is part of the cause" in out
    assert "hint: " in out
    assert lines[-1].startswith(f"{path}: 2 findings (")


def test_text_output_of_a_bounded_finding(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, "R1 when A then A within [1 seconds, 2 seconds]")
    rc, out, _ = _run(capsys, "--bound", "3", "--check", "vacuous-conflict", str(path))
    assert rc == 1 and re.search(
        rf"{re.escape(str(path))}:3:1: error: \[vacuous-conflict\] .* \[up to bound 3\]", out
    )


def test_json_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = write(tmp_path, CONFLICT, name="a.sleec")
    b = write(tmp_path, CLEAN, name="b.sleec")
    rc, out, _ = _run(capsys, "--json", str(a), str(b))
    assert rc == 1
    files = json.loads(out)["files"]
    assert [f["path"] for f in files] == [str(a), str(b)]
    assert all(f["ok"] for f in files) and files[1]["findings"] == []
    found = files[0]["findings"]
    assert {(f["code"], f["subject"]) for f in found} >= {
        ("vacuous-conflict", "R1"),
        ("vacuous-conflict", "R2"),
    }
    for f in found:
        assert f["code"] in CHECKS and f["status"] in ("proved", "bounded")
        assert isinstance(f["rules"], list) and f["line"] >= 3 and f["col"] >= 1
        assert f["severity"] in ("error", "warning", "note")
        assert (f["bound"] is None) == (f["status"] == "proved")
    vac = next(f for f in found if f["subject"] == "R1" and f["code"] == "vacuous-conflict")
    assert vac["rules"] == ["R1", "R2"] and vac["line"] == 3 and vac["witness"] is None
    rt = next(f for f in found if f["code"] == "runtime-conflict")
    assert rt["witness"]["confirmed"] is True and rt["witness"]["timeline"]
    trace = rt["witness"]["trace"]
    assert [s["event"] for s in trace if "event" in s] == ["A"] and "event" not in trace[-1]


def test_check_selects_checks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, CONFLICT)
    for checks in ("vacuous-conflict", "runtime-conflict", "vacuous-conflict, runtime-conflict"):
        rc, out, _ = _run(capsys, "--json", "--check", checks, str(path))
        codes = {f["code"] for f in json.loads(out)["files"][0]["findings"]}
        assert rc == 1 and codes == {c.strip() for c in checks.split(",")}


def test_priority_option_settles_a_runtime_conflict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, "R1 when A then B within 5 seconds\nR2 when C then not B within 3 seconds")
    rc, _, _ = _run(capsys, "--check", "runtime-conflict", str(path))
    assert rc == 1
    for given in ("R1 > R2", "R2 > R1"):
        rc, out, _ = _run(capsys, "--check", "runtime-conflict", "--priority", given, str(path))
        assert rc == 0 and "no findings" in out, given


def test_semantics_and_untimed_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, "R1 when A then B within 5 seconds unless x then C unless (not x) then D")
    rc, out, _ = _run(capsys, "--json", "--check", "unselectable-clause", str(path))
    assert rc == 1 and [f["subject"] for f in json.loads(out)["files"][0]["findings"]] == ["R1.0"]
    rc, out, _ = _run(capsys, "--json", "--check", "unselectable-clause", "--semantics", "nested", str(path))
    assert rc == 1 and [f["subject"] for f in json.loads(out)["files"][0]["findings"]] == ["R1.2"]
    untimed = write(tmp_path, "R1 when A then B\nR2 when A then not B within 5 seconds", name="untimed.sleec")
    assert _run(capsys, "--check", "vacuous-conflict", str(untimed))[0] == 0
    assert _run(capsys, "--check", "vacuous-conflict", "--untimed", "0", str(untimed))[0] == 1
    assert _run(capsys, "--check", "vacuous-conflict", "--untimed", "5.5", str(untimed))[0] == 0


def test_a_directory_stands_for_its_rule_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / "rules"
    d.mkdir()
    (d / "a.sleec").write_text(sleec(CONFLICT))
    (d / "b.sleec").write_text(sleec(CLEAN))
    (d / "notes.txt").write_text("not rules")
    rc, out, _ = _run(capsys, "--json", str(d))
    assert rc == 1 and [Path(f["path"]).name for f in json.loads(out)["files"]] == ["a.sleec", "b.sleec"]
    empty = tmp_path / "empty"
    empty.mkdir()
    rc, out, err = _run(capsys, str(empty))
    assert rc != 0 and "no .sleec file" in err


def test_the_analyze_spelling_and_legos_compat(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, CLEAN)
    assert main(["analyze", str(path)]) == 0
    assert main(["analyse", "--legos-compat", str(path)]) == 0
    capsys.readouterr()


def test_a_check_list_that_names_no_check_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, CONFLICT)
    for empty in (",", " , ", ""):
        rc, _, err = _run(capsys, "--check", empty, str(path))
        assert rc == 2 and "names no check" in err


def test_a_priority_naming_a_rule_no_file_declares_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, CONFLICT)
    rc, _, err = _run(capsys, "--priority", "R1 > R3", str(path))
    assert rc == 2 and "'R3'" in err and "no file declares" in err
    rc, _, err = _run(capsys, "--priority", "Rx1 > R2", str(path))
    assert rc == 2 and "did you mean R1" in err
    rc, out, _ = _run(capsys, "--priority", "R1 > R2", "--check", "runtime-conflict", str(path))
    assert rc == 0 and "no findings" in out  # a priority the file declares settles the conflict


def test_an_interval_that_can_close_before_it_opens_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules = sleec("R1 when A then B within [{d} seconds, 10 seconds]")
    path = tmp_path / "interval.sleec"
    path.write_text(rules)
    rc, out, _ = _run(capsys, "--check", "negative-deadline", str(path))
    assert rc == 1 and re.search(r"its window is \[\d+(\.\d+)?, 10\] seconds", out), out


def test_input_errors_of_the_robot_side_exit_2_with_the_fix(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write(tmp_path, CONFLICT)
    (tmp_path / "boom_tasks.py").write_text("def install(manager):\n    raise RuntimeError('boom')\n")
    (tmp_path / "broken_tasks.py").write_text("def install(manager) -> :\n")
    (tmp_path / "exit_tasks.py").write_text("import sys\nsys.exit(3)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for module, said in [
        ("boom_tasks", "install(manager) of 'boom_tasks' failed: RuntimeError: boom"),
        ("broken_tasks", "failed while importing: SyntaxError"),
        ("exit_tasks", "failed while importing: SystemExit"),
        ("no_such_tasks", "cannot import the task module"),
    ]:
        rc, _, err = _run(capsys, "--check", "unimplemented-clause", "--tasks", module, str(path))
        assert rc == 2 and said in err, err
    mapping = tmp_path / "mapping.yaml"
    mapping.write_text("measures:\n  nosuch: {topic: /x, type: std_msgs/Bool}\n")
    rc, _, err = _run(capsys, "--check", "unproduced-input", "--mapping", str(mapping), str(path))
    assert rc == 2 and "nosuch" in err
    a_file = tmp_path / "a-file"
    a_file.write_text("")
    rc, _, err = _run(capsys, "--witnesses", str(a_file), str(path))
    assert rc == 2 and "not a file" in err
    rc, _, err = _run(capsys, "--sarif", str(tmp_path / "no" / "such" / "dir" / "x.sarif"), str(path))
    assert rc == 2 and "cannot write the SARIF file" in err


def test_tasks_as_a_file_and_events_the_robot_produces_itself(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, "R1 when A then B within 5 seconds\nR2 when B then C within 5 seconds")
    tasks = tmp_path / "my_tasks.py"
    tasks.write_text("def install(manager):\n    manager.capability('B')(lambda ob, d: None)\n")
    mapping = tmp_path / "mapping.yaml"
    mapping.write_text("events:\n  A: {topic: /a, type: std_msgs/Bool, equals: true}\n")
    rc, out, _ = _run(
        capsys, "--check", "unimplemented-clause,unproduced-input", "--tasks", str(tasks),
        "--mapping", str(mapping), str(path),
    )  # fmt: skip
    assert rc == 1
    assert "R2: no task and no capability for response event C" in out
    assert "response event B" not in out  # bound by the module
    assert "unproduced-input" not in out  # B is owed by R1: the robot's own action, not an input


NOTE_ONLY = "R1 when A then B within 5 seconds unless x then C unless y then D"  # semantics-differ: a note
WARNING_ONLY = CONFLICT  # with --check runtime-conflict: one warning


@pytest.mark.parametrize(
    ("rules", "check", "fail_on", "rc"),
    [
        (NOTE_ONLY, "all", None, 0),  # a note alone no longer fails CI by default
        (NOTE_ONLY, "all", "warning", 0),
        (NOTE_ONLY, "all", "note", 1),
        (NOTE_ONLY, "all", "error", 0),
        (WARNING_ONLY, "runtime-conflict", None, 1),
        (WARNING_ONLY, "runtime-conflict", "note", 1),
        (WARNING_ONLY, "runtime-conflict", "warning", 1),
        (WARNING_ONLY, "runtime-conflict", "error", 0),
        (WARNING_ONLY, "vacuous-conflict", "error", 1),  # the same file's errors
    ],
)
def test_fail_on_exits_1_only_for_a_finding_at_or_above_its_level(
    rules: str, check: str, fail_on: str | None, rc: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write(tmp_path, rules)
    args = [] if check == "all" else ["--check", check]
    args += [] if fail_on is None else ["--fail-on", fail_on]
    got, out, _ = _run(capsys, "--json", *args, str(path))
    severities = {f["severity"] for f in json.loads(out)["files"][0]["findings"]}
    expected = {"note"} if rules == NOTE_ONLY else {"warning" if check == "runtime-conflict" else "error"}
    assert severities == expected  # the file has findings of exactly this level: the boundary is tested
    assert got == rc


def test_fail_on_takes_only_the_three_levels(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "--fail-on", "warnings", "x.sleec"]) == 2
    err = capsys.readouterr().err
    assert "--fail-on: invalid choice: 'warnings'" in err and "did you mean 'warning'?" in err


def test_the_files_declared_clause_semantics_is_used_unless_contradicted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rule = "R1 when A then B within 5 seconds unless x then C unless (not x) then D"
    declared = write(tmp_path, rule, "semantics_start\n  unless nested\nsemantics_end", name="nested.sleec")
    plain = write(tmp_path, rule, name="plain.sleec")
    subjects = []
    for args in ([str(declared)], ["--semantics", "nested", str(declared)], [str(plain), str(declared)]):
        rc, out, _ = _run(capsys, "--json", "--check", "unselectable-clause", *args)
        subjects.append([f["subject"] for r in json.loads(out)["files"] for f in r["findings"]])
    # nested (the file's) for the declaring file, last-wins (SLEEC's) for the one that declares nothing
    assert subjects == [["R1.2"], ["R1.2"], ["R1.0", "R1.2"]]
    rc, out, err = _run(capsys, "--check", "unselectable-clause", "--semantics", "last-wins", str(declared))
    assert rc == 2 and out == ""
    assert (
        f"{declared}:6:3: --semantics last-wins contradicts the rule file, which declares `unless nested`"
        in err
    )
    assert "hint: leave out --semantics (the file's `nested` is used)" in err
