"""``cosleec conforms``: exit 0 conforms (pending printed), 1 violated or blocked, 2 input errors."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

from cosleec.cli.conforms import json_safe
from cosleec.cli.main import main
from cosleec.runtime import Manager, VirtualClock
from cosleec.semantics import Conflict, Firing, Judgement, Verdict
from tests.unit.semantics.test_trace import RULES, options_record, piped, run_manager

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
    assert out.splitlines()[-1] == "0 violations, 1 pending, 0 conflicts (trace up to 60 s)"


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
    assert out.splitlines()[-1] == "1 violation, 0 pending, 1 conflict (trace up to 120 s)"


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


def test_without_priority_the_prohibition_wins_and_the_obligation_is_blocked(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 200}])
    rc, out, _ = conforms(capsys, rules, trace)
    assert rc == 1
    assert "blocked   Rule21 (default) at 120 s: CallSupport in [120, 420] -- " in out
    assert "no priority settles the conflict" in out
    assert out.splitlines()[-1] == "1 violation (1 blocked), 1 pending, 1 conflict (trace up to 200 s)"


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
        "priority_lead": 0.0,
        "from_audit": [],
    }
    assert doc["notes"] == [] and doc["warnings"] == []
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


# ---------------------------------------------------------------------------- a trace read once

COSLEEC = Path(sys.executable).with_name("cosleec")


def violating_then_padding(n: int) -> bytes:
    """A violation of Rule3 in the first lines, then ``n`` lines of time passing."""
    lines = [*FALL_THEN_SMOKE[:2], {"t": 1, "event": "CallSupport"}, *({"t": 2 + k / 1000} for k in range(n))]
    return "".join(json.dumps(x) + "\n" for x in lines).encode()


@pytest.mark.skipif(not COSLEEC.exists(), reason="needs the cosleec script next to the interpreter")
@pytest.mark.parametrize("trace", ["/dev/stdin", "-"])
def test_a_piped_trace_is_judged_whole(rules: str, tmp_path: Path, trace: str) -> None:
    """``cat big.jsonl | cosleec conforms rules.sleec /dev/stdin``: the violation on line 3 counts."""
    data = violating_then_padding(5000)
    as_file = write(tmp_path, data.decode())
    assert subprocess.run([str(COSLEEC), "conforms", rules, as_file], capture_output=True).returncode == 1
    done = subprocess.run(
        [str(COSLEEC), "conforms", rules, trace], input=data, capture_output=True, timeout=60
    )
    assert done.returncode == 1, done.stdout.decode() + done.stderr.decode()
    assert b"violated  Rule3 (default) at 1 s" in done.stdout


@pytest.mark.skipif(not Path("/dev/fd").is_dir(), reason="needs /dev/fd")
@pytest.mark.parametrize("n", [0, 3000])
def test_a_process_substitution_is_judged_whole(
    rules: str, capsys: pytest.CaptureFixture[str], n: int
) -> None:
    """``cosleec conforms rules.sleec <(cat trace.jsonl)``: a /dev/fd path of a pipe."""
    path, thread = piped(violating_then_padding(n))
    try:
        rc, out, err = conforms(capsys, rules, path)
    finally:
        os.close(int(path.rsplit("/", 1)[1]))
        thread.join(5)
    assert rc == 1, err
    assert "violated  Rule3 (default) at 1 s" in out


# ---------------------------------------------------------------------------- options of the run


def audit_log(tmp_path: Path, *options: str, name: str = "audit.jsonl", semantics: str = "last-wins") -> str:
    """The TIAGo run as a Manager's audit log: fall without assent, smoke at 120 s, CallSupport at
    ``call`` s; ``options`` are options records put at the start."""
    head = ',"wall":"2026-01-01T00:00:00+00:00","mono":1.0,"run":"r9","rules":"06700cf8c39a7f6f"'
    body = [
        f'{{"seq":10,"kind":"context","time":0.0{head},"values":{{"assentToSupportCalls":false}}}}',
        f'{{"seq":11,"kind":"event","time":0.0{head},"event":"UserFallen"}}',
        f'{{"seq":12,"kind":"decision","time":0.0{head},"rule":"Rule3","clause":0,"semantics":"{semantics}"}}',
        f'{{"seq":13,"kind":"context","time":120.0{head},"values":{{"alarmOn":true}}}}',
        f'{{"seq":14,"kind":"event","time":120.0{head},"event":"SmokeDetected"}}',
        f'{{"seq":15,"kind":"event","time":380.0{head},"event":"CallSupport"}}',
    ]
    return write(tmp_path, "".join(options) + "".join(line + "\n" for line in body), name)


def test_the_options_the_run_used_are_used(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """CallSupport at 380 s: with Rule21 > Rule3 conflict-aware, Rule3 is cancelled at 420 s (a
    violation at 380) or, with a 60 s lead, at 360 s (no violation). The log says which."""
    plain = audit_log(tmp_path, name="plain.jsonl")
    rc, out, _ = conforms(capsys, rules, plain)
    assert rc == 1 and "blocked   Rule21" in out  # no options record: the defaults
    assert "note      the audit log records no options" in out
    log = audit_log(tmp_path, options_record(1, 0, priority_lead=60, semantics="last-wins", untimed="none"))
    rc, out, _ = conforms(capsys, rules, log)
    assert rc == 0, out
    assert (
        "options   from the audit log (line 1): semantics last-wins, priority Rule21 > Rule3, "
        "priority-semantics conflict-aware, priority-lead 60, untimed none" in out
    )
    assert "cancelled Rule3 (default) at 360 s" in out
    # what the command line gives wins, and is no longer said to come from the log
    rc, out, _ = conforms(capsys, rules, log, "--priority-lead", "0")
    assert rc == 1 and "violated  Rule3 (default) at 380 s" in out
    assert "options   from the audit log (line 1): semantics last-wins, priority Rule21 > Rule3, " in out
    assert "priority-lead" not in out
    rc, out, _ = conforms(capsys, rules, log, "--priority-semantics", "cancel")
    assert rc == 0 and "cancelled Rule3 (default) at 120 s" in out
    rc, out, _ = conforms(capsys, rules, log, "--priority", "Rule3 > Rule21")  # replaces the log's pair
    assert rc == 1 and "priority Rule21" not in out


def test_json_names_the_options_from_the_audit_log(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = audit_log(tmp_path, options_record(1, 0, priority_lead=60, semantics="last-wins"))
    rc, out, _ = conforms(capsys, rules, log, "--json", "--semantics", "nested")
    assert rc == 0
    doc = json.loads(out)
    assert doc["options"] == {
        "semantics": "nested",
        "untimed": 1.0,  # "immediate": the Manager's one-second tolerance
        "priorities": [["Rule21", "Rule3"]],
        "priority_semantics": "conflict-aware",
        "priority_lead": 60.0,
        "from_audit": ["priorities", "priority_semantics", "priority_lead", "untimed"],
    }
    assert doc["warnings"] == [
        "the log's decisions were made with semantics last-wins (1 decision); "
        "judged with nested (given on the command line)"
    ]
    rc, out, _ = conforms(capsys, rules, write(tmp_path, FALL_THEN_SMOKE), "--json")
    assert json.loads(out)["options"]["from_audit"] == []


def test_untimed_immediate_in_the_log_is_a_one_second_deadline(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules = tmp_path / "r.sleec"
    rules.write_text("def_start event T event A def_end rule_start R1 when T then A rule_end\n")
    head = ',"run":"r","rules":"x"'
    body = (
        f'{{"seq":2,"kind":"event","time":0.0{head},"event":"T"}}\n'
        f'{{"seq":3,"kind":"event","time":1.5{head},"event":"A"}}\n'
    )
    log = write(tmp_path, options_record(1, 0, priorities=[], untimed="immediate") + body, "a.jsonl")
    rc, out, _ = conforms(capsys, str(rules), log)
    assert rc == 1 and "violated  R1 (default) at 1 s: A in [0, 1]" in out
    assert "untimed immediate (1 s)" in out
    assert conforms(capsys, str(rules), log, "--untimed", "none")[0] == 0
    assert conforms(capsys, str(rules), log, "--untimed", "2")[0] == 0
    rc, out, _ = conforms(capsys, str(rules), log, "--untimed", "immediate")
    assert (
        rc == 1
        and "from the audit log" in out
        and "untimed" not in out.split("from the audit log")[1].splitlines()[0]
    )
    log = write(tmp_path, options_record(1, 0, priorities=[], untimed="none") + body, "b.jsonl")
    assert conforms(capsys, str(rules), log)[0] == 0
    log = write(tmp_path, options_record(1, 0, priorities=[], untimed=1.25) + body, "c.jsonl")
    rc, out, _ = conforms(capsys, str(rules), log)
    assert rc == 1 and "untimed 1.25" in out


def test_several_runs_with_different_options_the_last_counts_and_is_said(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = audit_log(
        tmp_path,
        options_record(1, 0, run="r1", priorities=[]),
        options_record(2, 0, run="r2", priority_lead=60, semantics="last-wins"),
    )
    rc, out, _ = conforms(capsys, rules, log)
    assert rc == 0, out
    assert "warning   the log has runs with different options: those of the last (line 2) are used" in out
    log = audit_log(
        tmp_path, options_record(1, 0, run="r1"), options_record(2, 0, run="r2"), name="same.jsonl"
    )
    rc, out, _ = conforms(capsys, rules, log)
    assert "different options" not in out


def test_decisions_made_with_other_semantics_are_a_warning(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = audit_log(tmp_path, options_record(1, 0, semantics="last-wins"), semantics="nested")
    rc, out, err = conforms(capsys, rules, log)
    assert rc in (0, 1) and err == ""
    assert (
        "warning   the log's decisions were made with semantics nested (1 decision); judged with last-wins"
        in out
    )
    rc, out, _ = conforms(capsys, rules, log, "--semantics", "nested")
    assert "decisions were made" not in out


def test_the_logs_priorities_over_rules_not_in_these_rules_are_dropped(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = audit_log(
        tmp_path, options_record(1, 0, priorities=[["Rule21", "Rule3"], ["Rule9", "Rule3"]], priority_lead=60)
    )
    rc, out, _ = conforms(capsys, rules, log)
    assert rc == 0, out
    assert "note      priorities of the log over rules not in these rules, ignored: Rule9 > Rule3" in out


def test_the_logs_priorities_against_the_files_are_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules = tmp_path / "prio.sleec"
    rules.write_text(RULES + "priority_start\n    Rule3 > Rule21\npriority_end\n")
    log = audit_log(tmp_path, options_record(1, 0))
    rc, _, err = conforms(capsys, str(rules), log)
    assert rc == 2 and "circle" in err and f"{log}:1" in err


def test_a_run_that_read_unknowns_otherwise_is_a_warning(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = audit_log(tmp_path, options_record(1, 0, unknown="false"))
    _, out, _ = conforms(capsys, rules, log)
    assert "warning   the run read a condition over a measure with no value as false (unknown=false)" in out
    log = audit_log(tmp_path, options_record(1, 0, unknown="undetermined"), name="u.jsonl")
    assert "measure with no value" not in conforms(capsys, rules, log)[1]


def test_a_real_managers_options_are_used(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The options Manager.start() records are those conforms judges with (skipped until it records them)."""
    rules = tmp_path / "rules.sleec"
    rules.write_text(RULES)
    log = tmp_path / "audit.jsonl"
    clock = VirtualClock()
    m = Manager.from_text(
        RULES,
        clock=clock,
        audit=log,
        dispatch=False,
        priorities=["Rule21 > Rule3"],
        priority_semantics="conflict-aware",
        priority_lead=60,
    )
    m.start()
    m.update(assentToSupportCalls=False)
    m.event("UserFallen")
    clock.advance(120)
    m.update(alarmOn=True)
    m.event("SmokeDetected")
    clock.advance(260)
    m.tick()
    m.event("CallSupport")  # at 380 s: Rule3 was cancelled at 360 s, 60 s before Rule21's deadline
    m.close()
    rc, out, _ = conforms(capsys, str(rules), str(log))
    if "records no options" in out:
        pytest.skip("this Manager writes no options record yet")
    assert rc == 0, out
    assert (
        "options   from the audit log (line 1): semantics last-wins, priority Rule21 > Rule3, "
        "priority-semantics conflict-aware, priority-lead 60, untimed none" in out
    )
    assert "cancelled Rule3 (default) at 360 s" in out and "warning" not in out
    assert conforms(capsys, str(rules), str(log), "--priority-lead", "0")[0] == 1


