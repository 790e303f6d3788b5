"""``cosleec timeline``: a recorded run over time, drawn by the real matplotlib and Plotly.

The model is checked exactly on hand-made records (every outcome, an ``otherwise`` chain,
layer bands and their interval ends, measure steps, every record kind), then on the demo's
real audit trail and on a real MCAP recording of the same run. The pictures are real
files: a PNG with its signature, an SVG that parses, names the rules and is the same bytes
twice; the HTML holds Plotly inline and renders in Debian's Chromium (Playwright) with no
request leaving the page. A random run of the largest corpus file (624 rules) draws in all
three formats. Last, the command's mistakes: one message, exit 1, no traceback.

Tools missing locally are skipped; under CI (``$CI``) they fail, as ``scripts/setup --dev``
installs them.
"""

from __future__ import annotations

import json
import os
import random
import re
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from cosleec.cli.main import main
from cosleec.demo import run as run_demo
from cosleec.errors import UserError
from cosleec.nodes import McapRecorder
from cosleec.runtime import AuditLog, Manager, RuleSet, VirtualClock
from cosleec.testing import CHROMIUM, CHROMIUM_ARGS, corpus_dir
from cosleec.views import Band, Link, MarkerKind, Outcome, Timeline, layout, timeline_html, timeline_image
from cosleec.views.timeline_layout import steps

LARGEST = (
    "a-l-partis__SLEEC-ADAPT__AgentAdaption__agentAdaptionCode__scalability__sleecRules__rulestest625.sleec"
)
ARGS = list(CHROMIUM_ARGS)


def need(module: str) -> None:
    """Skip without ``module`` locally; under CI, fail (the dev setup installs it)."""
    try:
        __import__(module)
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail(f"{module} is missing under CI: scripts/setup --dev installs the timeline extra")
        pytest.skip(f"{module} is not installed here (pip install 'cosleec[timeline]')")


# ---------------------------------------------------------------------- hand-made records


def ob(
    id: int,
    rule: str,
    event: str,
    status: str,
    start: float,
    deadline: float | None,
    *,
    at: float | None = None,
    late: tuple[float, ...] = (),
    decision: int = 1,
    negated: bool = False,
    depth: int = 0,
    time: float | None = None,
) -> dict[str, Any]:
    """An ``obligation`` record shaped as ``Tracked.to_json`` writes it."""
    return {
        "kind": "obligation",
        "time": start if time is None else time,
        "type": "obligation",
        "id": id,
        "decision": decision,
        "clause": 0,
        "causal": 1,
        "obligation": {"event": event, "negated": negated, "within_s": None, "otherwise": None},
        "rule": rule,
        "event": event,
        "negated": negated,
        "start": start,
        "window": [start, deadline],
        "deadline": deadline,
        "instance": decision,
        "status": status,
        "at": at,
        "by": None,
        "late": list(late),
        "refused": 0,
        "depth": depth,
        "branches": [],
        "met": [],
    }


def dec(
    id: int, rule: str, t: float, clause: int | None, *, event: str = "E", violated: int | None = None
) -> dict[str, Any]:
    """A ``decision`` record."""
    return {
        "kind": "decision",
        "time": t,
        "id": id,
        "event": "otherwise" if violated is not None else event,
        "rule": rule,
        "clause": clause,
        "layer": None if not clause else f"{rule}.{clause}",
        "obligations": [{"event": "A", "negated": False, "within_s": 10.0}],
        "missing": ["m"] if clause is None else [],
        "explanation": "because",
        "violated": violated,
    }


def layers(t: float, *switches: tuple[str, str | None, str | None]) -> dict[str, Any]:
    return {
        "kind": "layers",
        "time": t,
        "active": [],
        "switches": [{"rule": r, "from": a, "to": b} for r, a, b in switches],
        "semantics": "last-wins",
        "version": 1,
    }


