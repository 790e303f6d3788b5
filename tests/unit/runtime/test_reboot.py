"""Restarting after a reboot: what the journal kept is moved into the new boot's clock whole.

A monotonic clock starts again at a reboot, so a journal's times are shifted by what the
new boot's clock says now less the time the Manager was down (``Restore``): an obligation's
start, window and deadline, its own event's window and its `else` branches' windows alike.
"""

from __future__ import annotations

import functools
import json
import sqlite3
from pathlib import Path

import pytest

from cosleec.runtime import Manager, MonotonicClock


class Uptime(MonotonicClock):
    """A monotonic clock reading ``t`` (a machine's uptime), set by the test."""

    def __init__(self, t: float) -> None:
        self.t = t

    def now(self) -> float:
        return self.t


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

    def manager(t: float) -> Manager:
        return Manager.from_file(
            tmp_path / "rules.sleec", clock=Uptime(t), journal=tmp_path / "state.db", dispatch=False
        )

    m = manager(100)
    m.start()
    m.event("Trigger")  # R1: Act by 105; R2: Act by 105, else Alt by 120
    m.close()
    db = sqlite3.connect(tmp_path / "state.db")
    state = json.loads(db.execute("SELECT value FROM meta WHERE key = 'state'").fetchone()[0])
    state.update(boot="another boot", wall=state["wall"] - 1)  # down for a second, then rebooted
    db.execute("UPDATE meta SET value = ? WHERE key = 'state'", (json.dumps(state),))
    db.commit()
    db.close()
    m = manager(5000)  # the new boot's uptime, 4,899 s ahead of the old clock at the stop (1 s down)
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
