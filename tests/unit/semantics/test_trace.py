"""Traces and audit logs read as steps: every way a line can be wrong names its line, and a
Manager's audit log reads back as what the Manager was fed."""

from __future__ import annotations

import itertools
import json
import os
import threading
from pathlib import Path

import pytest

from cosleec.lang import parse
from cosleec.runtime import ContextError, Manager, VirtualClock
from cosleec.semantics import Step
from cosleec.semantics.trace import (
    RunOptions,
    TraceError,
    check_trace,
    fit_trace,
    read,
    read_audit_trace,
    read_recording,
    read_trace,
)

RULES = """def_start
    event UserFallen
    event SmokeDetected
    event CallSupport
    measure assentToSupportCalls : boolean
    measure alarmOn : boolean
    measure level : scale(low, medium, high)
    measure temperature : numeric
def_end
rule_start
    Rule3 when UserFallen and not assentToSupportCalls then not CallSupport within 10 minutes
    Rule21 when SmokeDetected and alarmOn then CallSupport within 5 minutes
rule_end
"""


def steps_of(steps: list[Step]) -> list[tuple[float, str | None, dict[str, object]]]:
    return [(s.t, s.event, dict(s.values)) for s in steps]


# ---------------------------------------------------------------------------- written traces


def test_reads_the_issue_format(tmp_path: Path) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text(
        '{"t": 0, "set": {"assentToSupportCalls": false, "level": "high", "temperature": 21.5}}\n'
        "\n"
        '{"t": 0, "event": "UserFallen"}\r\n'
        "   \n"
        '{"t": 120.5, "set": {"alarmOn": true}, "event": "SmokeDetected"}\n'
        '{"t": 360, "set": {"level": null}}\n'
        '{"t": 360}'
    )
    steps = read_trace(f)
    assert steps_of(steps) == [
        (0, None, {"assentToSupportCalls": False, "level": "high", "temperature": 21.5}),
        (0, "UserFallen", {}),
        (120.5, "SmokeDetected", {"alarmOn": True}),
        (360, None, {"level": None}),
        (360, None, {}),
    ]
    assert [s.line for s in steps] == [1, 3, 5, 6, 7]
    assert all(isinstance(s.t, float) for s in steps)
    assert read(f) == steps


def test_a_bom_and_an_empty_file(tmp_path: Path) -> None:
    f = tmp_path / "t.jsonl"
    f.write_bytes(b'\xef\xbb\xbf{"t": 1}\n')
    assert steps_of(read_trace(f)) == [(1, None, {})]
    f.write_text("\n\n")
    assert read_trace(f) == [] and read(f) == []


BAD_LINES = [
    ('{"t": 0, "event": "E"', "not valid JSON", "one JSON object"),
    ("[1, 2]", "a JSON object, not a list", "write e.g."),
    ('"UserFallen"', "not a string", "write e.g."),
    ("null", "not null", "write e.g."),
    ('{"t": 0, "evnt": "E"}', "unknown key 'evnt'", "did you mean 'event'?"),
    ('{"t": 0, "sets": {}}', "unknown key 'sets'", "did you mean 'set'?"),
    ('{"t": 0, "zzz": 1}', "unknown key 'zzz'", 'a line has "t"'),
    ('{"event": "E"}', 'no time "t"', 'add "t"'),
    ('{"t": "0"}', "\"t\" is a number of seconds, not '0'", '"t": 360'),
    ('{"t": true}', '"t" is a number of seconds, not True', '"t": 360'),
    ('{"t": null}', '"t" is a number of seconds, not None', '"t": 360'),
    ('{"t": NaN}', '"t" must be a finite number', "seconds"),
    ('{"t": Infinity}', '"t" must be a finite number', "seconds"),
    ('{"t": 1e400}', '"t" must be a finite number', "seconds"),
    ('{"t": 1' + "0" * 400 + "}", '"t" must be a finite number', "seconds"),
    ('{"t": 1' + "0" * 5000 + "}", "more than 4,300 digits", "smaller number"),
    ('{"t": 5}', "time goes back: t is 5, after 10", "non-decreasing"),
    ('{"t": 10, "event": 3}', '"event" is the name of an event, not 3', '"event": "UserFallen"'),
    ('{"t": 10, "event": ""}', '"event" is the name of an event', '"event": "UserFallen"'),
    ('{"t": 10, "event": null}', '"event" is the name of an event, not None', '"event": "UserFallen"'),
    ('{"t": 10, "set": [1]}', '"set" is an object of measure values, not a list', '"set": {'),
    ('{"t": 10, "set": "alarmOn"}', '"set" is an object of measure values, not a string', '"set": {'),
    ('{"t": 10, "set": {"alarmOn": [true]}}', "measure 'alarmOn': [True] is not a value", "true/false"),
    ('{"t": 10, "set": {"alarmOn": {"v": 1}}}', "is not a value", "true/false"),
    ('{"t": 10, "set": {"temperature": NaN}}', "nan is not a value (not a finite number)", "finite"),
    ('{"t": 10, "t": 11}', "the key 't' appears twice", "once"),
    ('{"t": ' + "[" * 100_000 + "]" * 100_000 + "}", "nested too deeply", "one JSON object"),
]