RECORDS: list[dict[str, Any]] = [
    {
        "kind": "options",
        "time": 0.0,
        "semantics": "last-wins",
        "priorities": [],
        "priority_semantics": "cancel",
    },
    {"kind": "context", "time": 0.0, "values": {"m": False, "n": 3, "s": "low"}, "version": 1},
    layers(0.0, ("R1", "?", None), ("R2", "?", None)),
    layers(2.0, ("R1", None, "R1.1")),
    layers(2.0, ("R2", None, "R2.2")),  # switched in and out at one instant: no band
    layers(2.0, ("R2", "R2.2", None)),
    {"kind": "event", "time": 2.0, "event": "E", "causal": 1},
    dec(1, "R1", 2.0, 1),
    ob(1, "R1", "A", "pending", 2.0, 12.0),
    ob(2, "R1", "B", "pending", 2.0, 4.0),
    {"kind": "context", "time": 3.0, "values": {"m": True, "n": 3}, "version": 2},  # n unchanged
    ob(1, "R1", "A", "fulfilled", 2.0, 12.0, at=5.0, time=5.0),
    ob(2, "R1", "B", "violated", 2.0, 4.0, at=4.0, time=6.0),  # judged late: settled at its deadline
    dec(2, "R1", 4.0, 1, violated=2),
    ob(3, "R1", "C", "pending", 4.0, 9.0, decision=2, depth=1, time=6.0),
    ob(3, "R1", "C", "fulfilled", 4.0, 9.0, at=7.0, decision=2, depth=1, time=7.0),
    dec(3, "R2", 6.0, 0),
    ob(4, "R2", "D", "violated", 6.0, 8.0, at=8.0, decision=3, time=8.0),
    ob(4, "R2", "D", "violated", 6.0, 8.0, at=8.0, late=(9.5,), decision=3, time=9.5),
    dec(4, "R3", 7.0, None),
    ob(5, "R3", "F", "refused", 7.0, 17.0, at=7.0, decision=4),
    ob(6, "R4", "F", "pending", 7.0, 20.0, decision=5, negated=True),
    {
        "kind": "conflict",
        "time": 7.0,
        "event": "F",
        "at": 7.0,
        "obligation": 5,
        "prohibition": 6,
        "between": ["R3", "R4"],
        "clauses": [None, 0],
        "resolution": "prohibition-wins",
        "winner": "R4",
        "explanation": "R3 requires F and R4 forbids F",
    },
    ob(7, "R4", "G", "pending", 7.0, 30.0, decision=5),
    ob(8, "R4", "H", "pending", 7.0, 30.0, decision=5),
    {
        "kind": "conflict",
        "time": 7.0,
        "event": "G",
        "at": 7.0,
        "obligation": 7,
        "prohibition": 6,
        "between": ["R4", "R4"],
        "resolution": "conflict-aware",
        "winner": "R4",
        "explanation": "x",
    },
    ob(9, "R5", "J", "cancelled", 7.5, 20.0, at=8.5, decision=6, time=8.5),
    ob(10, "R5", "K", "withdrawn", 7.5, 20.0, at=8.5, decision=6, time=8.5),
    ob(11, "R6", "L", "pending", 8.0, None, decision=7),  # untimed, still owed at the end
    ob(12, "R6", "M", "fulfilled", 8.0, None, at=8.25, decision=7),  # untimed, met
    ob(13, "R6", "N", "respected", 8.0, 9.0, at=9.0, decision=7, negated=True),
    ob(14, "R6", "P", "future-status", 8.0, 9.0, decision=7),
    {"kind": "refused", "time": 8.0, "event": "F", "by": ["R4"], "obligations": [6], "reason": "forbidden"},
    {"kind": "rejected", "time": 8.0, "reason": "unknown event 'Zap'", "what": "event", "hint": "declare it"},
    {"kind": "task-done", "time": 8.0, "rule": "R1", "decision": 1},
    {
        "kind": "task-failed",
        "time": 8.1,
        "rule": "R2",
        "decision": 3,
        "what": "task",
        "event": "D",
        "error": "boom",
    },
    {"kind": "held", "time": 8.2, "decision": 3, "rule": "R2", "events": ["D"], "by": ["R4"], "opens": None},
    {"kind": "dispatch", "time": 8.3, "decision": {"id": 3}},
    {
        "kind": "withheld",
        "time": 8.4,
        "decision": 5,
        "rule": "R4",
        "reason": "nothing it required is still owed",
    },
    {
        "kind": "cancelled",
        "time": 8.5,
        "instance": 6,
        "rule": "R5",
        "by": "R1",
        "at": 8.5,
        "priority": "cancel",
        "obligations": [9],
    },
    {"kind": "semantics", "time": 8.6, "semantics": "nested", "before": ["R1.1"], "active": ["R1.2"]},
    {"kind": "context", "time": 8.7, "values": {"m": None}, "stale": ["m"]},
    {"kind": "reloaded", "time": 8.8, "added": [], "removed": []},
    {"kind": "from-the-future", "time": 8.9},
    {"kind": "context", "time": 10.0, "values": {"s": "high"}, "version": 3},
]


