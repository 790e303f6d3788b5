"""Under threads: no dispatch of a forbidden event, and audit times that never go back.

Issue 28, findings 3 and 6. Many threads trigger a rule that obliges ``Snap``, one that
forbids it and one that lifts the ban (a higher-priority rule cancels the forbidding
one), while others ask ``request("Snap")``. An independent oracle replays the audit log
in ``seq`` order and checks, at the record each ``Snap`` dispatch was admitted after
(``task-done.checked``), that no prohibition of ``Snap`` was in force -- what ``request``
would have answered at that instant. The clock is frozen, so a prohibition ends only by
a cancellation the log records: the oracle needs no clock arithmetic.

``COSLEEC_THREAD_OPS`` sets the operations per thread (300 in CI; 20000 on demand).
"""

from __future__ import annotations

import itertools
import os
import random
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cosleec.cli.main import main
from cosleec.runtime import AuditLog, Manager, MonotonicClock, VirtualClock, read_audit

OPS = int(os.environ.get("COSLEEC_THREAD_OPS", "300"))
THREADS = 6

RULES = """def_start
  event Motion event Visitor event AllClear event Snap event Wave
def_end
rule_start
R1 when Motion then Snap within 100 seconds
R2 when Visitor then not Snap within 50 seconds
R3 when AllClear then Wave within 100 seconds
rule_end
"""


def hammer(work: Callable[[random.Random], None], threads: int = THREADS) -> None:
    """Run ``work`` from ``threads`` threads at once, each with its own seeded generator."""
    errors: list[BaseException] = []
    start = threading.Barrier(threads)

    def run(seed: int) -> None:
        rng = random.Random(seed)
        start.wait()
        try:
            work(rng)
        except BaseException as e:  # reported below: a thread's failure must fail the test
            errors.append(e)

    pool = [threading.Thread(target=run, args=(i,)) for i in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    assert errors == []


def snap_in_force(records: list[dict[str, Any]]) -> list[tuple[int, list[int]]]:
    """The oracle: for each Snap dispatch, (checked, the prohibitions of Snap in force then)."""
    checks: dict[int, list[int]] = {}
    for r in records:
        if r["kind"] == "task-done" and r["event"] == "Snap":
            checks.setdefault(r["checked"], []).append(r["decision"])
    forbidding: set[int] = set()
    out: list[tuple[int, list[int]]] = [(c, []) for c in checks.pop(0, [])]
    for r in records:
        if r["kind"] == "obligation" and r["negated"] and r["event"] == "Snap":
            if r["status"] == "pending":
                forbidding.add(r["id"])
            else:
                forbidding.discard(r["id"])
        for _ in checks.pop(r["seq"], []):
            out.append((r["seq"], sorted(forbidding)))
    assert checks == {}, "a dispatch names a record that is not in the log"
    return out


def test_no_dispatch_of_a_forbidden_event_under_threads(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m = Manager.from_text(RULES, clock=VirtualClock(0.0), audit=AuditLog(log), priorities=["R3 > R2"])
    m.capability("Snap")(lambda ob, d: m.event("Snap"))
    m.capability("Wave")(lambda ob, d: m.event("Wave"))
    m.start()

    def work(rng: random.Random) -> None:
        for _ in range(OPS):
            roll = rng.random()
            if roll < 0.45:
                m.event("Motion")
            elif roll < 0.65:
                m.event("Visitor")
            elif roll < 0.8:
                m.event("AllClear")
            else:
                m.request("Snap")

    hammer(work)
    m.event("AllClear")  # the last ban is lifted: every action still held runs
    m.close()
    records = sorted(read_audit(log), key=lambda r: r["seq"])
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    checks = snap_in_force(records)
    assert len(checks) > OPS // 10  # Snap ran often ...
    assert [c for c in checks if c[1]] == []  # ... and never while forbidden
    assert any(r["kind"] == "held" for r in records)  # the race was there to lose
    status: dict[int, str] = {}
    for r in records:
        if r["kind"] == "obligation" and r["rule"] == "R1":
            status[r["id"]] = r["status"]
    assert set(status.values()) == {"fulfilled"}  # no permitted action left unrun


def test_audit_times_never_go_back_under_threads_and_conforms_accepts_the_log(
    tmp_path: Path, capsys: Any
) -> None:
    log = tmp_path / "audit.jsonl"
    rules = tmp_path / "rules.sleec"
    rules.write_text(RULES, encoding="utf-8")
    m = Manager.from_text(RULES, clock=MonotonicClock(), audit=AuditLog(log), priorities=["R3 > R2"])
    m.capability("Snap")(lambda ob, d: m.event("Snap"))
    m.capability("Wave")(lambda ob, d: m.event("Wave"))
    m.start()

    def work(rng: random.Random) -> None:
        for _ in range(OPS):
            m.event(rng.choice(("Motion", "Visitor", "AllClear")))

    hammer(work)
    m.close()
    records = sorted(read_audit(log), key=lambda r: r["seq"])
    times = [r["time"] for r in records if r["kind"] != "decision"]  # (a fallback's is its deadline)
    back = [(a, b) for a, b in itertools.pairwise(times) if b < a]
    assert back == []
    assert main(["conforms", str(rules), str(log), "--priority", "R3 > R2"]) in (0, 1)
    assert "time goes back" not in capsys.readouterr().err


class Ticking:
    """A clock that moves on a second at every reading: a step that read it twice
    would stamp its records with two times."""

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        self.t += 1.0
        return self.t


def test_every_record_of_a_step_has_the_step_time() -> None:
    m = Manager.from_text(
        "def_start event E event F event G def_end rule_start R1 when E then F within 2 seconds rule_end",
        clock=Ticking(),
    )
    records: list[Any] = []
    m.subscribe(records.append)
    m.start(check=False)  # no implementation of F: its deadline is missed
    m.event("E")
    m.event("G")  # the step that judges F's deadline (violated) and then records G
    times = [r.time for r in records if r.kind != "decision"]
    assert times == sorted(times)
    g = next(r for r in records if r.kind == "event" and r.data["event"] == "G")
    violated = next(r for r in records if r.kind == "obligation" and r.data["status"] == "violated")
    assert violated.time == g.time  # one step, one time
    m.close()