@pytest.mark.parametrize(("line", "message", "hint"), BAD_LINES)
def test_every_bad_line_is_a_trace_error_naming_its_line(
    tmp_path: Path, line: str, message: str, hint: str
) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text(f'{{"t": 0}}\n\n{{"t": 10}}\n{line}\n{{"t": 20}}\n')
    with pytest.raises(TraceError) as e:
        read_trace(f)
    assert e.value.where.startswith(f"{f}:4"), e.value.where
    assert message in str(e.value)
    assert hint in e.value.hint
    assert len(e.value.render()) < 600  # quoted text is bounded


def test_json_syntax_errors_carry_the_column(tmp_path: Path) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text('{"t": 0}\n{"t": 1,, "event": "E"}\n')
    with pytest.raises(TraceError) as e:
        read_trace(f)
    assert e.value.where == f"{f}:2:9"


def test_long_names_are_clipped(tmp_path: Path) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text(json.dumps({"t": 0, "x" * 100_000: 1}) + "\n")
    with pytest.raises(TraceError) as e:
        read_trace(f)
    assert len(e.value.render()) < 400


def test_unreadable_and_non_utf8_files(tmp_path: Path) -> None:
    with pytest.raises(TraceError, match="cannot read the trace") as e:
        read_trace(tmp_path / "missing.jsonl")
    assert e.value.where == str(tmp_path / "missing.jsonl")
    f = tmp_path / "latin.jsonl"
    f.write_bytes(b'{"t": 0}\n{"t": 1, "event": "caf\xe9"}\n')
    with pytest.raises(TraceError, match="not UTF-8") as e:
        read(f)
    assert e.value.where == f"{f}:2"


# ---------------------------------------------------------------------------- check_trace


@pytest.mark.parametrize(
    ("line", "message", "hint"),
    [
        ('{"t": 1, "event": "UserFalen"}', "event 'UserFalen' is not declared", "did you mean 'UserFallen'?"),
        ('{"t": 1, "event": "Dance"}', "event 'Dance' is not declared", "declare `event Dance`"),
        (
            '{"t": 1, "event": "alarmOn"}',
            "event 'alarmOn' is not declared",
            'alarmOn is a measure: set it with "set"',
        ),
        (
            '{"t": 1, "set": {"alarmOm": true}}',
            "measure 'alarmOm' is not declared",
            "did you mean 'alarmOn'?",
        ),
        (
            '{"t": 1, "set": {"UserFallen": true}}',
            "measure 'UserFallen'",
            'UserFallen is an event: write "event"',
        ),
        ('{"t": 1, "set": {"alarmOn": 1}}', "alarmOn is boolean: give true or false, not 1", "true"),
        (
            '{"t": 1, "set": {"alarmOn": "true"}}',
            "alarmOn is boolean: give true or false, not 'true'",
            "true",
        ),
        ('{"t": 1, "set": {"temperature": true}}', "temperature is numeric: give a number, not True", "42"),
        ('{"t": 1, "set": {"temperature": "3"}}', "temperature is numeric: give a number, not '3'", "42"),
        (
            '{"t": 1, "set": {"level": "hihg"}}',
            "level is scale(low, medium, high)",
            '"low", "medium", "high"',
        ),
        ('{"t": 1, "set": {"level": 2}}', "give one of its literals as a string, not 2", '"low"'),
    ],
)
def test_check_trace_names_and_types(tmp_path: Path, line: str, message: str, hint: str) -> None:
    spec = parse(RULES, "rules.sleec")
    f = tmp_path / "trace.jsonl"
    f.write_text(f'{{"t": 0, "set": {{"alarmOn": null, "temperature": -3, "level": "low"}}}}\n{line}\n')
    steps = read_trace(f)
    with pytest.raises(TraceError) as e:
        check_trace(spec, steps, path=f)
    assert e.value.where == f"{f}:2"
    assert message in str(e.value)
    assert "not declared" not in message or "not declared in rules.sleec" in str(e.value)
    assert hint in e.value.hint


