"""No silent misuse (issue 33): hints that show, a Manager used before start(), a virtual
clock moved without tick(), and questions that are not attempts.

Each test names the one-character change (or the old behaviour) it catches.
"""

from __future__ import annotations

import logging
import time
import traceback
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.cli.main import main
from cosleec.errors import UserError
from cosleec.runtime import ContextError, Manager, VirtualClock, read_audit

ROBOT = """
def_start
    event FallDetected event CallNurse event RaiseAlarm event GoToDock event RecordVideo event Visit
    measure batteryLevel : numeric
    measure patientConsented : boolean
def_end
rule_start
    R1 when FallDetected then CallNurse within 60 seconds otherwise RaiseAlarm
    R2 when Visit then not RecordVideo within 10 minutes unless patientConsented
rule_end
"""


def robot(**options: Any) -> tuple[Manager, VirtualClock]:
    clock = VirtualClock()
    return Manager.from_text(ROBOT, clock=clock, **options), clock


# ---------------------------------------------------------------------------- 1. hints show


def test_an_unknown_event_shows_its_did_you_mean_in_str_and_in_a_traceback() -> None:
    m, _ = robot()
    with pytest.raises(ContextError) as e:
        m.event("FallDetect")
    # before: str(e) was only "unknown event 'FallDetect'", the hint in e.hint alone
    assert str(e.value) == "unknown event 'FallDetect'\n  hint: did you mean FallDetected?"
    shown = "".join(traceback.format_exception(e.value))
    assert "did you mean FallDetected?" in shown


@pytest.mark.parametrize(
    ("call", "meant"),
    [
        (lambda m: m.update(batteryLvl=3), "batteryLevel"),
        (lambda m: m.update({"patientconsented": True}), "patientConsented"),  # case only
        (lambda m: m.event("Visit", {"batteryLevl": 3}), "batteryLevel"),
    ],
)
def test_an_unknown_measure_gets_a_did_you_mean_like_an_event(call: Any, meant: str, tmp_path: Path) -> None:
    m, _ = robot(audit=tmp_path / "a.jsonl")
    m.start(check=False)
    with pytest.raises(ContextError) as e:
        call(m)
    assert e.value.hint == f"did you mean {meant}?" and f"did you mean {meant}?" in str(e.value)
    m.close()
    (rejected,) = [r for r in read_audit(tmp_path / "a.jsonl") if r["kind"] == "rejected"]
    # the record keeps the reason and the hint apart (the reason is not doubled by str(e))
    assert rejected["reason"].startswith("unknown measure '") and "hint" not in rejected["reason"]
    assert rejected["hint"] == f"did you mean {meant}?"


def test_a_measure_nothing_resembles_says_where_measures_are_declared() -> None:
    m, _ = robot()
    with pytest.raises(ContextError) as e:
        m.update(xyzzy=1)
    assert "def block" in e.value.hint and e.value.hint in str(e.value)


@given(
    message=st.text(st.characters(blacklist_categories=("Cs",)), min_size=1, max_size=40).filter(
        lambda t: "hint:" not in t
    ),
    hint=st.text(st.characters(blacklist_categories=("Cs",)), max_size=40).filter(lambda t: "hint:" not in t),
    where=st.sampled_from(["", "rules.sleec:3:14", "mapping.yaml"]),
)
def test_str_shows_the_hint_and_render_shows_it_exactly_once(message: str, hint: str, where: str) -> None:
    e = UserError(message, hint=hint, where=where)
    assert e.message == message
    assert str(e) == (f"{message}\n  hint: {hint}" if hint else message)
    rendered = e.render()
    assert rendered.count("hint:") == (1 if hint else 0)
    assert rendered.startswith(f"{where}: {message}" if where else message)


