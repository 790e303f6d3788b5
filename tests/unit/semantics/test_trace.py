"""Traces and audit logs read as steps: every way a line can be wrong names its line, and a
Manager's audit log reads back as what the Manager was fed."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest

from cosleec.lang import parse
from cosleec.runtime import ContextError, Manager, VirtualClock
from cosleec.semantics import Step
from cosleec.semantics.trace import TraceError, check_trace, read, read_audit, read_trace

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
    steps = read_audit(log)
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
    whole = read_audit(log)
    log.write_bytes(log.read_bytes() + b'{"seq":999,"kind":"event","time":700.0,"ev')
    assert read_audit(log) == whole
    assert read(log) == whole


def test_audit_log_bad_lines_are_errors(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    run_manager(log)
    lines = log.read_text().splitlines()
    n = len(lines)
    whole = read_audit(log)
    log.write_text("\n".join([*lines[:2], '{"seq":3,"kind":"event","ti', *lines[2:]]) + "\n")
    with pytest.raises(TraceError, match="not valid JSON") as e:
        read_audit(log)
    assert e.value.where.startswith(f"{log}:3:")
    # a complete but unterminated last line is a record all the same; a broken one with a newline is not
    log.write_text("\n".join(lines))
    assert read_audit(log) == whole
    log.write_text("\n".join([*lines, '{"seq":', ""]))
    with pytest.raises(TraceError) as e:
        read_audit(log)
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
    assert steps_of(read_audit(log)) == [(10, "E", {}), (12, None, {})]


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
    assert steps_of(read_audit(log)) == [(3, None, {}), (4, "E", {})]