def test_check_trace_accepts_every_type_and_null(tmp_path: Path) -> None:
    spec = parse(RULES)
    steps = [
        Step(0, values={"alarmOn": True, "assentToSupportCalls": None, "level": "medium", "temperature": 3}),
        Step(1, values={"temperature": 2.5, "level": None}),
        Step(2, event="CallSupport"),
    ]
    check_trace(spec, steps)
    with pytest.raises(TraceError) as e:
        check_trace(spec, [Step(3, event="Nope", line=7)])
    assert e.value.where == "line 7"


# ---------------------------------------------------------------------------- audit logs


def run_manager(log: Path) -> list[tuple[float, str | None, dict[str, object]]]:
    """Feed a Manager on a VirtualClock; return what it was fed, as trace steps."""
    clock = VirtualClock()
    m = Manager.from_text(
        RULES, clock=clock, audit=log, max_age={"temperature": 100}, unknown_events="refuse"
    )
    fed: list[tuple[float, str | None, dict[str, object]]] = []
    m.update(assentToSupportCalls=False, level="medium", temperature=21.5)
    fed.append((0, None, {"assentToSupportCalls": False, "level": "medium", "temperature": 21.5}))
    m.event("UserFallen")
    fed.append((0, "UserFallen", {}))
    with pytest.raises(ContextError):
        m.update(alarmOn="maybe")  # rejected: recorded, but nothing was set
    m.event("Dance")  # refused: recorded, but no event happened
    clock.advance(120)
    m.tick()  # temperature went stale at 100
    fed.append((120, None, {"temperature": None}))
    m.update(alarmOn=True, level="high")
    fed.append((120, None, {"alarmOn": True, "level": "high"}))
    m.event("SmokeDetected")
    fed.append((120, "SmokeDetected", {}))
    clock.advance(10)
    m.event("CallSupport")
    fed.append((130, "CallSupport", {}))
    clock.advance(500)
    m.tick()  # Rule21 is fulfilled, Rule3 violated; nothing is due: no record
    clock.advance(0.25)
    m.update(temperature=19)
    fed.append((630.25, None, {"temperature": 19}))
    m.close()
    return fed


