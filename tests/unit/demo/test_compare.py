"""The normalised record stream of a demo run: one outcome, whatever the transport."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from cosleec.demo import expected, first_difference, outcomes, run, scenario, summary
from cosleec.demo.compare import BARRIERS, normalise
from cosleec.runtime import read_audit


@pytest.fixture(scope="module")
def records() -> list[dict[str, Any]]:
    return run().records()


def instants(recs: list[dict[str, Any]]) -> list[list[dict[str, Any]]]:
    """Split as outcomes() does: at a context/layers record or where the clock moved."""
    out: list[list[dict[str, Any]]] = [[]]
    for r in recs:
        if r["kind"] in BARRIERS or (out[-1] and r["time"] != out[-1][0]["time"]):
            out.append([])
        out[-1].append(r)
    return [i for i in out if i]


def test_the_scripted_day_has_two_violations_and_one_late_report(records: list[dict[str, Any]]) -> None:
    result = run()
    stream = outcomes(records)
    assert summary(stream) == {"decisions": 32, "violations": 2, "late": 1, "refused": 1}
    assert summary(stream)["violations"] == result.manager.stats["violations"]
    assert [
        (o.rule, o.event, o.at, o.late) for o in stream if o.kind == "obligation" and o.status == "violated"
    ] == [
        ("R3", "RetryAgreed", 120.0, ()),
        ("R8", "MedicationTaken", 780.0, ()),
        ("R8", "MedicationTaken", 780.0, (880.0,)),  # the pills came late: reported again, not counted
    ]
    decisions = [o for o in stream if o.kind == "decision"]
    assert [
        (o.rule, "otherwise" if o.event == "otherwise" else o.clause) for o in decisions
    ] == scenario.EXPECTED


def test_the_embedded_run_is_its_own_reference(records: list[dict[str, Any]]) -> None:
    assert first_difference(expected(), outcomes(records)) is None
    assert expected() == outcomes(records)


def test_the_audit_log_and_the_runtime_events_give_the_same_stream(tmp_path: Path) -> None:
    # a ROS run is read from the Manager's --audit file: it must normalise like the events
    audit = tmp_path / "audit.jsonl"
    result = run(audit=str(audit))
    assert first_difference(outcomes(result.records()), outcomes(read_audit(audit))) is None


def test_the_order_of_records_within_an_instant_does_not_matter(records: list[dict[str, Any]]) -> None:
    # a task node reports in turn what the embedded Manager runs depth-first, and ROS 1
    # handles publishers on separate threads: the records of an instant come in any order
    shuffled = [
        r
        for i in instants(records)
        for r in ([i[0], *reversed(i[1:])] if i[0]["kind"] in BARRIERS else reversed(i))
    ]
    assert shuffled != records
    assert first_difference(outcomes(records), outcomes(shuffled)) is None
    # ...which a raw comparison would take for a difference
    raw = [normalise(r) for r in records]
    assert [normalise(r) for r in shuffled] != raw


def test_a_different_outcome_is_named_record_by_record(records: list[dict[str, Any]]) -> None:
    want = outcomes(records)
    # the robot cannot open the curtains: R1's first obligation is violated at its deadline
    steps = [("fail", "OpenCurtains", "broken motor"), *scenario.STEPS]
    got = outcomes(run(steps).records())
    difference = first_difference(want, got)
    assert difference is not None
    assert "record 4 differs" in difference
    assert "expected: t=0 obligation #1 R1 OpenCurtains fulfilled at 0" in difference
    assert "actual:   t=0 event CurtainOpenRequest" in difference  # no OpenCurtains, no fulfilment


@pytest.mark.parametrize(
    ("field", "value", "named"),
    [
        ("at", 121.0, "at: expected 120.0, actual 121.0"),
        ("time", 151.0, "time: expected 150.0, actual 151.0"),
        ("status", "fulfilled", "status: expected 'violated', actual 'fulfilled'"),
        ("by", "RetryAgreed", "by: expected None, actual 'RetryAgreed'"),
    ],
)
def test_each_compared_field_counts(
    records: list[dict[str, Any]], field: str, value: Any, named: str
) -> None:
    changed = copy.deepcopy(records)
    victim = next(r for r in changed if r["kind"] == "obligation" and r["status"] == "violated")
    victim[field] = value
    difference = first_difference(outcomes(records), outcomes(changed))
    assert difference is not None and named in difference, difference


def test_a_missing_or_extra_record_or_one_moved_across_a_step_is_a_difference(
    records: list[dict[str, Any]],
) -> None:
    want = outcomes(records)
    assert f"record {len(want) - 1} is missing" in (first_difference(want, want[:-1]) or "")
    assert f"record {len(want)} is extra" in (first_difference(want, [*want, want[-1]]) or "")
    # a decision taken before the context changed is not the same outcome as one after it
    i = next(k for k, r in enumerate(records) if r["kind"] == "context" and k > 5)
    j = max(k for k in range(i) if records[k]["kind"] == "obligation")  # the step's last outcome...
    moved = [*records[:j], *records[j + 1 : i + 1], records[j], *records[i + 1 :]]  # ...after the next update
    difference = first_difference(want, outcomes(moved))
    assert difference is not None and "expected: t=0 obligation #1 R1 OpenCurtains fulfilled" in difference


def test_what_legitimately_differs_is_ignored(records: list[dict[str, Any]]) -> None:
    noisy = copy.deepcopy(records)
    for r in noisy:
        r["seq"] = 10_000  # the Manager's input order: a task node reports in turn
        r["wall"] = 1.7e9
        if r["kind"] == "decision":
            r["explanation"] = r["reason"] = "worded differently"
            r["session"] = "another process"
    # only the embedded Manager runs tasks
    noisy.append({"kind": "task-failed", "time": 880.0, "rule": "R1", "decision": 1})
    assert first_difference(outcomes(records), outcomes(noisy)) is None


def test_streams_read_back_from_json_compare_equal(records: list[dict[str, Any]]) -> None:
    wire = [json.loads(json.dumps(r)) for r in records]
    assert outcomes(wire) == outcomes(records)
    assert all(str(o) and o.fields()["kind"] == o.kind for o in outcomes(records))


def test_a_record_of_a_new_kind_is_compared_not_dropped(records: list[dict[str, Any]]) -> None:
    more = [*records, {"kind": "audit-note", "time": 880.0, "text": "hello", "seq": 7}]
    difference = first_difference(outcomes(records), outcomes(more))
    assert difference is not None and "audit-note" in difference