# ---------------------------------------------------------------------------- --priority-lead


def test_priority_lead(rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = write(tmp_path, [*FALL_THEN_SMOKE, {"t": 380, "event": "CallSupport"}])
    high = ["--priority", "Rule21 > Rule3", "--priority-semantics", "conflict-aware"]
    rc, out, _ = conforms(capsys, rules, trace, *high)
    assert rc == 1 and "violated  Rule3 (default) at 380 s" in out
    rc, out, _ = conforms(capsys, rules, trace, *high, "--priority-lead", "60")
    assert rc == 0 and "cancelled Rule3 (default) at 360 s" in out
    rc, out, _ = conforms(capsys, rules, trace, *high, "--priority-lead", "60", "--json")
    assert json.loads(out)["options"]["priority_lead"] == 60.0


@pytest.mark.parametrize("lead", ["nan", "-1", "inf", "soon"])
def test_a_bad_priority_lead_is_exit_2(
    rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], lead: str
) -> None:
    rc, _, err = conforms(capsys, rules, write(tmp_path, FALL_THEN_SMOKE), "--priority-lead", lead)
    assert rc == 2 and "priority-lead" in err


# ---------------------------------------------------------------------------- audit logs and new rules


NEW_RULES = RULES.replace("    measure temperature : numeric\n", "").replace(
    "measure level : scale(low, medium, high)", "measure level : boolean"
)