def test_the_cli_prints_a_hint_once(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rules = tmp_path / "r.sleec"
    rules.write_text(ROBOT)
    bag = tmp_path / "run.mcap"  # a bag given without --mapping: a UserError with a hint
    bag.write_bytes(b"\x89MCAP0\r\n")
    assert main(["conforms", str(rules), str(bag)]) == 2
    err = capsys.readouterr().err
    assert err.count("hint:") == 1 and "--mapping" in err


# ---------------------------------------------------------------------------- 2. before start()


def test_an_event_before_start_starts_the_manager_and_says_so(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    m, _ = robot(audit=tmp_path / "a.jsonl")
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        m.event("FallDetected")
        m.event("Visit")  # once: the Manager is started now
    (warning,) = [r.getMessage() for r in caplog.records if "before start()" in r.getMessage()]
    # before: nothing at all -- no warning, no completeness check, no options record
    assert warning.startswith("Manager.event() before start(): the Manager started itself")
    assert "R1: no task and no capability for response event CallNurse" in warning
    assert "call start() before the first event" in warning
    m.close()
    kinds = [r["kind"] for r in read_audit(tmp_path / "a.jsonl")]
    assert kinds[0] == "options" and kinds.count("options") == 1  # what start() records, once


@pytest.mark.parametrize("first", ["update", "request"])
def test_an_update_or_a_request_before_start_starts_it_too(
    first: str, caplog: pytest.LogCaptureFixture
) -> None:
    m, _ = robot(dispatch=False)  # nothing to implement: the warning names start() only
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        if first == "update":
            m.update(batteryLevel=50)
        else:
            m.request("RecordVideo")
    (warning,) = [r.getMessage() for r in caplog.records if "before start()" in r.getMessage()]
    assert warning.startswith(f"Manager.{first}() before start()") and "completeness" not in warning


def test_a_started_manager_and_a_question_give_no_warning(caplog: pytest.LogCaptureFixture) -> None:
    m, _ = robot()
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        assert m.permission("RecordVideo")  # a question does not start the Manager
        m.start(check=False)
        m.event("FallDetected")
        m.update(batteryLevel=50)
    assert not [r for r in caplog.records if "before start()" in r.getMessage()]


def test_start_after_an_implicit_start_still_checks(caplog: pytest.LogCaptureFixture) -> None:
    from cosleec.runtime import BindingError

    m, _ = robot()
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        m.event("Visit")
    with pytest.raises(BindingError):
        m.start()  # the explicit call keeps its contract: incomplete implementations raise


# ---------------------------------------------------------------------------- 3. the virtual clock


def nurse_robot(tmp_path: Path) -> tuple[Manager, VirtualClock, list[str]]:
    m, clock = robot(audit=tmp_path / "a.jsonl")
    done: list[str] = []
    m.capability("CallNurse")(lambda ob, d: done.append("nurse called (not reported)"))
    m.capability("RaiseAlarm")(lambda ob, d: done.append("alarm"))
    m.start()
    return m, clock, done


def test_advancing_the_virtual_clock_alone_starts_the_otherwise(tmp_path: Path) -> None:
    m, clock, done = nurse_robot(tmp_path)
    m.event("FallDetected")
    clock.advance(60)
    assert done == ["nurse called (not reported)"]  # the deadline's instant is still inside
    clock.advance(1)  # before: nothing judged until someone called tick()
    assert done == ["nurse called (not reported)", "alarm"] and m.stats["violations"] == 1
    (d,) = m.tick()  # tick() still returns the otherwise the move started, once
    assert (d.rule, [o.event for o in d.obligations]) == ("R1", ["RaiseAlarm"]) and m.tick() == []
    m.close()
    statuses = [r["status"] for r in read_audit(tmp_path / "a.jsonl") if r["kind"] == "obligation"]
    assert statuses[-2:] == ["violated", "pending"]  # R1's miss, then its otherwise's obligation


def test_setting_the_virtual_clock_judges_too(tmp_path: Path) -> None:
    m, clock, done = nurse_robot(tmp_path)
    m.event("FallDetected")
    clock.set(61)
    assert done[-1] == "alarm"
    m.close()
    clock.advance(100)  # a closed Manager no longer watches: nothing raised


def test_a_big_step_judges_every_deadline_it_passes_in_one_quick_move() -> None:
    m, clock = robot(dispatch=False)
    m.start()
    for _ in range(2000):
        m.event("FallDetected")
        clock.advance(0.01)
    began = time.perf_counter()
    clock.advance(3600)
    assert m.stats["violations"] == 2000 and len(m.tick()) == 2000
    assert time.perf_counter() - began < 10


def test_a_manager_that_is_dropped_is_not_kept_by_its_clock() -> None:
    import gc
    import weakref

    m, clock = robot(dispatch=False)
    m.start()
    gone = weakref.ref(m)
    del m
    gc.collect()
    assert gone() is None
    clock.advance(10)  # nothing to tell: no error


# ---------------------------------------------------------------------------- 4. questions and attempts


def test_a_ui_question_records_nothing_and_a_real_attempt_records_once(tmp_path: Path) -> None:
    m, _ = robot(audit=tmp_path / "a.jsonl", dispatch=False)
    m.start()
    m.update(patientConsented=False)
    m.event("Visit")
    for _ in range(3):  # a status screen asks again and again
        assert not m.permission("RecordVideo")
    answer = m.request("RecordVideo", source="camera")
    assert not answer and answer.rules == ("R2",)  # the Permission: false, and why
    m.close()
    refused = [r for r in read_audit(tmp_path / "a.jsonl") if r["kind"] == "refused"]
    # before: refused == 4 (each question counted as an attempt)
    assert m.stats["refused"] == 1 and [r["source"] for r in refused] == ["camera"]