@pytest.fixture(scope="module")
def tl() -> Timeline:
    return Timeline.from_records(RECORDS, "hand.jsonl")


def test_every_outcome_is_a_bar_from_trigger_to_deadline(tl: Timeline) -> None:
    got = {b.id: (b.rule, b.label, b.start, b.end, b.outcome, b.at, b.late, b.open) for b in tl.bars}
    assert got == {
        1: ("R1", "A #1", 2.0, 12.0, Outcome.FULFILLED, 5.0, None, False),
        2: ("R1", "B #2", 2.0, 4.0, Outcome.VIOLATED, 4.0, None, False),
        3: ("R1", "C #3", 4.0, 9.0, Outcome.FULFILLED, 7.0, None, False),
        4: ("R2", "D #4", 6.0, 8.0, Outcome.LATE, 8.0, 9.5, False),
        5: ("R3", "F #5", 7.0, 17.0, Outcome.BLOCKED, 7.0, None, False),  # blocked says more than conflict
        6: ("R4", "not F #6", 7.0, 20.0, Outcome.CONFLICT, None, None, False),
        7: ("R4", "G #7", 7.0, 30.0, Outcome.CONFLICT, None, None, False),
        8: ("R4", "H #8", 7.0, 30.0, Outcome.PENDING, None, None, False),
        9: ("R5", "J #9", 7.5, 20.0, Outcome.CANCELLED, 8.5, None, False),
        10: ("R5", "K #10", 7.5, 20.0, Outcome.WITHDRAWN, 8.5, None, False),
        11: ("R6", "L #11", 8.0, 10.0, Outcome.PENDING, None, None, True),  # no deadline: to the run's end
        12: ("R6", "M #12", 8.0, 8.25, Outcome.FULFILLED, 8.25, None, False),  # no deadline: to when met
        13: ("R6", "not N #13", 8.0, 9.0, Outcome.RESPECTED, 9.0, None, False),
        14: ("R6", "P #14", 8.0, 9.0, Outcome.OTHER, None, None, False),
    }
    assert tl.bar((0, 14)).status == "future-status"
    assert tl.bar((0, 3)).depth == 1 and tl.bar((0, 3)).decision == 2
    assert all(b.deadline == (None if b.id in (11, 12) else b.end) for b in tl.bars)


def test_an_otherwise_chain_links_the_missed_obligation_to_its_fallbacks(tl: Timeline) -> None:
    assert tl.links == (Link(parent=(0, 2), child=(0, 3), time=4.0),)


def test_bands_cover_start_to_end_and_an_instant_layer_has_none(tl: Timeline) -> None:
    assert tl.bands == (
        Band(rule="R1", layer="R1.1", start=2.0, end=8.6),  # until the semantics switch
        Band(rule="R1", layer="R1.2", start=8.6, end=10.0),  # then to the end of the run
    )
    assert [b.clause for b in tl.bands] == [1, 2]
    assert Band(rule="R9", layer="?", start=0, end=1).clause is None


def test_a_band_is_half_open_and_an_undetermined_layer_is_drawn() -> None:
    records = [
        layers(0.0, ("R1", None, "R1.1")),
        layers(1.0, ("R1", "R1.1", "?")),
        layers(2.5, ("R1", "?", None)),
        layers(2.5, ("R1", None, "R1.1")),
        {"kind": "event", "time": 4.0, "event": "E"},
        layers(4.0, ("R2", None, "R2.1")),  # at the very end: active for no time, no band
    ]
    got = Timeline.from_records(records).bands
    assert [(b.layer, b.start, b.end) for b in got] == [
        ("R1.1", 0.0, 1.0),
        ("?", 1.0, 2.5),
        ("R1.1", 2.5, 4.0),
    ]


def test_measures_are_steps_of_their_changes(tl: Timeline) -> None:
    series = {s.name: s.points for s in tl.series}
    assert series == {
        "m": ((0.0, False), (3.0, True), (8.7, None)),
        "n": ((0.0, 3),),  # set again to 3: no change
        "s": ((0.0, "low"), (10.0, "high")),
    }
    xs, ys, ticks = steps(next(s for s in tl.series if s.name == "m"), tl.end)
    assert xs == [0.0, 3.0, 3.0, 8.7, 8.7, 10.0]
    assert ys == [0.0, 0.0, 1.0, 1.0, None, None]
    assert ticks == [(0.0, "false"), (1.0, "true")]
    xs, ys, ticks = steps(next(s for s in tl.series if s.name == "s"), 12.0)
    assert (xs, ys, ticks) == ([0.0, 10.0, 10.0, 12.0], [0.0, 0.0, 1.0, 1.0], [(0.0, "low"), (1.0, "high")])
    xs, ys, ticks = steps(next(s for s in tl.series if s.name == "n"), 10.0)
    assert (xs, ys, ticks) == ([0.0, 10.0], [3.0, 3.0], [])


