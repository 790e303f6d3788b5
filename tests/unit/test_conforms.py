"""``cosleec conforms``: exit 0 conforms (pending printed), 1 violated or refused, 2 input errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.cli.main import main
from tests.unit.semantics.test_trace import RULES, run_manager

FALL_THEN_SMOKE = [
    {"t": 0, "set": {"assentToSupportCalls": False}},
    {"t": 0, "event": "UserFallen"},
    {"t": 120, "set": {"alarmOn": True}, "event": "SmokeDetected"},
]


def write(tmp_path: Path, lines: list[dict[str, object]] | str, name: str = "trace.jsonl") -> str:
    f = tmp_path / name
    f.write_text(lines if isinstance(lines, str) else "".join(json.dumps(x) + "\n" for x in lines))
    return str(f)


@pytest.fixture
def rules(tmp_path: Path) -> str:
    f = tmp_path / "rules.sleec"
    f.write_text(RULES)
    return str(f)


def conforms(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    rc = main(["conforms", *args])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


# ---------------------------------------------------------------------------- exit 0 and 1


def test_conforms_up_to_the_last_time_prints_what_is_pending(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE[:2], {"t": 60}])
    rc, out, _ = conforms(capsys, rules, trace)
    assert rc == 0
    assert "pending   Rule3 (default): not CallSupport in [0, 600]" in out
    assert out.splitlines()[-1] == "0 violations, 0 refused, 1 pending, 0 conflicts (trace up to 60 s)"


def test_a_violation_names_rule_clause_window_and_cause(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 120, "event": "CallSupport"}])
    rc, out, _ = conforms(
        capsys, rules, trace, "--priority", "Rule21 > Rule3", "--priority-semantics", "conflict-aware"
    )
    assert rc == 1
    assert (
        "violated  Rule3 (default) at 120 s: not CallSupport in [0, 600] -- CallSupport happened at 120 s"
        in out
    )
    assert "conflict  at 120 s: Rule21 (default) owes CallSupport, Rule3 (default) forbids it" in out
    assert out.splitlines()[-1] == "1 violation, 0 refused, 0 pending, 1 conflict (trace up to 120 s)"


def test_tiago_priorities(rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The issue's example: with Rule21 > Rule3, CallSupport 2 minutes after the fall and at the smoke
    conforms under cancellation and violates Rule3 when conflict-aware; 5 minutes later, under both."""
    early = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 120, "event": "CallSupport"}], "early.jsonl")
    late = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 420, "event": "CallSupport"}], "late.jsonl")
    high = ["--priority", "Rule21 > Rule3"]
    assert conforms(capsys, rules, early, *high)[0] == 0
    assert conforms(capsys, rules, early, *high, "--priority-semantics", "cancel")[0] == 0
    rc, out, _ = conforms(capsys, rules, early, *high, "--priority-semantics", "conflict-aware")
    assert rc == 1 and "violated  Rule3" in out
    for semantics in ("cancel", "conflict-aware"):
        rc, out, _ = conforms(capsys, rules, late, *high, "--priority-semantics", semantics)
        assert rc == 0, out
        assert "cancelled Rule3 (default)" in out


def test_without_priority_the_prohibition_wins_and_the_obligation_is_refused(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 200}])
    rc, out, _ = conforms(capsys, rules, trace)
    assert rc == 1
    assert "refused   Rule21 (default) at 120 s: CallSupport in [120, 420] -- " in out
    assert "no priority settles the conflict" in out
    assert out.splitlines()[-1] == "0 violations, 1 refused, 1 pending, 1 conflict (trace up to 200 s)"


def test_json_is_one_document_with_the_options(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 120, "event": "CallSupport"}])
    rc, out, _ = conforms(
        capsys,
        rules,
        trace,
        "--json",
        "--priority",
        "Rule21 > Rule3",
        "--semantics",
        "nested",
        "--untimed",
        "30",
    )
    assert rc == 0
    doc = json.loads(out)
    assert doc["conforms"] is True and doc["end"] == 120
    assert doc["options"] == {
        "semantics": "nested",
        "untimed": 30.0,
        "priorities": [["Rule21", "Rule3"]],
        "priority_semantics": "cancel",
    }
    assert {"firings", "verdicts", "conflicts"} <= set(doc)
    assert {v["status"] for v in doc["verdicts"]} == {"fulfilled", "cancelled"}
    rc, out, _ = conforms(capsys, rules, trace, "--json")
    assert rc == 1 and json.loads(out)["conforms"] is False


