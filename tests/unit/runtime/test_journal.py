"""The journal: a Manager killed with SIGKILL forgets nothing it must enforce.

Each test kills a real process (``os.kill(os.getpid(), SIGKILL)`` inside it, at a chosen
point) and starts a new Manager on the same journal.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from cosleec.runtime import JournalError, Manager, VirtualClock, read_audit

RULES = """def_start
 event Trigger event Act event Help event Rec event Watch
 measure consent : boolean
def_end
rule_start
 R1 when Trigger then Act within 5 seconds otherwise Help
 R2 when Watch then not Rec within 10 minutes unless consent
rule_end
"""


def die_after(tmp_path: Path, body: str) -> None:
    """Run ``body`` in a new process with ``m`` (a Manager on the journal) and kill it with SIGKILL."""
    (tmp_path / "rules.sleec").write_text(RULES)
    script = (
        textwrap.dedent(
            f"""
        import os, signal
        from cosleec.runtime import Manager, VirtualClock
        clock = VirtualClock(100)
        m = Manager.from_file({str(tmp_path / "rules.sleec")!r}, clock=clock,
                              journal={str(tmp_path / "state.db")!r}, audit={str(tmp_path / "audit.jsonl")!r})
        m.capability("Act")(lambda ob, d: None)
        m.capability("Help")(lambda ob, d: print("HELP", d.id, flush=True))
        m.start()
        """
        )
        + textwrap.dedent(body)
        + "\nos.kill(os.getpid(), signal.SIGKILL)\n"
    )
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert p.returncode == -9, p.stderr


def again(tmp_path: Path, t: float, helped: list[int] | None = None, **kw: Any) -> Manager:
    m = Manager.from_file(
        tmp_path / "rules.sleec",
        clock=VirtualClock(t),
        journal=tmp_path / "state.db",
        audit=tmp_path / "audit.jsonl",
        **kw,
    )
    m.capability("Act")(lambda ob, d: None)
    m.capability("Help")(lambda ob, d: helped.append(d.id) if helped is not None else None)
    return m


def test_a_prohibition_survives_a_kill(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=False); m.event("Watch"); assert not m.request("Rec")')
    m = again(tmp_path, 160).start()
    assert m.request("Rec") is False  # before: allowed after the restart
    assert m.values()["consent"] is False and m.active_layers() == []
    (d,) = m.event("Watch")
    assert d.id == 2  # decision ids go on (before: 1 again)
    m.close()


def test_a_deadline_passed_while_down_is_violated_and_its_otherwise_runs_once(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.event("Trigger")')
    helped: list[int] = []
    m = again(tmp_path, 110, helped).start()  # the deadline was 105
    assert len(helped) == 1 and m.stats["violations"] == 1
    m.close()
    helped2: list[int] = []
    again(tmp_path, 120, helped2).start().close()  # a third run: nothing is owed any more
    assert helped2 == []
    records = read_audit(tmp_path / "audit.jsonl")
    violated = [r for r in records if r["kind"] == "obligation" and r["status"] == "violated"]
    assert [(r["event"], r["window"][1]) for r in violated] == [("Act", 105.0)]
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))


def test_an_obligation_fulfilled_after_the_restart_counts(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.event("Trigger")')
    helped: list[int] = []
    m = again(tmp_path, 103, helped).start()
    m.event("Act")
    m.tick()
    assert m.outstanding() == [] and helped == [] and m.stats["violations"] == 0
    m.close()


def test_an_implementation_cut_short_by_the_kill_is_recorded_not_run_again(tmp_path: Path) -> None:
    (tmp_path / "rules.sleec").write_text(RULES)
    die_after(
        tmp_path,
        """
        import os, signal
        m.capability("Act")(lambda ob, d: os.kill(os.getpid(), signal.SIGKILL))
        m.event("Trigger")
        """,
    )
    ran: list[int] = []
    m = again(tmp_path, 101)
    m.capability("Act")(lambda ob, d: ran.append(d.id))
    m.start()
    m.close()
    assert ran == []
    records = read_audit(tmp_path / "audit.jsonl")
    (cut,) = [r for r in records if r["kind"] == "task-interrupted"]
    assert cut["decision"] == 1 and cut["rule"] == "R1"


def test_records_of_a_step_never_committed_are_set_aside(tmp_path: Path) -> None:
    # a step's records are written to the audit log, then the step is committed with the
    # log's length: a kill in between leaves records of a change that never happened (and
    # perhaps a torn line); the next start sets them aside and numbers on without a gap
    die_after(tmp_path, 'm.update(consent=True); m.event("Watch")')
    log = tmp_path / "audit.jsonl"
    lines = log.read_text().splitlines(keepends=True)
    last = json.loads(lines[-1])
    ghost = [
        json.dumps({**last, "seq": last["seq"] + k, "kind": "decision", "id": 99}) + "\n" for k in (1, 2)
    ]
    log.write_text("".join(lines) + "".join(ghost) + '{"seq": 99, "ki')
    m = again(tmp_path, 101)
    m.event("Watch")
    m.close()
    records = read_audit(log)
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    assert records[: len(lines)] == [json.loads(x) for x in lines]  # the committed history, untouched
    assert all(r.get("id") != 99 for r in records)
    (aside,) = [r for r in records if r["kind"] == "uncommitted"]
    assert aside["records"] == 2 and aside["first"] == last["seq"] + 1
    assert (tmp_path / "audit.jsonl.uncommitted").read_text() == "".join(ghost)
    assert (tmp_path / "audit.jsonl.torn").read_text() == '{"seq": 99, "ki\n'


def test_a_changed_rule_set_keeps_what_it_still_names_and_records_what_it_drops(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=False); m.event("Watch"); m.event("Trigger")')
    (tmp_path / "rules.sleec").write_text(
        RULES.replace(" R2 when Watch then not Rec within 10 minutes unless consent\n", "")
    )
    m = again(tmp_path, 101).start()
    assert m.request("Rec") is True  # the rule that forbade it is gone, and that is recorded
    assert [t.rule for t in m.outstanding()] == ["R1"]
    m.close()
    records = read_audit(tmp_path / "audit.jsonl")
    dropped = [r["what"] for r in records if r["kind"] == "dropped"]
    assert any("R2: not Rec" in w for w in dropped)
    restored = [r for r in records if r["kind"] == "restored" and r["from"]]
    assert restored[-1]["rules_changed"] is True and restored[-1]["obligations"] == 1


def test_an_unwritable_journal_is_a_user_error(tmp_path: Path) -> None:
    (tmp_path / "dir").mkdir()
    with pytest.raises(JournalError, match="cannot open the journal"):
        Manager.from_text(RULES, journal=tmp_path / "dir")


# ---------------------------------------------------------------------------- review findings


def test_one_journal_serves_one_manager_at_a_time(tmp_path: Path) -> None:
    (tmp_path / "rules.sleec").write_text(RULES)
    m = again(tmp_path, 100)
    with pytest.raises(JournalError, match="in use by another Manager"):
        again(tmp_path, 100)
    m.close()
    again(tmp_path, 100).close()


def test_a_damaged_journal_is_a_user_error_and_restores_nothing(tmp_path: Path) -> None:
    import sqlite3

    die_after(tmp_path, 'm.event("Trigger")')
    db = sqlite3.connect(tmp_path / "state.db")
    db.execute("UPDATE meta SET value = '{not json' WHERE key = 'state'")
    db.commit()
    db.close()
    with pytest.raises(JournalError, match="damaged"):
        again(tmp_path, 110)


def test_a_journal_written_on_another_kind_of_clock_is_refused(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=False); m.event("Watch")')
    with pytest.raises(JournalError, match="VirtualClock and this Manager runs on a MonotonicClock"):
        Manager.from_file(tmp_path / "rules.sleec", journal=tmp_path / "state.db")


def test_after_a_reboot_obligations_are_due_sooner_and_prohibitions_stay(tmp_path: Path) -> None:
    import sqlite3

    from cosleec.runtime import MonotonicClock

    class Uptime(MonotonicClock):
        """A monotonic clock reading ``t`` (a machine's uptime)."""

        def __init__(self, t: float) -> None:
            self.t = t

        def now(self) -> float:
            return self.t

    (tmp_path / "rules.sleec").write_text(RULES)
    m = Manager.from_file(
        tmp_path / "rules.sleec", clock=Uptime(100), journal=tmp_path / "state.db", dispatch=False
    )
    m.update(consent=False)
    m.event("Watch")  # not Rec until 700
    m.event("Trigger")  # Act by 105
    m.close()
    db = sqlite3.connect(tmp_path / "state.db")
    state = json.loads(db.execute("SELECT value FROM meta WHERE key = 'state'").fetchone()[0])
    state.update(boot="another boot", wall=state["wall"] - 3600)  # down for an hour, then rebooted
    db.execute("UPDATE meta SET value = ? WHERE key = 'state'", (json.dumps(state),))
    db.commit()
    db.close()
    m = Manager.from_file(
        tmp_path / "rules.sleec", clock=Uptime(200), journal=tmp_path / "state.db", dispatch=False
    )
    m.start()
    assert m.stats["violations"] == 1  # before: uptime 200 > 100 looked like the same boot, no shift
    assert m.request("Rec") is False  # the prohibition as if no time had passed: still in force
    m.close()


def test_an_audit_log_that_fails_stops_the_manager(tmp_path: Path) -> None:
    (tmp_path / "rules.sleec").write_text(RULES)
    m = again(tmp_path, 100)
    assert m.audit is not None
    m.audit._fh.close()  # as a full disk would: the next write fails
    with pytest.raises(JournalError, match="cannot write the audit log"):
        m.event("Watch")
    assert m.request("Rec") is False  # fail closed from now on
    with pytest.raises(JournalError):
        m.update(consent=True)


def test_an_audit_log_edited_by_hand_is_not_cut_mid_record(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=True); m.event("Watch")')
    log = tmp_path / "audit.jsonl"
    log.write_text("# reviewed by Ann\n" + log.read_text())  # every committed offset moves
    before = log.read_text()
    m = again(tmp_path, 101)
    m.close()
    records = read_audit(log)
    assert log.read_text().startswith(before)  # nothing of the history was cut or moved
    assert any(r["kind"] == "audit-mismatch" for r in records)


def test_a_dropped_obligation_is_reported_once(tmp_path: Path) -> None:
    die_after(
        tmp_path, 'm.event("Trigger"); m.clock.set(110); m.tick()'
    )  # Act missed: kept for its late event
    (tmp_path / "rules.sleec").write_text(
        RULES.replace(" R1 when Trigger then Act within 5 seconds otherwise Help\n", "")
    )
    for t in (111, 112):
        Manager.from_file(
            tmp_path / "rules.sleec",
            clock=VirtualClock(t),
            journal=tmp_path / "state.db",
            audit=tmp_path / "audit.jsonl",
        ).close()
    records = read_audit(tmp_path / "audit.jsonl")
    dropped = [r for r in records if r["kind"] == "dropped"]
    assert sorted(r["what"].split(" (")[0] for r in dropped) == [
        "obligation 1",
        "obligation 2",
    ]  # missed Act, Help
    assert {r["run"] for r in dropped} == {
        records[-1]["from"]
    }  # none again on the next restart (before: every time)


def test_a_prohibition_survives_an_item_inserted_before_it(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=False); m.event("Watch")')
    (tmp_path / "rules.sleec").write_text(
        RULES.replace(
            "then not Rec within 10 minutes", "then Act within 1 minutes and not Rec within 10 minutes"
        )
    )
    m = again(tmp_path, 160).start()
    assert m.request("Rec") is False  # before: dropped, its key R2:0 now names `Act`
    m.close()