def test_triggers_decisions_and_every_other_record_are_marked(tl: Timeline) -> None:
    marks = [(m.kind, m.time, m.rule, m.label) for m in tl.markers]
    assert (MarkerKind.TRIGGER, 2.0, None, "E") in marks
    assert (MarkerKind.DECISION, 2.0, "R1", "R1.1") in marks
    assert (MarkerKind.OTHERWISE, 4.0, "R1", "otherwise #2") in marks
    assert (MarkerKind.DECISION, 6.0, "R2", "default") in marks
    assert (MarkerKind.UNDETERMINED, 7.0, "R3", "?") in marks
    assert (MarkerKind.CONFLICT, 7.0, "R3", "conflict F") in marks
    assert (MarkerKind.CONFLICT, 7.0, "R4", "conflict F") in marks
    assert (MarkerKind.REFUSED, 8.0, "R4", "refused F") in marks
    assert (MarkerKind.REJECTED, 8.0, None, "rejected") in marks
    assert (MarkerKind.TASK_FAILED, 8.1, "R2", "D failed") in marks
    assert (MarkerKind.HELD, 8.2, "R2", "held") in marks
    assert (MarkerKind.WITHHELD, 8.4, "R4", "withheld") in marks
    assert (MarkerKind.CANCELLED, 8.5, "R5", "cancelled by R1") in marks
    assert (MarkerKind.NOTE, 8.6, None, "semantics nested") in marks
    assert (MarkerKind.NOTE, 8.8, None, "reloaded") in marks
    assert len(marks) == 16  # task-done and dispatch are counted, not drawn; the unknown kind is ignored
    assert tl.counts["task-done"] == 1 and tl.counts["dispatch"] == 1
    assert tl.ignored == {"from-the-future": 1}
    assert tl.rules == ("R1", "R2", "R3", "R4", "R5", "R6")
    assert (tl.start, tl.end) == (0.0, 10.0)
    assert tl.options["semantics"] == "last-wins"
    detail = next(m.detail for m in tl.markers if m.kind == MarkerKind.UNDETERMINED)
    assert "no value for m" in detail and "A within 10 s" in detail


def test_rules_sort_naturally() -> None:
    records = [dec(i, f"R{n}", 0.0, 0) for i, n in enumerate((10, 2, 1), 1)]
    assert Timeline.from_records(records).rules == ("R1", "R2", "R10")


def test_runs_that_do_not_continue_one_another_number_their_obligations_anew() -> None:
    first = [{**r, "run": "a"} for r in (dec(1, "R1", 0.0, 0), ob(1, "R1", "A", "pending", 0.0, 5.0))]
    second = [
        {**r, "run": "b"} for r in (dec(1, "R1", 1.0, 0), ob(1, "R1", "B", "fulfilled", 1.0, 5.0, at=2.0))
    ]
    tl = Timeline.from_records(first + second)
    assert [(b.key, b.event, b.outcome) for b in tl.bars] == [
        ((0, 1), "A", Outcome.PENDING),
        ((1, 1), "B", Outcome.FULFILLED),
    ]
    assert tl.runs == 2
    assert [(m.time, m.label) for m in tl.markers if m.kind == MarkerKind.NOTE] == [(1.0, "new run")]
    restored = [{"kind": "restored", "time": 1.0, "run": "b", "from": "a"}]
    again = [{**r, "run": "b"} for r in (ob(1, "R1", "A", "fulfilled", 0.0, 5.0, at=2.0),)]
    tl = Timeline.from_records(first + restored + again)  # restored from its journal: the ids go on
    assert [(b.key, b.outcome) for b in tl.bars] == [((0, 1), Outcome.FULFILLED)]
    assert tl.runs == 1


@pytest.mark.parametrize(
    ("record", "says"),
    [
        (
            {"kind": "obligation", "time": 1, "seq": 7},
            "record seq 7 (obligation) cannot be drawn: its id is not",
        ),
        (
            {"kind": "event", "time": "soon"},
            "record 1 (event) cannot be drawn: its time is not a finite number",
        ),
        ({"time": 1}, "record 1 (None) cannot be drawn: it names no kind"),
        ({"kind": "context", "time": 1, "values": [1]}, "its values are not an object"),
    ],
)
def test_a_record_that_lacks_what_its_kind_needs_is_named(record: dict[str, Any], says: str) -> None:
    with pytest.raises(UserError) as e:
        Timeline.from_records([record], "x.jsonl")
    assert says in str(e.value) and e.value.where == "x.jsonl"