def test_an_old_audit_log_is_checked_against_new_rules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The new rules dropped ``temperature`` and made ``level`` boolean: the log is still judged."""
    rules = tmp_path / "new.sleec"
    rules.write_text(
        NEW_RULES.replace("    event SmokeDetected\n", "").replace(
            "    Rule21 when SmokeDetected and alarmOn then CallSupport within 5 minutes\n", ""
        )
    )
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    rc, out, err = conforms(capsys, str(rules), str(log))
    assert rc == 1, err
    assert "violated  Rule3 (default) at 130 s" in out
    assert "note      not in these rules, ignored: SmokeDetected, temperature" in out
    assert (
        "note      not of the type these rules declare, read as unknown: level (boolean): 'medium' (line 2)"
        in out
    )
    rc, out, _ = conforms(capsys, str(rules), str(log), "--json")
    assert rc == 1 and json.loads(out)["notes"][:1] == [
        "not in these rules, ignored: SmokeDetected, temperature"
    ]
    # a written trace stays strict
    trace = write(tmp_path, [{"t": 0, "set": {"temperature": 20}}])
    rc, _, err = conforms(capsys, str(rules), trace)
    assert rc == 2 and f"{trace}:1" in err and "measure 'temperature' is not declared" in err


# ---------------------------------------------------------------------------- negative times


def test_a_negative_time_is_exit_2(rules: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = write(tmp_path, [{"t": -5, "event": "UserFallen"}, {"t": 0}])
    rc, out, err = conforms(capsys, rules, trace)
    assert rc == 2 and out == ""
    assert err.startswith(f"cosleec: {trace}:1: ") and "negative" in err
    assert "seconds from the start of the run, >= 0" in err


# ---------------------------------------------------------------------------- non-finite numbers


def strict(text: str) -> object:
    def refuse(token: str) -> object:
        raise AssertionError(f"{token} in the JSON output")

    return json.loads(text, parse_constant=refuse)


def test_an_infinite_window_end_is_json_and_reads_never(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A deadline that overflows (1e308 s after t = 1e308) is an infinite window end."""
    rules = tmp_path / "r.sleec"
    rules.write_text("def_start event T event A def_end rule_start R1 when T then A rule_end\n")
    trace = write(tmp_path, [{"t": 1e308, "event": "T"}])
    rc, out, _ = conforms(capsys, str(rules), trace, "--untimed", "1e308", "--json")
    assert rc == 0
    doc = strict(out)
    assert isinstance(doc, dict) and doc["verdicts"][0]["window"] == [1e308, "inf"]
    rc, out, _ = conforms(capsys, str(rules), trace, "--untimed", "1e308")
    assert rc == 0 and "inf" not in out
    assert "pending   R1 (default): A in [1e+308, never] -- not yet; no deadline" in out


def test_every_judgement_is_strict_json() -> None:
    """Whatever numbers a judgement holds, --json writes no NaN or Infinity."""
    j = Judgement(
        end=math.inf,
        firings=[Firing(0, math.nan, "R1", "T", True, 0, 1)],
        verdicts=[
            Verdict(1, 1, "R1", 0, "R1:0", "A", False, 0.0, (0.0, math.inf)),
            Verdict(2, 1, "R1", 0, "R1:1", "B", True, -math.inf, (-math.inf, math.nan), at=math.nan),
        ],
        conflicts=[Conflict(math.inf, "A", 1, 2, ("R1", "R2"), (0, 0), "prohibition-wins")],
    )
    doc = strict(json.dumps(json_safe(j.to_json()), allow_nan=False))
    assert isinstance(doc, dict)
    assert doc["end"] == "inf" and doc["firings"][0]["time"] == "nan"
    assert doc["verdicts"][1]["window"] == ["-inf", "nan"] and doc["conflicts"][0]["time"] == "inf"
