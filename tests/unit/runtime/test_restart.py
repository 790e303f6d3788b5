"""Restarting on a journal: an obligation in force goes on as if the Manager had not stopped.

After a reboot a monotonic clock starts again, so a journal's times are shifted by what the
new boot's clock says now less the time the Manager was down (``Restore``): an obligation's
start, window and deadline, its own event's window and its `else` branches' windows alike,
and journaled so (a second restart in the same boot shifts nothing). And an `else` branch
partly met when the Manager stops is still partly met after it starts again.
"""

from __future__ import annotations

import functools
import json
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from cosleec.records import Kind
from cosleec.runtime import Manager, MonotonicClock, VirtualClock


class Uptime(MonotonicClock):
    """A monotonic clock reading ``t`` (a machine's uptime), set by the test."""

    def __init__(self, t: float) -> None:
        self.t = t

    def now(self) -> float:
        return self.t


def rebooted(journal: Path) -> None:
    """Make the journal's last state one of another boot, down for a second since."""
    db = sqlite3.connect(journal)
    state = json.loads(db.execute("SELECT value FROM meta WHERE key = 'state'").fetchone()[0])
    state.update(boot="another boot", wall=state["wall"] - 1)
    db.execute("UPDATE meta SET value = ? WHERE key = 'state'", (json.dumps(state),))
    db.commit()
    db.close()


def on_uptime(journal_dir: Path, t: float) -> Manager:
    """A Manager of ``rules.sleec`` in ``journal_dir`` on its journal, its clock reading ``t``."""
    return Manager.from_file(
        journal_dir / "rules.sleec", clock=Uptime(t), journal=journal_dir / "state.db", dispatch=False
    )


ELSE_RULES = """def_start
 event Trigger event Act event Alt event Help
def_end
rule_start
 R1 when Trigger then Act within 5 seconds otherwise Help
 R2 when Trigger then Act within 5 seconds else Alt within 20 seconds otherwise Help
rule_end
"""


@pytest.mark.parametrize("settle", ["Act", "Alt"])
def test_after_a_reboot_an_obligation_is_met_in_its_shifted_window(tmp_path: Path, settle: str) -> None:
    """A reboot shifts an obligation's whole window into the new boot's clock: its own
    event's window (``own_hi``, which decides whether ``Act`` counts) and its ``else``
    branches' windows too, not only its start and deadline. Here the new boot's uptime is
    far ahead of the old one's: ``Act`` 3 s after the restart fulfils R1 (it did not: the
    unshifted own window had ended long before), and ``Alt`` fulfils R2's ``else`` (it did
    not: the unshifted branch window had too)."""
    (tmp_path / "rules.sleec").write_text(ELSE_RULES)
    m = on_uptime(tmp_path, 100)
    m.start()
    m.event("Trigger")  # R1: Act by 105; R2: Act by 105, else Alt by 120
    m.close()
    rebooted(tmp_path / "state.db")
    # the new boot's uptime, 4,899 s ahead of the old clock at the stop (1 s down)
    m = on_uptime(tmp_path, 5000)
    m.start()
    held = {t.rule: t for t in m.outstanding()}
    near = functools.partial(pytest.approx, abs=0.5)  # (the time down is read from the wall clock)
    assert (held["R1"].lo, held["R1"].own_hi, held["R1"].hi) == near((4999, 5004, 5004))
    ((alt, lo, hi),) = held["R2"].branches[0]
    assert (held["R2"].own_hi, held["R2"].hi, alt, lo, hi) == (
        near(5004),
        near(5019),
        "Alt",
        near(4999),
        near(5019),
    )
    m.clock.t = 5002  # type: ignore[attr-defined]
    m.event(settle)
    m.clock.t = 5100  # type: ignore[attr-defined]
    fallbacks = m.tick()
    status = {t.rule: t.status for t in held.values()}
    assert status == {"R1": "fulfilled" if settle == "Act" else "violated", "R2": "fulfilled"}
    assert m.stats["violations"] == (settle == "Alt")
    assert [(d.rule, d.fallback) for d in fallbacks] == ([("R1", True)] if settle == "Alt" else [])
    m.close()