# ---------------------------------------------------------------------- layout


def test_bars_of_a_rule_share_a_row_only_when_they_do_not_overlap() -> None:
    span_end = 1000.0
    records = [
        ob(1, "R1", "A", "pending", 0.0, 10.0),
        ob(2, "R1", "B", "pending", 5.0, 20.0),  # overlaps 1: a row of its own
        ob(3, "R1", "C", "pending", 20.0, 30.0),  # starts as 2 ends, but 1's row is free: row 0
        ob(4, "R1", "D", "pending", 10.0, 12.0),  # starts where 1 ends: the gap (2 s) keeps it off row 0
        ob(5, "R1", "E", "pending", 12.0, 13.0),  # starts where 1 ends, gap included: row 0
        {"kind": "event", "time": span_end, "event": "E"},
    ]
    lay = layout(Timeline.from_records(records))
    lane = lay.lane("R1")
    rows = {key[1]: round((y - lane.top) - 1.5) for key, y in lay.bar_y.items()}
    assert rows == {1: 0, 2: 1, 4: 2, 5: 0, 3: 0}
    assert lane.rows == 3 and not lay.notes


def test_what_would_be_unreadable_is_capped_and_said() -> None:
    records: list[dict[str, Any]] = [
        {"kind": "context", "time": 0.0, "values": {f"m{i}": i for i in range(5)}},
        {"kind": "context", "time": 1.0, "values": {"m3": 30, "m4": 40}},
    ]
    records += [dec(i, f"R{i}", 0.0, 0) for i in range(1, 6)]
    records += [dec(10 + i, "R4", 1.0, 0) for i in range(3)]
    records += [ob(i, "R1", "A", "pending", 0.0, 5.0) for i in range(1, 5)]  # four overlapping bars
    lay = layout(Timeline.from_records(records), max_rules=2, max_measures=2, max_rows=3)
    assert [lane.rule for lane in lay.lanes] == ["R1", "R4"]  # the busiest, in natural order
    assert [s.name for s in lay.measures] == ["m3", "m4"]
    assert lay.notes == (
        "3 more rules took part; the 2 with the most marks are drawn",
        "3 more measures changed; the 2 that changed most are drawn",
        "1 obligation bars overlap others (a lane holds 3 rows)",
    )
    assert {m.rule for m in lay.markers} == {"R1", "R4"}
    exactly = layout(Timeline.from_records(records), max_rules=5, max_measures=5, max_rows=4)
    assert exactly.notes == () and len(exactly.lanes) == 5 and len(exactly.measures) == 5


# ---------------------------------------------------------------------- the demo's real run


@pytest.fixture(scope="module")
def demo_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The demo's audit trail and a Manager-node-style MCAP recording of the same run."""
    folder = tmp_path_factory.mktemp("demo")
    audit, mcap = folder / "demo.jsonl", folder / "demo.mcap"
    recorder = McapRecorder(mcap)
    try:
        run_demo(audit=str(audit), on_event=lambda ev: recorder.write(ev.kind, ev.time, ev.data))
    finally:
        recorder.close()
    return audit, mcap


def test_the_demos_audit_trail(demo_log: tuple[Path, Path]) -> None:
    tl = Timeline.read(demo_log[0])
    assert tl.rules == tuple(f"R{i}" for i in range(1, 11))
    assert (tl.start, tl.end) == (0.0, 880.0)
    assert Link(parent=(0, 7), child=(0, 8), time=120.0) in tl.links  # R3: RetryAgreed missed, otherwise
    assert Link(parent=(0, 19), child=(0, 20), time=780.0) in tl.links  # R8: MedicationTaken missed
    late = tl.bar((0, 19))
    assert (late.rule, late.event, late.outcome, late.start, late.end, late.at, late.late) == (
        "R8",
        "MedicationTaken",
        Outcome.LATE,
        180.0,
        780.0,
        780.0,
        880.0,
    )
    assert tl.bar((0, 7)).outcome == Outcome.VIOLATED
    assert tl.bar((0, 11)).outcome == Outcome.RESPECTED and tl.bar((0, 11)).negated
    assert Band(rule="R6", layer="R6.1", start=150.0, end=880.0) in tl.bands
    assert any(m.kind == MarkerKind.REFUSED and m.rule == "R6" and m.time == 150.0 for m in tl.markers)
    # each decision says what the robot says to people; an otherwise says what it missed
    said = {m.detail.partition("\nsays: ")[2] for m in tl.markers if m.kind == MarkerKind.OTHERWISE}
    assert said == {
        "I did not retry agreed in time, so I will support called within 1 minute.",
        "I did not medication taken in time, so I will inform carer within 2 minutes.",
    }
    assert all("\nsays: " in m.detail for m in tl.markers if m.kind == MarkerKind.DECISION)
    assert not tl.ignored


