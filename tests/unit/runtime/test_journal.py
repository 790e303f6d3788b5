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

from cosleec.runtime import ConfigurationError, JournalError, Manager, VirtualClock, read_audit

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
    assert m.request("Rec").permitted is False  # before: allowed after the restart
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
    assert m.request("Rec").permitted is True  # the rule that forbade it is gone, and that is recorded
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
    def plain() -> Manager:  # no audit log: the journal's own lock
        return Manager.from_text(RULES, clock=VirtualClock(100), journal=tmp_path / "state.db")

    m = plain()
    with pytest.raises(JournalError, match="in use by another Manager"):
        plain()
    m.close()
    plain().close()


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
    assert m.request("Rec").permitted is False  # the prohibition as if no time had passed: still in force
    m.close()


def test_an_audit_log_that_fails_stops_the_manager(tmp_path: Path) -> None:
    (tmp_path / "rules.sleec").write_text(RULES)
    m = again(tmp_path, 100)
    assert m.audit is not None
    m.audit._fh.close()  # as a full disk would: the next write fails
    with pytest.raises(JournalError, match="cannot write the audit log"):
        m.event("Watch")
    assert m.request("Rec").permitted is False  # fail closed from now on
    with pytest.raises(JournalError):
        m.update(consent=True)


def test_an_audit_log_edited_by_hand_is_not_cut_mid_record(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.update(consent=True); m.event("Watch")')
    log = tmp_path / "audit.jsonl"
    log.write_text("# reviewed by Ann\n" + log.read_text())  # every committed offset moves
    before = log.read_text()
    # the journal can no longer show where its history ends in the log: refused (it was recorded
    # as an audit-mismatch before the journal proved what it restores), and nothing is cut
    with pytest.raises(JournalError, match=r"does not continue where the journal state\.db stopped"):
        again(tmp_path, 101)
    assert log.read_text() == before


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
    assert m.request("Rec").permitted is False  # before: dropped, its key R2:0 now names `Act`
    m.close()


# ------------------------------------------- a journal that proves what it restores (issue 28)
# A kill leaves the commits since the Manager opened its journal in state.db-wal only. Each test
# kills a real process with a prohibition in force (not Rec for 10 minutes), damages the files
# as a lost or restored file would, and expects a refusal naming the files -- never an empty
# start that answers request("Rec") True.

FORBID = 'm.update(consent=False); m.event("Watch"); m.event("Trigger"); m.event("Act")'


def two_lives(tmp_path: Path) -> None:
    """A first life, then a second killed with the prohibition in force: the journal's main file
    holds the first life's state (copied in when the second opened it), its -wal file the rest."""
    die_after(tmp_path, 'm.event("Trigger"); m.event("Act")')
    die_after(tmp_path, FORBID)


def refused(tmp_path: Path, match: str) -> JournalError:
    """Start a Manager on the damaged files: refused, naming them and both ways out -- twice, as
    the first refusal left the files as it found them (the -wal file there, or not there)."""
    wal = (tmp_path / "state.db-wal").exists()
    log = (tmp_path / "audit.jsonl").read_bytes()
    with pytest.raises(JournalError, match=match) as e:
        again(tmp_path, 160)
    said = e.value.render()
    assert "state.db" in said and "state.db-wal" in said and "reset_journal=True" in said
    assert (tmp_path / "state.db-wal").exists() == wal and (tmp_path / "audit.jsonl").read_bytes() == log
    with pytest.raises(JournalError) as second:
        again(tmp_path, 160)
    assert str(second.value) == str(e.value)
    return e.value


@pytest.mark.parametrize("lives", [1, 2])
def test_a_deleted_wal_is_refused_not_an_empty_start(tmp_path: Path, lives: int) -> None:
    two_lives(tmp_path) if lives == 2 else die_after(tmp_path, FORBID)
    (tmp_path / "state.db-wal").unlink()
    e = refused(tmp_path, "left running .* state.db-wal file is gone")
    assert "audit.jsonl" in e.render()  # put back with the log, from one backup


def test_a_deleted_wal_is_refused_without_an_audit_log_too(tmp_path: Path) -> None:
    (tmp_path / "rules.sleec").write_text(RULES)
    script = f"""
import os, signal
from cosleec.runtime import Manager, VirtualClock
m = Manager.from_file({str(tmp_path / "rules.sleec")!r}, clock=VirtualClock(100), journal={str(tmp_path / "state.db")!r})
m.update(consent=False); m.event("Watch")
os.kill(os.getpid(), signal.SIGKILL)
"""
    assert subprocess.run([sys.executable, "-c", script], timeout=60).returncode == -9
    (tmp_path / "state.db-wal").unlink()
    with pytest.raises(JournalError, match="left running"):
        Manager.from_file(tmp_path / "rules.sleec", clock=VirtualClock(160), journal=tmp_path / "state.db")


@pytest.mark.parametrize("how", ["truncated", "deleted"])
def test_a_truncated_or_deleted_database_is_refused_and_its_wal_kept(tmp_path: Path, how: str) -> None:
    die_after(tmp_path, FORBID)
    db = tmp_path / "state.db"
    db.write_bytes(b"") if how == "truncated" else db.unlink()
    refused(
        tmp_path,
        f"database file state.db is {'empty' if how == 'truncated' else 'missing'} but its state.db-wal",
    )
    assert (tmp_path / "state.db-wal").stat().st_size > 0  # SQLite would have deleted it


@pytest.mark.parametrize(
    "damage", ["truncated to 0", "truncated to its header", "header flipped", "a frame flipped"]
)
def test_a_damaged_wal_is_refused_when_the_audit_log_has_more(tmp_path: Path, damage: str) -> None:
    two_lives(tmp_path)
    wal = tmp_path / "state.db-wal"
    data = bytearray(wal.read_bytes())
    if damage == "truncated to 0":
        data = bytearray()
    elif damage == "truncated to its header":
        data = data[:32]
    else:
        at = 20 if damage == "header flipped" else 32 + 24 + 4096 + 24 + 100  # inside the second frame
        data[at] ^= 0xFF
    wal.write_bytes(bytes(data))
    refused(tmp_path, "state.db is older than the audit log audit.jsonl")


def test_an_old_copy_of_the_journal_is_refused(tmp_path: Path) -> None:
    die_after(tmp_path, 'm.event("Trigger"); m.event("Act")')
    old = {n: (tmp_path / n).read_bytes() for n in ("state.db", "state.db-wal")}
    die_after(tmp_path, FORBID)  # a second life: the copy is a whole life behind the log
    for name, data in old.items():
        (tmp_path / name).write_bytes(data)
    e = refused(tmp_path, r"state.db is older than the audit log audit.jsonl: .* up to seq \d+")
    last = read_audit(tmp_path / "audit.jsonl")[-1]["seq"]
    assert f"up to seq {last}" in str(e)


def test_an_empty_journal_beside_a_journaled_audit_log_is_refused(tmp_path: Path) -> None:
    die_after(tmp_path, FORBID)
    (tmp_path / "state.db").unlink()
    (tmp_path / "state.db-wal").unlink()
    records = read_audit(tmp_path / "audit.jsonl")
    lineage = records[0]["run"]
    refused(
        tmp_path,
        f"holds no state, but the audit log audit.jsonl continues a journaled history "
        f"\\(lineage {lineage}, records up to seq {records[-1]['seq']}\\)",
    )


def test_a_first_life_killed_before_its_first_commit_is_not_a_lost_history(tmp_path: Path) -> None:
    # its `restored` record is in the log, its commit never happened: the journal is empty, rightly
    (tmp_path / "rules.sleec").write_text(RULES)
    script = f"""
import os, signal
from cosleec.runtime import Manager, VirtualClock, journal
journal.Journal.commit = lambda *a, **k: os.kill(os.getpid(), signal.SIGKILL)
Manager.from_file({str(tmp_path / "rules.sleec")!r}, clock=VirtualClock(100),
                  journal={str(tmp_path / "state.db")!r}, audit={str(tmp_path / "audit.jsonl")!r})
"""
    assert subprocess.run([sys.executable, "-c", script], timeout=60).returncode == -9
    assert [r["kind"] for r in read_audit(tmp_path / "audit.jsonl")] == ["restored"]
    m = again(tmp_path, 101).start()  # not refused: the log holds no committed journaled history
    m.close()


def test_the_records_of_one_step_share_run_mono_and_wall(tmp_path: Path) -> None:
    # what tells one step's uncommitted records (a kill) from lost commits (two steps or more)
    m = again_text(tmp_path)
    m.update(consent=False)
    m.event("Watch")
    m.event("Trigger")  # a step of several records: event, decision, obligation
    m.close()
    steps: dict[tuple[Any, Any, Any], list[str]] = {}
    for r in read_audit(tmp_path / "audit.jsonl"):
        steps.setdefault((r["run"], r["mono"], r["wall"]), []).append(r["kind"])
    assert list(steps.values())[-1] == ["event", "decision", "obligation"]
    assert len(steps) == 5  # restored; options (the update started it); context and layers; Watch; Trigger


def again_text(tmp_path: Path) -> Manager:
    journal, audit = tmp_path / "state.db", tmp_path / "audit.jsonl"
    return Manager.from_text(RULES, clock=VirtualClock(100), journal=journal, audit=audit, dispatch=False)


def test_reset_journal_starts_afresh_once_and_records_what_was_lost(tmp_path: Path) -> None:
    two_lives(tmp_path)
    (tmp_path / "state.db-wal").unlink()
    before = read_audit(tmp_path / "audit.jsonl")
    m = again(tmp_path, 160, reset_journal=True).start()
    assert m.request("Rec").permitted is True  # forgotten, on purpose -- and said so:
    assert m.lineage == m.run_id != before[0]["run"]
    m.close()
    records = read_audit(tmp_path / "audit.jsonl")
    assert records[: len(before)] == before and [r["seq"] for r in records] == list(
        range(1, len(records) + 1)
    )
    reset, restored = records[len(before)], records[len(before) + 1]
    assert reset["kind"] == "journal-reset" and "state.db-wal file is gone" in reset["reason"]
    assert reset["lineage"] == before[0]["run"] and reset["last_seq"] == before[-1]["seq"]
    assert reset["journal"]["lineage"] == before[0]["run"]  # what the main file still said
    assert restored["kind"] == "restored" and restored["from"] is None and restored["lineage"] == m.run_id
    with pytest.raises(ConfigurationError, match="nothing to reset"):  # once: the journal is sound now
        again(tmp_path, 170, reset_journal=True)
    m = again(tmp_path, 170).start()  # and it is the new lineage's journal
    assert m.lineage == restored["lineage"]
    m.close()


def test_a_log_with_a_reset_is_read_by_conforms_and_the_timeline(tmp_path: Path) -> None:
    from cosleec.cli.main import main
    from cosleec.views.timeline import Timeline

    die_after(tmp_path, FORBID)
    (tmp_path / "state.db-wal").unlink()
    m = again(tmp_path, 160, reset_journal=True).start()
    m.event("Trigger")
    m.clock.set(170)  # type: ignore[attr-defined]
    m.tick()
    m.close()
    log = tmp_path / "audit.jsonl"
    assert main(["conforms", str(tmp_path / "rules.sleec"), str(log)]) in (0, 1)  # judged, not refused (2)
    timeline = Timeline.read(log)
    assert timeline.counts["journal-reset"] == 1 and timeline.ignored == {"journal-reset": 1}
    # the reset run's ids start again: its obligations are its own, not merged with the old run's
    from cosleec.runtime import read_audit

    made = {(r["run"], r["id"]) for r in read_audit(log) if r["kind"] == "obligation"}
    assert len(timeline.bars) == len(made) == 4  # two of each run, none lost to a merge


def test_reset_journal_needs_a_journal_the_manager_refused(tmp_path: Path) -> None:
    die_after(tmp_path, FORBID)
    with pytest.raises(ConfigurationError, match="nothing to reset"):
        again(tmp_path, 160, reset_journal=True)
    assert (
        again(tmp_path, 160).start().request("Rec").permitted is False
    )  # the refusal to reset changed nothing
    with pytest.raises(ConfigurationError, match="only with a journal"):
        Manager.from_text(RULES, reset_journal=True)


def test_a_clean_close_or_a_checkpoint_by_another_program_is_not_a_lost_wal(tmp_path: Path) -> None:
    import sqlite3

    (tmp_path / "rules.sleec").write_text(RULES)
    m = again(tmp_path, 100)
    m.update(consent=False)
    m.event("Watch")
    m.close()
    assert not (tmp_path / "state.db-wal").exists()  # SQLite removes it on a clean close
    m = again(tmp_path, 101).start()
    assert m.request("Rec").permitted is False
    m.close()
    die_after(tmp_path, 'm.event("Trigger")')
    sqlite3.connect(tmp_path / "state.db").close()  # copies the WAL into the database, deletes it
    m = again(tmp_path, 102).start()  # the audit log shows nothing was lost
    assert m.request("Rec").permitted is False
    m.close()


def test_one_audit_log_has_one_writer(tmp_path: Path) -> None:
    from cosleec.errors import UserError
    from cosleec.runtime import AuditLog

    log = tmp_path / "audit.jsonl"
    m = Manager.from_text(RULES, clock=VirtualClock(0), audit=log, journal=tmp_path / "a.db")
    with pytest.raises(
        UserError, match=r"audit log is in use by another writer \(process \d+, this one\)"
    ) as e:
        Manager.from_text(RULES, clock=VirtualClock(0), audit=log, journal=tmp_path / "b.db")
    assert e.value.where == str(log) and "give each Manager its own audit log" in e.value.hint
    with pytest.raises(UserError, match="in use by another writer"):
        Manager.from_text(RULES, clock=VirtualClock(0), audit=log)  # nor one without a journal
    with pytest.raises(UserError, match="in use by another writer"):
        AuditLog(log)
    m.event("Watch")
    m.close()
    other = Manager.from_text(RULES, clock=VirtualClock(0), audit=log)  # free once it closed
    other.event("Watch")
    other.close()
    assert [r["seq"] for r in read_audit(log)] == list(range(1, len(read_audit(log)) + 1))


def test_one_audit_log_has_one_writer_across_processes(tmp_path: Path) -> None:
    from cosleec.errors import UserError

    log = tmp_path / "audit.jsonl"
    script = f"""
import sys
from cosleec.runtime import Manager
m = Manager.from_text({RULES!r}, audit={str(log)!r})
print("open", flush=True)
sys.stdin.read()
m.close()
"""
    p = subprocess.Popen(
        [sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert p.stdout is not None and p.stdout.readline() == "open\n"
        with pytest.raises(UserError, match=f"in use by another writer \\(process {p.pid}\\)"):
            Manager.from_text(RULES, audit=log)
    finally:
        p.communicate("", timeout=30)
    Manager.from_text(RULES, audit=log).close()


def test_a_manager_refused_at_construction_frees_its_audit_log(tmp_path: Path) -> None:
    m = Manager.from_text(RULES, clock=VirtualClock(0), journal=tmp_path / "state.db")
    with pytest.raises(JournalError, match="in use by another Manager") as e:
        Manager.from_text(
            RULES, clock=VirtualClock(0), journal=tmp_path / "state.db", audit=tmp_path / "b.jsonl"
        )
    # the refused Manager lives on in the traceback (as in any caller that keeps the error):
    # its audit log is closed all the same
    assert e.traceback
    Manager.from_text(RULES, clock=VirtualClock(0), audit=tmp_path / "b.jsonl").close()
    m.close()


# ------------------------------------------------------------ a full disk (issue 28, finding 13)
# A real full disk: a 1 MiB tmpfs mounted in a mount namespace of the test's own (unshare), the
# audit log or the journal on it, filled to the last byte once the Manager runs.

FULL = """
import json, os, sys
from cosleec.runtime import JournalError, Manager, VirtualClock, read_audit
full, disk, on_it = sys.argv[1], sys.argv[2], sys.argv[3]
where = {"journal": (disk, full), "audit": (full, disk)}[on_it]
rules = sys.stdin.read()
out = {}

def manager(t):
    return Manager.from_text(rules, clock=VirtualClock(t), journal=where[1] + "/state.db",
                             audit=where[0] + "/audit.jsonl", dispatch=False)

m = manager(100)
m.update(consent=False)
m.event("Watch")
fd = os.open(full + "/filler", os.O_WRONLY | os.O_CREAT)
try:
    while True:
        os.write(fd, b"x" * 256)
except OSError as e:
    out["filled"] = e.strerror
os.close(fd)
try:
    for _ in range(10_000):
        m.event("Trigger")
        m.event("Act")
except JournalError as e:
    out["error"] = e.render()
out["refuses"] = m.request("Rec").permitted is False
try:
    m.close()
    out["close"] = "ok"
except BaseException as e:
    out["close"] = f"{type(e).__name__}: {e}"
os.unlink(full + "/filler")  # space is freed: a new Manager goes on from the journal
try:
    m = manager(101)
    out["restarted"] = m.request("Rec").permitted is False
    m.close()
except BaseException as e:
    out["restarted"] = f"{type(e).__name__}: {e}"
seqs = [r["seq"] for r in read_audit(where[0] + "/audit.jsonl")]
out["seq"] = seqs == list(range(1, len(seqs) + 1))
print(json.dumps(out))
"""


def on_a_full_disk(tmp_path: Path, on_it: str) -> dict[str, Any]:
    """Run :data:`FULL` with the journal or the audit log (``on_it``) on a disk that fills up."""
    import shutil

    unshare = shutil.which("unshare")
    if unshare is None or subprocess.run([unshare, "--mount", "--map-root-user", "true"]).returncode != 0:
        pytest.skip("a real full disk needs `unshare --mount --map-root-user` (a tmpfs of the test's own)")
    full, disk = tmp_path / "full", tmp_path / "disk"
    full.mkdir()
    disk.mkdir()
    mount = f'mount -t tmpfs -o size=1m tmpfs {full} && exec "$@"'
    args = [str(full), str(disk), on_it]
    p = subprocess.run(
        [unshare, "--mount", "--map-root-user", "sh", "-c", mount, "sh", sys.executable, "-c", FULL, *args],
        input=RULES,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 0, p.stderr
    out: dict[str, Any] = json.loads(p.stdout)
    assert out["filled"] == "No space left on device"
    return out


def test_a_full_audit_disk_is_named_and_close_does_not_raise(tmp_path: Path) -> None:
    out = on_a_full_disk(tmp_path, "audit")
    assert "cannot write the audit log: No space left on device" in out["error"]
    assert out["close"] == "ok"  # before: OSError [Errno 28] No space left on device
    assert out["refuses"] is True and out["restarted"] is True and out["seq"] is True


def test_a_full_journal_disk_is_named_and_the_journal_restarts(tmp_path: Path) -> None:
    out = on_a_full_disk(tmp_path, "journal")
    # before: "cannot write the journal: cannot rollback - no transaction is active"
    assert "cannot write the journal: the disk is full (database or disk is full)" in out["error"]
    assert "hint: free space on the disk that holds" in out["error"]
    assert out["close"] == "ok"
    # the running mark could not be cleared: its -wal file was kept, so the restart is no "lost WAL"
    assert out["refuses"] is True and out["restarted"] is True and out["seq"] is True
