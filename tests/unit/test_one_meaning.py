"""`refused` and `violated` mean one thing in Manager.stats, the audit log and `cosleec conforms`
(issue 33): *refused* is an attempt a prohibition did not permit, never a verdict; a
*violation* is a verdict that makes the run not conform -- ``violated`` or ``blocked`` (an
obligation whose whole window another rule forbade, called ``refused`` before).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.cli.main import main
from cosleec.runtime import Manager, VirtualClock, read_audit
from cosleec.semantics import BLOCKED, BREACHES
from cosleec.semantics.verdicts import status

RULES = """
def_start
    event FallDetected event CallNurse event RaiseAlarm event Visit event RecordVideo
    event CurtainRequest event OpenCurtains
    measure patientConsented : boolean
    measure night : boolean
def_end
rule_start
    R1 when FallDetected then CallNurse within 60 seconds otherwise RaiseAlarm
    R2 when Visit then not RecordVideo within 10 minutes unless patientConsented
    R3 when CurtainRequest then OpenCurtains within 1 minutes
    R4 when CurtainRequest and night then not OpenCurtains within 10 minutes
rule_end
"""


def one_run(tmp_path: Path) -> tuple[Path, Path, dict[str, int]]:
    """A run with each kind: a missed deadline, a forbidden event done anyway, a conflict the
    prohibition wins, two refused attempts and three questions."""
    rules, log = tmp_path / "robot.sleec", tmp_path / "audit.jsonl"
    rules.write_text(RULES)
    clock = VirtualClock()
    m = Manager.from_text(RULES, clock=clock, audit=log, dispatch=False)
    m.start()
    m.update(patientConsented=False, night=True)
    m.event("FallDetected")
    m.event("Visit")
    for _ in range(3):
        assert not m.permission("RecordVideo")  # questions: not attempts
    assert not m.request("RecordVideo", source="camera")
    assert not m.request("RecordVideo", source="camera")
    m.event("CurtainRequest")  # R3's window is all forbidden by R4: blocked
    clock.advance(10)
    m.event("RecordVideo")  # R2 violated
    clock.advance(60)  # R1's deadline passes: violated, its otherwise starts
    m.close()
    return rules, log, m.stats.to_json()


def final_statuses(log: Path) -> dict[int, dict[str, object]]:
    last: dict[int, dict[str, object]] = {}
    for r in read_audit(log):
        if r["kind"] == "obligation":
            last[int(r["id"])] = r
    return last


def test_one_run_counts_the_same_in_stats_the_audit_log_and_conforms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules, log, stats = one_run(tmp_path)
    ends = final_statuses(log)
    in_the_log = sorted(
        str(r["status"]) for r in ends.values() if r["status"] in BREACHES and not r.get("late")
    )
    assert in_the_log == ["blocked", "violated", "violated"]
    refusals = [r for r in read_audit(log) if r["kind"] == "refused"]
    assert stats["violations"] == len(in_the_log) == 3
    assert stats["refused"] == len(refusals) == 2

    assert main(["conforms", str(rules), str(log), "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    verdicts = sorted(v["status"] for v in doc["verdicts"] if v["status"] in BREACHES)
    assert doc["violations"] == len(verdicts) == stats["violations"]
    assert verdicts == in_the_log  # the same words for the same outcomes

    assert main(["conforms", str(rules), str(log)]) == 1
    out = capsys.readouterr().out
    assert "blocked   R3 (default)" in out and "R4 forbids OpenCurtains" in out
    assert out.splitlines()[-1].startswith("3 violations (1 blocked), ")
    assert "refused" not in out  # refused is an attempt; conforms judges verdicts


def test_the_old_name_of_blocked_is_read_as_blocked(tmp_path: Path) -> None:
    from cosleec.runtime.obligations import Tracked

    assert status("refused") == BLOCKED == "blocked" and status("violated") == "violated"
    _, log, _ = one_run(tmp_path)
    (blocked,) = [r for r in final_statuses(log).values() if r["status"] == "blocked"]
    old = {**blocked, "status": "refused"}  # as a journal written before issue 33 holds it
    assert Tracked.from_json(old).status == "blocked" and Tracked.from_json(blocked).status == "blocked"