def test_a_recording_gives_the_same_timeline_as_the_audit_trail(demo_log: tuple[Path, Path]) -> None:
    audit, recorded = Timeline.read(demo_log[0]), Timeline.read(demo_log[1])
    assert recorded.bars == audit.bars
    assert recorded.bands == audit.bands
    assert recorded.links == audit.links
    assert recorded.series == audit.series
    assert recorded.markers == audit.markers
    assert recorded.source.endswith("demo.mcap")


# ---------------------------------------------------------------------- the pictures


@pytest.fixture(scope="module")
def demo_tl(demo_log: tuple[Path, Path]) -> Timeline:
    return Timeline.read(demo_log[0])


@pytest.fixture(scope="module")
def demo_svg(demo_tl: Timeline) -> bytes:
    need("matplotlib")
    return timeline_image(demo_tl, "svg")


def test_the_png_is_a_real_image(tl: Timeline) -> None:
    need("matplotlib")
    png = timeline_image(tl, "png")
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000
    width = int.from_bytes(png[16:20], "big")
    assert width == 1400


def test_the_svg_parses_names_the_rules_and_is_the_same_every_time(
    demo_tl: Timeline, demo_svg: bytes
) -> None:
    root = ET.fromstring(demo_svg)
    assert root.tag.endswith("svg")
    texts = " ".join(t for t in root.itertext())
    for rule in demo_tl.rules:
        assert rule in texts
    assert "R6.1" in texts and "otherwise #19" in texts and "obligation late" in texts
    assert b"<dc:date>" not in demo_svg
    assert timeline_image(demo_tl, "svg") == demo_svg


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail("Playwright is missing under CI: scripts/setup --dev installs it")
        pytest.skip("Playwright is not installed here (the browser extra)")
    if not Path(CHROMIUM).exists():
        if os.environ.get("CI"):
            pytest.fail("Debian's chromium is missing under CI: scripts/setup --dev installs it (as root)")
        pytest.skip("Debian's chromium is not installed here (apt-get install chromium)")
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        yield b
        b.close()


def rendered(browser: Any, page: Path) -> dict[str, Any]:
    """Open ``page`` in Chromium; every request is recorded and only the file itself is let through."""
    context = browser.new_context()
    tab = context.new_page()
    requests: list[str] = []
    errors: list[str] = []

    def route(r: Any) -> None:
        requests.append(r.request.url)
        if r.request.url == page.as_uri():
            r.continue_()
        else:
            r.abort()

    tab.route("**/*", route)
    tab.on("request", lambda r: requests.append(r.url))
    tab.on("pageerror", lambda e: errors.append(str(e)))
    try:
        tab.goto(page.as_uri())
        tab.wait_for_selector(".js-plotly-plot .main-svg", timeout=20_000)
        found = tab.evaluate(
            """() => ({
                plots: document.querySelectorAll('.js-plotly-plot').length,
                svgs: document.querySelectorAll('.main-svg').length,
                bars: document.querySelectorAll('.barlayer .point').length,
                traces: document.getElementById('cosleec-timeline').data.length,
                ticks: [...document.querySelectorAll('g[class^=y][class$=tick] text')].map(t => t.textContent),
            })"""
        )
    finally:
        context.close()
    return {**found, "requests": sorted(set(requests)), "errors": errors}