def test_audit_log_round_trip(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    fed = run_manager(log)
    steps = read_audit_trace(log)
    records = [json.loads(line) for line in log.read_text().splitlines()]
    # the event and context steps are exactly what was fed; the others only advance time
    assert [s for s in steps_of(steps) if s[1] is not None or s[2]] == fed
    assert steps[-1].t == records[-1]["time"]
    assert all(a.t <= b.t for a, b in itertools.pairwise(steps))
    assert all(records[s.line - 1]["kind"] in ("event", "context") for s in steps if s.event or s.values)
    assert read(log) == steps
    check_trace(parse(RULES), steps, path=log)


def test_audit_log_torn_last_line_is_ignored(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    whole = read_audit_trace(log)
    log.write_bytes(log.read_bytes() + b'{"seq":999,"kind":"event","time":700.0,"ev')
    assert read_audit_trace(log) == whole
    assert read(log) == whole


def test_audit_log_bad_lines_are_errors(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    lines = log.read_text().splitlines()
    n = len(lines)
    whole = read_audit_trace(log)
    log.write_text("\n".join([*lines[:2], '{"seq":3,"kind":"event","ti', *lines[2:]]) + "\n")
    with pytest.raises(TraceError, match="not valid JSON") as e:
        read_audit_trace(log)
    assert e.value.where.startswith(f"{log}:3:")
    # a complete but unterminated last line is a record all the same; a broken one with a newline is not
    log.write_text("\n".join(lines))
    assert read_audit_trace(log) == whole
    log.write_text("\n".join([*lines, '{"seq":', ""]))
    with pytest.raises(TraceError) as e:
        read_audit_trace(log)
    assert e.value.where.startswith(f"{log}:{n + 1}:")


@pytest.mark.parametrize(
    ("record", "message"),
    [
        ('{"t": 0, "event": "UserFallen"}', "not an audit record"),
        ('{"seq": 9, "kind": "event", "time": "soon", "event": "E"}', '"time" is a number of seconds'),
        ('{"seq": 9, "kind": "event", "event": "E"}', 'no time "time"'),
        ('{"seq": 9, "kind": "event", "time": 1}', "an event record names no event"),
        ('{"seq": 9, "kind": "context", "time": 1, "values": 3}', "a context record has no values"),
        ('{"seq": 9, "kind": "context", "time": 1, "values": {"a": [1]}}', "is not a value"),
        ('{"seq": 9, "kind": "event", "time": 0.5, "event": "E", "run": "other"}', "time goes back"),
    ],
)
def test_audit_records_that_are_not_records(tmp_path: Path, record: str, message: str) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_text(
        '{"seq": 1, "kind": "context", "time": 1, "values": {"a": 1}, "run": "r"}\n' + record + "\n"
    )
    with pytest.raises(TraceError, match=message) as e:
        read(log)
    assert e.value.where == f"{log}:2"


def test_audit_records_at_an_earlier_time_do_not_step_back(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_text(
        '{"seq": 1, "kind": "event", "time": 10, "event": "E"}\n'
        '{"seq": 2, "kind": "decision", "time": 5}\n'  # a fallback's decision, at its deadline
        '{"seq": 3, "kind": "obligation", "time": 10}\n'
        '{"seq": 4, "kind": "task-done", "time": 12}\n'
    )
    assert steps_of(read_audit_trace(log)) == [(10, "E", {}), (12, None, {})]


def test_a_lone_torn_record_is_an_empty_audit_log(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_text('{"seq":1,"kind":"ev')
    assert read(log) == []


def test_audit_records_may_repeat_a_header_key(tmp_path: Path) -> None:
    """The Manager writes its header (``rules``: the digest) before a record's data, which may
    reuse the name (a conflict's ``rules``): a record as written is read, not refused."""
    log = tmp_path / "audit.jsonl"
    log.write_text(
        '{"seq":1,"kind":"conflict","time":3,"rules":"e4e99dbb","rules":["R1","R2"]}\n'
        '{"seq":2,"kind":"event","time":4,"rules":"e4e99dbb","event":"E"}\n'
    )
    assert steps_of(read_audit_trace(log)) == [(3, None, {}), (4, "E", {})]


# ---------------------------------------------------------------------------- read once (pipes)


def piped(data: bytes) -> tuple[str, threading.Thread]:
    """``/dev/fd/N`` of a pipe a thread fills with ``data`` (as ``<(cat trace)`` gives a path)."""
    r, w = os.pipe()

    def feed() -> None:
        try:
            with os.fdopen(w, "wb") as fh:
                fh.write(data)
        except BrokenPipeError:  # the reader stopped early: that is the bug a test shows
            pass

    thread = threading.Thread(target=feed, daemon=True)
    thread.start()
    return f"/dev/fd/{r}", thread


@pytest.mark.skipif(not Path("/dev/fd").is_dir(), reason="needs /dev/fd")
def test_a_pipe_is_read_once_whole(tmp_path: Path) -> None:
    """A pipe can be read once: detecting the format must not consume what the parser reads."""
    lines = [{"t": 0, "event": "UserFallen"}, *({"t": n} for n in range(1, 3000))]
    data = "".join(json.dumps(x) + "\n" for x in lines).encode()
    path, thread = piped(data)
    try:
        steps = read(path)
    finally:
        os.close(int(path.rsplit("/", 1)[1]))
        thread.join(5)
    assert len(steps) == len(lines) and steps[0].event == "UserFallen" and steps[-1].t == 2999


@pytest.mark.skipif(not Path("/dev/fd").is_dir(), reason="needs /dev/fd")
def test_a_piped_audit_log_keeps_its_records_and_drops_a_torn_tail(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    whole = read_audit_trace(log)
    path, thread = piped(log.read_bytes() + b'{"seq":999,"kind":"event","time":700.0,"ev')
    try:
        rec = read_recording(path)
    finally:
        os.close(int(path.rsplit("/", 1)[1]))
        thread.join(5)
    assert rec.audit and rec.steps == whole


# ---------------------------------------------------------------------------- negative times


@pytest.mark.parametrize("t", ["-5", "-0.001", "-1e300"])
def test_a_negative_time_is_an_error(tmp_path: Path, t: str) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text(f'\n{{"t": {t}, "event": "UserFallen"}}\n{{"t": 1}}\n')
    with pytest.raises(TraceError, match="negative") as e:
        read_trace(f)
    assert e.value.where == f"{f}:2"
    assert "seconds from the start of the run" in e.value.hint and ">= 0" in e.value.hint


def test_minus_zero_is_the_start(tmp_path: Path) -> None:
    f = tmp_path / "trace.jsonl"
    f.write_text('{"t": -0.0}\n{"t": 0}\n')
    assert [s.t for s in read_trace(f)] == [0, 0]


# ---------------------------------------------------------------------------- options records


def options_record(seq: int, time: float, run: str = "r1", **over: object) -> str:
    """An ``options`` audit record as the Manager writes it at start()."""
    rec: dict[str, object] = {
        "seq": seq,
        "kind": "options",
        "time": time,
        "wall": "2026-01-01T00:00:00.000000+00:00",
        "mono": 1.5,
        "run": run,
        "rules": "06700cf8c39a7f6f",
        "semantics": "nested",
        "priorities": [["Rule21", "Rule3"]],
        "priority_semantics": "conflict-aware",
        "priority_lead": 2.5,
        "untimed": "immediate",
    }
    rec.update(over)
    return json.dumps(rec, separators=(",", ":")) + "\n"


def decision_record(seq: int, time: float, semantics: str, run: str = "r1") -> str:
    return (
        json.dumps(
            {
                "seq": seq,
                "kind": "decision",
                "time": time,
                "run": run,
                "rules": "x",
                "type": "decision",
                "id": seq,
                "event": "UserFallen",
                "rule": "Rule3",
                "clause": 0,
                "semantics": semantics,
            },
            separators=(",", ":"),
        )
        + "\n"
    )


def test_the_options_of_an_audit_log_are_read_with_its_steps(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_text(
        options_record(1, 0)
        + '{"seq":2,"kind":"event","time":0,"run":"r1","rules":"x","event":"UserFallen"}\n'
        + decision_record(3, 0, "nested")
        + decision_record(4, 0, "nested")
    )
    rec = read_recording(log)
    assert rec.audit and steps_of(rec.steps) == [(0, None, {}), (0, "UserFallen", {})]
    assert rec.options == RunOptions(
        semantics="nested",
        priorities=(("Rule21", "Rule3"),),
        priority_semantics="conflict-aware",
        priority_lead=2.5,
        untimed="immediate",
    )
    assert rec.options is not None and rec.options.line == 1 and rec.options.run == "r1"
    assert rec.options.unknown is None  # not in this record
    assert not rec.options_differ
    assert rec.decision_semantics == {"nested": 2}
    assert read(log) == rec.steps  # the options record is no step of its own beyond time


def test_a_log_without_options_and_a_written_trace_have_none(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    rec = read_recording(log)
    if rec.options is not None:  # the Manager writes them since issue 12
        assert rec.options.semantics == "last-wins"
    assert rec.audit and rec.decision_semantics == {"last-wins": 2}
    f = tmp_path / "trace.jsonl"
    f.write_text('{"t": 0, "event": "UserFallen"}\n')
    rec = read_recording(f)
    assert not rec.audit and rec.options is None and rec.decision_semantics == {}


def test_several_runs_the_last_options_count(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    same = options_record(1, 0, "r1") + options_record(2, 5, "r2")
    log.write_text(same)
    assert not read_recording(log).options_differ
    log.write_text(same + options_record(3, 9, "r3", semantics="last-wins", untimed=30))
    rec = read_recording(log)
    assert rec.options_differ
    assert rec.options is not None and rec.options.line == 3 and rec.options.run == "r3"
    assert rec.options.semantics == "last-wins" and rec.options.untimed == 30.0
    # the order of the priority pairs is no difference
    log.write_text(
        options_record(1, 0, "r1", priorities=[["A", "B"], ["C", "D"]])
        + options_record(2, 5, "r2", priorities=[["C", "D"], ["A", "B"], ["A", "B"]])
    )
    assert not read_recording(log).options_differ


@pytest.mark.parametrize(
    ("over", "message"),
    [
        ({"semantics": "nestd"}, "semantics"),
        ({"semantics": None}, "semantics"),
        ({"priorities": "R1 > R2"}, "priorities"),
        ({"priorities": [["R1"]]}, "priorities"),
        ({"priorities": [["R1", 2]]}, "priorities"),
        ({"priority_semantics": "first"}, "priority_semantics"),
        ({"priority_lead": -1}, "priority_lead"),
        ({"priority_lead": "1"}, "priority_lead"),
        ({"priority_lead": True}, "priority_lead"),
        ({"untimed": "later"}, "untimed"),
        ({"untimed": -3}, "untimed"),
        ({"untimed": None}, "untimed"),
        ({"unknown": "maybe"}, "unknown"),
    ],
)
def test_a_bad_options_record_is_an_error(tmp_path: Path, over: dict[str, object], message: str) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_text('{"seq":1,"kind":"event","time":0,"event":"UserFallen"}\n' + options_record(2, 0, **over))
    with pytest.raises(TraceError, match=message) as e:
        read_recording(log)
    assert e.value.where == f"{log}:2"


def test_an_options_record_missing_a_field_is_an_error(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    rec = json.loads(options_record(1, 0))
    del rec["untimed"]
    log.write_text(json.dumps(rec) + "\n")
    with pytest.raises(TraceError, match="untimed") as e:
        read_recording(log)
    assert e.value.where == f"{log}:1"


def test_a_real_manager_records_its_options(tmp_path: Path) -> None:
    """Manager.start() writes an ``options`` record (issue 12); skipped until the runtime does."""
    log = tmp_path / "audit.jsonl"
    rules = (
        "def_start event T event A def_end\n"
        "rule_start\n R1 when T then A within 5 seconds\n R2 when T then not A within 9 seconds\nrule_end\n"
    )
    m = Manager.from_text(
        rules, clock=VirtualClock(), audit=log, semantics="nested", priorities=["R1 > R2"], dispatch=False
    )
    m.start()
    m.event("T")
    m.close()
    rec = read_recording(log)
    if rec.options is None:
        pytest.skip("this Manager writes no options record yet")
    assert rec.options.semantics == "nested"
    assert rec.options.priorities == (("R1", "R2"),)
    assert rec.options.priority_semantics == "cancel"
    assert rec.options.priority_lead == 0
    assert rec.options.untimed == "none"
    assert rec.options.unknown in (None, "undetermined")
    assert rec.decision_semantics == {"nested": 2}  # R1 and R2


# ---------------------------------------------------------------------------- other rules


NEW_RULES = """def_start
    event UserFallen
    event SmokeDetected
    event CallSupport
    measure assentToSupportCalls : boolean
    measure alarmOn : boolean
    measure level : numeric
def_end
rule_start
    Rule3 when UserFallen and not assentToSupportCalls then not CallSupport within 10 minutes
rule_end
"""


def test_fit_trace_drops_what_other_rules_do_not_declare(tmp_path: Path) -> None:
    """An audit log checked against a new version of the rules: unknown names are dropped,
    values of a changed type become unknown, and each is said once."""
    steps = [
        Step(0, values={"assentToSupportCalls": False, "temperature": 21.5, "level": "medium"}, line=1),
        Step(0, event="UserFallen", line=2),
        Step(1, event="Dance", values={"heartRate": 80}, line=3),
        Step(2, values={"temperature": 20, "level": 3}, line=4),
    ]
    fitted, notes = fit_trace(parse(NEW_RULES), steps)
    assert steps_of(fitted) == [
        (0, None, {"assentToSupportCalls": False, "level": None}),
        (0, "UserFallen", {}),
        (1, None, {}),
        (2, None, {"level": 3}),
    ]
    assert [s.line for s in fitted] == [1, 2, 3, 4]
    assert notes == [
        "not in these rules, ignored: Dance, heartRate, temperature",
        "not of the type these rules declare, read as unknown: level (numeric): 'medium' (line 1)",
    ]
    assert fit_trace(parse(RULES), steps[:2]) == (steps[:2], [])
    # a name declared as the other kind is said so
    _, notes = fit_trace(parse(NEW_RULES), [Step(0, event="alarmOn", values={"CallSupport": 1})])
    assert notes == ["not in these rules, ignored: CallSupport (an event here), alarmOn (a measure here)"]