def test_an_audit_log_is_checked_like_a_trace(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)  # CallSupport 130 s after a fall without assent, 10 s after the smoke
    rc, out, _ = conforms(capsys, rules, str(log))
    assert rc == 1 and "violated  Rule3 (default) at 130 s" in out
    assert conforms(capsys, rules, str(log), "--priority", "Rule21 > Rule3")[0] == 0


# ---------------------------------------------------------------------------- exit 2


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("{not json", "not valid JSON"),
        ('{"t": 5}', "time goes back"),
        ('{"t": 200, "evnt": "CallSupport"}', "unknown key 'evnt'"),
        ('{"t": 200, "event": "CallSuport"}', "event 'CallSuport' is not declared"),
        ('{"t": 200, "set": {"alarmOn": "yes"}}', "alarmOn is boolean"),
    ],
)
def test_a_bad_trace_line_is_exit_2_with_file_and_line(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, message: str
) -> None:
    trace = write(tmp_path, "".join(json.dumps(x) + "\n" for x in FALL_THEN_SMOKE) + line + "\n")
    rc, out, err = conforms(capsys, rules, trace)
    assert rc == 2 and out == ""
    assert err.startswith(f"cosleec: {trace}:4") and message in err
    assert "\n  hint: " in err


def test_input_errors_are_exit_2(rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = write(tmp_path, FALL_THEN_SMOKE)
    bad_rules = tmp_path / "bad.sleec"
    bad_rules.write_text("def_start event E def_end rule_start R1 when E then G rule_end\n")
    rc, _, err = conforms(capsys, str(bad_rules), trace)
    assert rc == 2 and f"{bad_rules}:1:" in err and "not declared" in err
    rc, _, err = conforms(capsys, str(tmp_path / "missing.sleec"), trace)
    assert rc == 2 and "missing.sleec" in err
    rc, _, err = conforms(capsys, rules, str(tmp_path / "missing.jsonl"))
    assert rc == 2 and "cannot read the trace" in err
    rc, _, err = conforms(capsys, rules, write(tmp_path, "\n", "empty.jsonl"))
    assert rc == 2 and "the trace is empty" in err


@pytest.mark.parametrize(
    ("priority", "message"),
    [
        ("Rule21 > Rule4", "no rule named 'Rule4'"),
        ("Rule2 > Rule3", "did you mean 'Rule21'?"),
        ("Rule3 > Rule3", "rule 'Rule3' is declared above itself"),
        ("Rule3 > Rule21 > Rule3", "go round in a circle: Rule3 > Rule21 > Rule3"),
        ("Rule21 >", ""),
        ("", ""),
    ],
)
def test_bad_priorities_are_exit_2(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], priority: str, message: str
) -> None:
    rc, _, err = conforms(capsys, rules, write(tmp_path, FALL_THEN_SMOKE), "--priority", priority)
    assert rc == 2 and message in err


def test_priority_cycles_across_options_are_exit_2(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, FALL_THEN_SMOKE)
    rc, _, err = conforms(
        capsys, rules, trace, "--priority", "Rule21 > Rule3", "--priority", "Rule3 > Rule21"
    )
    assert rc == 2 and "circle" in err


@pytest.mark.parametrize(
    "args",
    [
        ["--untimed", "nan"],
        ["--untimed", "-1"],
        ["--untimed", "soon"],
        ["--priority-semantics", "first"],
        ["--semantics", "nestd"],
        [],  # no trace
    ],
)
def test_usage_errors_are_exit_2(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str]
) -> None:
    trace = [write(tmp_path, FALL_THEN_SMOKE)] if args else []
    assert conforms(capsys, rules, *trace, *args)[0] == 2


def test_the_files_own_priorities_count_and_clash_with_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules = tmp_path / "prio.sleec"
    rules.write_text(RULES + "priority_start\n    Rule21 > Rule3\npriority_end\n")
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 120, "event": "CallSupport"}])
    rc, out, _ = conforms(capsys, str(rules), trace, "--json")
    assert rc == 0 and json.loads(out)["options"]["priorities"] == [["Rule21", "Rule3"]]
    rc, _, err = conforms(capsys, str(rules), trace, "--priority", "Rule3 > Rule21")
    assert rc == 2 and "circle" in err