def test_the_html_is_self_contained_and_renders_in_chromium(
    demo_tl: Timeline, browser: Any, tmp_path: Path
) -> None:
    need("plotly")
    html = timeline_html(demo_tl)
    assert not re.findall(r"<script[^>]*\bsrc\s*=", html, re.I)  # no script fetched: Plotly is inline
    assert not re.findall(r"<link[^>]*\bhref\s*=\s*.https?:", html, re.I)
    assert "plotly.js" in html and 'id="cosleec-timeline"' in html
    # small (issue 33: 4.8 MB for one short shift): plotly.js's basic bundle, not the whole library
    assert 1_000_000 < len(html.encode()) < 1_400_000 and "plotly.js (basic - minified)" in html
    page = tmp_path / "demo.html"
    page.write_text(html)
    got = rendered(browser, page)
    assert got["requests"] == [page.as_uri()]  # nothing leaves the page
    assert not got["errors"]
    assert got["plots"] == 1 and got["svgs"] >= 1 and got["traces"] > 5
    assert got["bars"] >= len(demo_tl.bars) + len(demo_tl.bands)
    assert {"run", "false", "true", "low", "high", *demo_tl.rules} <= set(got["ticks"])  # every lane drawn


def test_the_largest_corpus_file_s_run_draws_in_every_format(browser: Any, tmp_path: Path) -> None:
    need("matplotlib")
    need("plotly")
    path = corpus_dir() / LARGEST
    if not path.exists():
        if os.environ.get("CI"):
            pytest.fail(f"the corpus file {path} is missing under CI")
        pytest.skip("the corpus is not beside the checkout")
    rules = RuleSet.from_file(path)
    log = tmp_path / "big.jsonl"
    clock = VirtualClock()
    m = Manager(rules, clock=clock, audit=AuditLog(log), untimed=5.0, dispatch=False)
    m.start()
    rng = random.Random(17)
    triggers = sorted({r.trigger for r in rules.rules})
    measures = sorted(rules.measures)
    for _ in range(300):  # random measures, triggers, and about half the responses, in time or not
        name = rng.choice(measures)
        m.update({name: rng.random() < 0.5 if rules.measures[name].kind == "boolean" else rng.randint(0, 50)})
        for d in m.event(rng.choice(triggers)):
            if d.obligations and rng.random() < 0.6:
                clock.advance(rng.uniform(0, 4))
                m.event(d.obligations[0].event)
        clock.advance(rng.uniform(0, 2))
        m.tick()
    m.close()
    tl = Timeline.read(log)
    assert len(tl.rules) > 100 and {b.outcome for b in tl.bars} >= {Outcome.FULFILLED, Outcome.VIOLATED}
    lay = layout(tl)
    assert len(lay.lanes) == 30 and len(lay.measures) == 10 and len(lay.notes) == 2
    png, svg = timeline_image(tl, "png"), timeline_image(tl, "svg")
    assert png.startswith(b"\x89PNG") and ET.fromstring(svg).tag.endswith("svg")
    page = tmp_path / "big.html"
    page.write_text(timeline_html(tl))
    got = rendered(browser, page)
    assert got["requests"] == [page.as_uri()] and not got["errors"] and got["plots"] == 1


@pytest.mark.parametrize(
    ("module", "draw", "extra"),
    [
        ("matplotlib", lambda tl: timeline_image(tl, "png"), "cosleec[timeline]"),
        ("plotly", timeline_html, "cosleec[timeline]"),
    ],
)
def test_a_missing_library_names_the_extra(
    tl: Timeline, monkeypatch: pytest.MonkeyPatch, module: str, draw: Any, extra: str
) -> None:
    for name in [m for m in sys.modules if m.startswith(module + ".")] + [module]:
        monkeypatch.setitem(sys.modules, name, None)  # as if never installed, whatever was imported before
    with pytest.raises(UserError) as e:
        draw(tl)
    assert f"({module} is missing)" in str(e.value) and e.value.hint == f"pip install '{extra}'"