def test_a_restart_in_the_new_boot_finds_the_windows_shifted(tmp_path: Path) -> None:
    """The shifted windows are journaled by the restore's own step, with the new boot's
    clock: a second restart in the same boot (a crash loop, a service restarted after a
    reboot: no shift then) finds them as this boot's clock reads them, not the old boot's."""
    (tmp_path / "rules.sleec").write_text(ELSE_RULES)

    def windows(m: Manager) -> dict[str, tuple[object, ...]]:
        return {t.rule: (t.start, t.lo, t.own_hi, t.hi, t.branches) for t in m.outstanding()}

    m = on_uptime(tmp_path, 100)
    m.start()
    m.event("Trigger")
    m.close()
    rebooted(tmp_path / "state.db")
    m = on_uptime(tmp_path, 5000)
    m.start()
    first = windows(m)
    assert first["R1"][1] == pytest.approx(4999, abs=0.5)
    m.close()
    m = on_uptime(tmp_path, 5001)  # the same boot, a second later
    m.start()
    assert windows(m) == first
    m.clock.t = 5002  # type: ignore[attr-defined]
    m.event("Act")
    m.clock.t = 5100  # type: ignore[attr-defined]
    assert m.tick() == [] and m.stats["violations"] == 0
    m.close()


def then_c(m: Manager, clock: VirtualClock) -> None:
    """After B at 3 s: C at 6 s completes R4's `else`; by 30 s nothing was violated."""
    clock.set(6)
    m.event("C")
    clock.set(30)
    assert m.tick() == [] and m.stats["violations"] == 0


PARTS = """def_start event T event A event B event C def_end
rule_start
R4 when T then A within 5 seconds else {B within 20 seconds and C within 20 seconds}
rule_end
"""


@pytest.mark.parametrize("restart", [False, True])
def test_an_else_branch_partly_met_stays_so_across_a_restart(tmp_path: Path, restart: bool) -> None:
    """B then C meet R4's `else`; a restart between them (the journal) must not forget B:
    the obligation is fulfilled by C either way. Meeting B is a new state of the obligation:
    it has its record (``met``), which the journal keeps."""
    clock = VirtualClock()
    heard: list[dict[str, object]] = []

    def manager() -> Manager:
        m = Manager.from_text(PARTS, clock=clock, journal=tmp_path / "state.db", dispatch=False)
        m.subscribe(lambda ev: heard.append(ev.data) if ev.kind == Kind.OBLIGATION else None)
        return m

    m = manager()
    m.start()
    m.event("T")
    clock.set(3)
    m.event("B")
    assert [(r["status"], r["met"]) for r in heard] == [("pending", [[]]), ("pending", [[0]])]
    if restart:
        m.close()
        m = manager()
        m.start()
        assert [t.met for t in m.outstanding()] == [([0],)]
    then_c(m, clock)
    assert (heard[-1]["status"], heard[-1]["by"], heard[-1]["met"]) == ("fulfilled", "C", [[0, 1]])
    m.close()


def test_an_else_branch_partly_met_survives_a_kill(tmp_path: Path) -> None:
    """As above, the Manager killed with SIGKILL right after B (its step committed)."""
    script = f"""
import os, signal
from cosleec.runtime import Manager, VirtualClock
clock = VirtualClock()
m = Manager.from_text({PARTS!r}, clock=clock, journal={str(tmp_path / "state.db")!r}, dispatch=False)
m.start()
m.event("T")
clock.set(3)
m.event("B")
os.kill(os.getpid(), signal.SIGKILL)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert done.returncode == -9, done.stderr
    clock = VirtualClock(3)
    m = Manager.from_text(PARTS, clock=clock, journal=tmp_path / "state.db", dispatch=False)
    m.start()
    assert [t.met for t in m.outstanding()] == [([0],)]
    then_c(m, clock)
    m.close()