def test_a_recording_without_mcap_installed_names_the_extra(
    demo_log: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    for name in [m for m in sys.modules if m == "mcap" or m.startswith("mcap.")] + ["mcap"]:
        monkeypatch.setitem(sys.modules, name, None)  # as if never installed, whatever was imported before
    with pytest.raises(UserError) as e:
        Timeline.read(demo_log[1])
    assert "needs the `mcap` package" in str(e.value) and e.value.hint == "pip install 'cosleec[record]'"


# ---------------------------------------------------------------------- the command


def cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    rc = main(list(args))
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return rc, out, err


def test_the_command_draws_each_format(
    demo_log: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    need("matplotlib")
    need("plotly")
    log = tmp_path / "run.jsonl"
    log.write_bytes(demo_log[0].read_bytes())
    rc, out, _ = cli(capsys, "timeline", str(log))
    assert rc == 0 and (tmp_path / "run.html").read_text().startswith(
        "<!doctype html>"
    )  # the default: beside it, .html
    assert out == f"{tmp_path / 'run.html'}: 10 rule(s), 32 obligation(s), t = 0 to 880 s (html)\n"
    rc, _, _ = cli(capsys, "timeline", str(demo_log[1]), "-o", str(tmp_path / "rec.png"))
    assert rc == 0 and (tmp_path / "rec.png").read_bytes().startswith(b"\x89PNG")


def test_demo_plot_draws_the_demo_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    need("matplotlib")
    out = tmp_path / "demo.svg"
    rc, stdout, _ = cli(capsys, "demo", "--json", "--plot", str(out))
    assert rc == 0
    lines = stdout.splitlines()
    assert all(json.loads(line)["kind"] for line in lines)  # the picture does not break the JSON lines
    svg = out.read_text()
    assert "R10.2" in svg and "MedicationTaken" in svg


@pytest.fixture
def files(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, demo_log: tuple[Path, Path]) -> Path:
    good = demo_log[0].read_text().splitlines()
    (tmp_path / "good.jsonl").write_text("\n".join(good) + "\n")
    (tmp_path / "bad.jsonl").write_text("\n".join([*good[:3], '{"seq": 4, "kind": oops}', *good[3:]]) + "\n")
    (tmp_path / "empty.jsonl").write_text("")
    (tmp_path / "trace.jsonl").write_text('{"t": 0, "event": "E"}\n')
    (tmp_path / "notes.txt").write_text("hello\n")
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap file")
    (tmp_path / "link.html").symlink_to(tmp_path / "good.jsonl")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["missing.jsonl"], "missing.jsonl: cannot read the audit log: No such file or directory"),
        (["bad.jsonl"], "bad.jsonl:4:20: not valid JSON"),
        (["notes.txt"], "notes.txt: cannot tell what notes.txt is: .txt"),
        (["empty.jsonl"], "empty.jsonl: the audit log is empty"),
        (["trace.jsonl"], "trace.jsonl:1: this is not an audit log"),
        (["junk.mcap"], "junk.mcap: the recording holds no runtime record"),
        (["good.jsonl", "-o", "good.pdf"], "good.pdf: cannot tell what to draw good.pdf as: .pdf"),
        (["good.jsonl", "-o", "nowhere/x.png"], "the directory nowhere does not exist"),
        (
            ["good.jsonl", "-o", "link.html"],
            "link.html: refusing to overwrite the run file with its own picture",
        ),
    ],
)
def test_the_commands_mistakes_are_one_clear_message(
    files: Path, capsys: pytest.CaptureFixture[str], args: list[str], says: str
) -> None:
    rc, out, err = cli(capsys, "timeline", *args)
    assert rc == 1 and not out
    assert err.startswith(f"cosleec: {says}") if ":" in says.split(" ")[0] else says in err
    assert "hint:" in err or "empty" in says
    assert (files / "good.jsonl").read_text().startswith('{"seq":1')  # the input is never touched


def test_demo_plot_refuses_an_unknown_format_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, out, err = cli(capsys, "demo", "--plot", str(tmp_path / "day.gif"))
    assert rc == 1 and not out  # said before the demo prints anything
    assert "cannot tell what to draw" in err and ".png, .svg, .html" in err


def test_a_long_measure_name_is_drawn_whole_inside_the_picture() -> None:
    # issue 33: `batteryLowDeliveringUrgentMedication` came out as `veringUrgentMedication`
    need("matplotlib")
    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib import pyplot as plt

    from cosleec.views.timeline_mpl import _figure

    long = "batteryLowDeliveringUrgentMedication"
    records = [
        {"kind": "context", "time": 0.0, "values": {long: True, "m": "veryHighIndeed"}, "version": 1},
        {"kind": "context", "time": 5.0, "values": {long: False}, "version": 2},
    ]
    tl = Timeline.from_records(records, "long.jsonl")
    fig = _figure(layout(tl), plt)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
        drawn = {ax.yaxis.label.get_text(): ax.yaxis.label.get_window_extent(renderer) for ax in fig.axes}
        assert {long, "m"} <= drawn.keys()  # the whole name is the label's text...
        for name in (long, "m"):  # ...and the whole label is inside the picture
            box = drawn[name]
            assert fig.bbox.x0 <= box.x0 and box.x1 <= fig.bbox.x1, (name, box)
        for ax in fig.axes:  # the lanes' names and the values' ticks too
            assert ax.get_tightbbox(renderer).x0 >= fig.bbox.x0
    finally:
        plt.close(fig)
