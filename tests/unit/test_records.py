"""The record format, defined once (issue 29, part 3): its kinds, the fields of each, the one
writer of audit lines and the one reader, each built and checked on its own."""

from __future__ import annotations

import collections
import dataclasses
import datetime
import enum
import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.records import (
    FIELDS,
    HEADER,
    AuditRecord,
    Json,
    Kind,
    RecordError,
    RuntimeEvent,
    as_object,
    audit_lines,
    check_fields,
    load_json,
    problem,
    read_records,
    records_in,
    seconds,
    starts_audit_log,
)
from cosleec.records.kinds import BY_VALUE
from tests.unit.runtime.test_conflicts import CURTAINS

WALL = "2026-01-01T00:00:00.000000+00:00"
HEAD = f'"wall":"{WALL}","mono":12.5,"run":"run-1","rules":"0123456789abcdef"'


def lines_of(*events: RuntimeEvent) -> list[str]:
    return audit_lines(events, run="run-1", rules="0123456789abcdef0123456789", wall=WALL, mono=12.5)


def numbered(*texts: str) -> list[tuple[int, str]]:
    return list(enumerate(texts, 1))


# ---------------------------------------------------------------------------- kinds


def test_each_kind_keeps_the_string_logs_hold() -> None:
    """The values are the format: a log of any version is read by them."""
    assert {k.value for k in Kind} == {
        "options", "event", "context", "layers", "semantics", "decision", "obligation",
        "refused", "rejected", "conflict", "cancelled", "held", "dispatch", "withheld",
        "task-done", "task-failed", "task-interrupted", "restored", "reloaded",
        "reload-attempt", "dropped", "uncommitted", "audit-mismatch", "journal-reset",
        "observer-removed",
    }  # fmt: skip
    occurrence: str = Kind.OCCURRENCE
    assert occurrence == "event" and hash(occurrence) == hash("event")
    assert f"{Kind.TASK_DONE}" == "task-done" and json.dumps({"k": Kind.TASK_DONE}) == '{"k": "task-done"}'
    assert all(BY_VALUE[k.value] is k for k in Kind)


def test_a_runtime_event_is_made_as_constructed_and_compares_with_strings() -> None:
    fast = RuntimeEvent.made(Kind.DECISION, 1.5, {"a": 1}, 7)
    assert fast == RuntimeEvent(Kind.DECISION, 1.5, {"a": 1}, 7) and fast.kind is Kind.DECISION
    kind: str = fast.kind
    assert kind == "decision"


# ---------------------------------------------------------------------------- fields


def test_every_kind_has_its_fields_and_nothing_else_does() -> None:
    assert set(FIELDS) == set(Kind)
    for kind, fields in FIELDS.items():
        names = [f.name for f in fields]
        assert len(names) == len(set(names)), kind  # each field once
        assert not set(names) & set(HEADER) - {"rules"}, kind  # no field hides a header key


@pytest.mark.parametrize(
    ("kind", "data", "said"),
    [
        ("event", {}, "an event record names no event: None"),
        ("event", {"event": ""}, "an event record names no event: ''"),
        ("event", {"event": 3}, "an event record names no event: 3"),
        ("context", {"values": 3}, "a context record has no values: 3"),
        ("decision", {"id": 1, "rule": 3, "event": "E", "clause": 0}, "a decision record has no rule (a non-empty string): 3"),
        ("decision", {"id": True, "rule": "R", "event": "E", "clause": 0}, "a decision record has no id (a whole number): True"),
        ("obligation", {"id": 1, "decision": 1, "rule": "R", "event": "E", "status": "pending"}, "an obligation record has no start (a number): None"),
    ],
)  # fmt: skip
def test_a_required_field_missing_or_mistyped_is_named(kind: str, data: dict[str, Any], said: str) -> None:
    assert problem(kind, data) == said


def test_optional_fields_are_checked_only_on_request_and_unknown_kinds_never() -> None:
    data = {"event": "E", "causal": "first"}
    assert problem("event", data) is None
    assert problem("event", data, optional=True) == "an event record has no causal (a whole number): 'first'"
    assert problem("event", {"event": "E", "causal": 3}, optional=True) is None
    assert (
        problem("clause", {"event": "E", "clause": 3, "more": [1]}) is None
    )  # a later kind: nothing to check
    assert problem("decision", {"id": 1, "rule": "R", "event": "E", "clause": None}) is None  # null allowed


@pytest.mark.parametrize(
    ("json_type", "holds", "not_held"),
    [
        (Json.NAME, ["E"], ["", 1, None]),
        (Json.TEXT, ["", "E"], [1, None, True]),
        (Json.INT, [0, -3], [True, 1.0, "1"]),
        (Json.NUMBER, [0, 1.5], [True, False, "1", None]),
        (Json.BOOL, [True, False], [0, 1, None]),
        (Json.LIST, [[], [1]], [(), {}, "ab"]),
        (Json.OBJECT, [{}, {"a": 1}], [[], None]),
        (Json.NULL, [None], [0, "", False]),
        (Json.ANY, [None, 0, "x", [], {}], []),
    ],
)
def test_json_types_as_json_loads_gives_them(json_type: Json, holds: list[Any], not_held: list[Any]) -> None:
    assert all(json_type.holds(v) for v in holds)
    assert not any(json_type.holds(v) for v in not_held)


# ---------------------------------------------------------------------------- the writer


def test_a_decision_is_written_at_its_own_time_with_one_time_key() -> None:
    ev = RuntimeEvent.made(Kind.DECISION, 9.0, {"type": "decision", "id": 3, "time": 4.5, "rule": "R1"}, 7)
    assert lines_of(ev) == [
        f'{{"seq":7,"kind":"decision","time":4.5,{HEAD},"type":"decision","id":3,"rule":"R1"}}'
    ]
    assert ev.data["time"] == 4.5  # the event itself is not changed


def test_a_record_without_data_closes_after_the_header() -> None:
    ev = RuntimeEvent.made(Kind.JOURNAL_RESET, 1.0, {}, 8)
    assert lines_of(ev) == [f'{{"seq":8,"kind":"journal-reset","time":1.0,{HEAD}}}']


@pytest.mark.parametrize("t", [math.inf, -math.inf, math.nan])
def test_a_time_that_is_not_finite_is_null(t: float) -> None:
    ev = RuntimeEvent.made(Kind.OCCURRENCE, t, {"event": "E", "causal": 2}, 9)
    assert lines_of(ev) == [f'{{"seq":9,"kind":"event","time":null,{HEAD},"event":"E","causal":2}}']


def test_values_json_cannot_hold_are_written_as_text_and_one_header_serves_a_step() -> None:
    a = RuntimeEvent.made(Kind.REJECTED, 2, {"reason": "é", "what": Path("/x")}, 1)
    b = RuntimeEvent.made(Kind.DROPPED, 2.25, {"what": "m"}, 2)
    assert lines_of(a, b) == [
        f'{{"seq":1,"kind":"rejected","time":2,{HEAD},"reason":"\\u00e9","what":"/x"}}',
        f'{{"seq":2,"kind":"dropped","time":2.25,{HEAD},"what":"m"}}',
    ]
    fresh = audit_lines([a, b], run="r", rules="d")  # the clocks read once, for the whole step
    heads = [{k: v for k, v in json.loads(line).items() if k in ("wall", "mono")} for line in fresh]
    assert (
        heads[0] == heads[1] and isinstance(heads[0]["mono"], float) and heads[0]["wall"].endswith("+00:00")
    )


class _Shown:
    """A value JSON cannot hold: written as its ``str``."""

    def __str__(self) -> str:
        return "shown ü"


class _Float(float):
    pass


class _Level(enum.IntEnum):
    HIGH = 2


@dataclasses.dataclass
class _Pose:
    x: int = 1


_Pair = collections.namedtuple("_Pair", "a b")

# (what the runtime's records hold, and each kind of value orjson writes otherwise than json:
# the hostile review's list -- a subclass of float, int or tuple, a dataclass, a datetime, DEL)
_ATOMS = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**70), max_value=2**70)  # beyond 64 bits too
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=8)  # not only ASCII
    | st.text("a\x7f\x1f\u00e9", max_size=4)
    | st.sampled_from(
        [
            _Shown(),
            Path("/x"),
            Kind.DECISION,
            _Float(1.5),
            _Level.HIGH,
            _Pose(),
            _Pair(1, 2),
            datetime.datetime(2020, 1, 1, 1, 2, 3),
            datetime.date(2020, 1, 1),
        ]
    )
)
_DATA = st.recursive(
    _ATOMS,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.tuples(inner, inner)
        | st.dictionaries(st.text(max_size=6) | st.integers(-5, 5) | st.booleans(), inner, max_size=4)
    ),
    max_leaves=12,
)


def _exponents(x: object) -> bool:
    """Does ``x`` hold a float whose repr has an exponent (spelt differently by orjson)?"""
    if isinstance(x, float):
        return "e" in repr(x)
    if isinstance(x, dict):
        return any(_exponents(k) or _exponents(v) for k, v in x.items())
    if isinstance(x, list | tuple):
        return any(map(_exponents, x))
    return False


@given(st.dictionaries(st.text(max_size=6), _DATA, max_size=5))
def test_the_fast_encoder_writes_what_json_writes(data: dict[str, Any]) -> None:
    """``encode`` (orjson where it writes alike) against ``json.dumps(data, default=str,
    separators=(",", ":"))``: the same text, ASCII only, but for a float's exponent, spelt
    ``1e16`` for ``1e+16``: the same numbers read back."""
    from cosleec.records.encode import encode

    want = json.dumps(data, default=str, separators=(",", ":"))
    got = encode(data)
    assert got.isascii()
    assert json.loads(got) == json.loads(want)
    if not _exponents(data):
        assert got == want


def test_a_record_that_may_hold_what_a_caller_gave_is_written_by_json() -> None:
    """A front end's ``note`` keeps what it was given: its record is written by json, a float
    that is not finite as json writes it (orjson would write null)."""
    a = RuntimeEvent.made(Kind.REJECTED, 2, {"reason": "r", "value": math.inf}, 1)
    assert lines_of(a) == [f'{{"seq":1,"kind":"rejected","time":2,{HEAD},"reason":"r","value":Infinity}}']


def test_a_record_as_one_object_is_kind_time_then_data() -> None:
    assert as_object(Kind.DECISION, 9.0, {"id": 1, "time": 4.5}) == {"kind": "decision", "time": 4.5, "id": 1}
    assert list(as_object("x", 1.0, {"a": 1})) == ["kind", "time", "a"]


# ---------------------------------------------------------------------------- the reader


def test_what_the_writer_writes_the_reader_reads_back_typed() -> None:
    written = lines_of(
        RuntimeEvent.made(
            Kind.DECISION, 9.0, {"id": 3, "time": 4.5, "rule": "R1", "event": "E", "clause": 0}, 7
        ),
        RuntimeEvent.made(Kind.OCCURRENCE, 5, {"event": "E"}, 8),
    )
    dec, occ = records_in(numbered(*written), "log")
    assert dec == AuditRecord(
        seq=7,
        kind=Kind.DECISION,
        time=4.5,
        data={"id": 3, "rule": "R1", "event": "E", "clause": 0},
        run="run-1",
        rules="0123456789abcdef",
        wall=WALL,
        mono=12.5,
        line=1,
    )
    assert dec.kind is Kind.DECISION and occ.line == 2
    for rec, line in zip((dec, occ), written, strict=True):
        assert rec.to_json() == json.loads(line)
        assert json.dumps(rec.to_json(), separators=(",", ":")) == line  # key order too
    assert type(occ.time) is int and type(occ.to_json()["time"]) is int  # the number as written


def test_a_kind_this_version_does_not_know_is_read_as_its_string() -> None:
    (rec,) = records_in(numbered('{"seq":1,"kind":"observed-later","time":0,"x":1}'), "log")
    assert rec.kind == "observed-later" and not isinstance(rec.kind, Kind) and rec.data == {"x": 1}


def test_a_header_key_the_data_reuses_stays_data() -> None:
    """An old conflict record wrote its rules after the digest: the data's value is the one read."""
    text = '{"seq":1,"kind":"conflict","time":3,"rules":"e4e99dbb","rules":["R1","R2"],"run":7}'
    (rec,) = records_in(numbered(text), "log")
    assert rec.rules is None and rec.run is None and rec.data == {"rules": ["R1", "R2"], "run": 7}
    assert rec.to_json() == json.loads(text)


def test_blank_lines_are_skipped_and_lines_keep_their_numbers() -> None:
    recs = list(
        records_in(
            numbered("", '{"seq":1,"kind":"event","time":0}', "  ", '{"seq":2,"kind":"event","time":1}'), "f"
        )
    )
    assert [(r.seq, r.line) for r in recs] == [(1, 2), (2, 4)]


@pytest.mark.parametrize(
    ("text", "message", "where"),
    [
        ('{"seq":2,"kind":"event","ti', "not valid JSON", "f:2:"),
        ('{"t": 0, "event": "E"}', "not an audit record (a JSON object with seq, kind and time)", "f:2"),
        ("[1]", "not an audit record", "f:2"),
        ('{"seq":"2","kind":"event","time":0}', "not an audit record", "f:2"),
        ('{"seq":true,"kind":"event","time":0}', "not an audit record", "f:2"),
        ('{"seq":2,"kind":3,"time":0}', "not an audit record", "f:2"),
        ('{"seq":2,"kind":"event"}', 'the line has no time "time"', "f:2"),
        ('{"seq":2,"kind":"event","time":"soon"}', "\"time\" is a number of seconds, not 'soon'", "f:2"),
        ('{"seq":2,"kind":"event","time":null}', '"time" is a number of seconds, not None', "f:2"),
        ('{"seq":2,"kind":"event","time":1e999}', '"time" must be a finite number', "f:2"),
        ('{"seq":2,"kind":"event","time":' + "9" * 400 + "}", '"time" must be a finite number', "f:2"),
        ('{"seq":2,"kind":"event","time":' + "9" * 5000 + "}", "more than 4,300 digits", "f:2"),
        ("[" * 100000, "nested too deeply", "f:2"),
    ],
)
def test_a_line_that_is_no_record_is_refused_with_its_place(text: str, message: str, where: str) -> None:
    with pytest.raises(RecordError, match=message.replace("(", r"\(").replace(")", r"\)")) as e:
        list(records_in(numbered('{"seq":1,"kind":"event","time":0}', text), "f"))
    assert e.value.where.startswith(where) and (e.value.where == where) == (not where.endswith(":"))
    assert e.value.hint


def test_a_torn_last_line_is_skipped_only_when_the_text_ends_there() -> None:
    lines = numbered('{"seq":1,"kind":"event","time":0}', '{"seq":2,"kind":"ev')
    assert [r.seq for r in records_in(lines, "f", complete=False)] == [1]
    with pytest.raises(RecordError, match="not valid JSON"):
        list(records_in(lines, "f", complete=True))
    torn_first = numbered('{"seq":1,"kind":"ev', '{"seq":2,"kind":"event","time":0}')
    with pytest.raises(RecordError) as e:  # only the last line can be torn
        list(records_in(torn_first, "f", complete=False))
    assert e.value.where.startswith("f:1:")
    whole_but_unterminated = numbered('{"seq":1,"kind":"event","time":0}', '{"seq":2,"kind":"x","time":0}')
    assert [r.seq for r in records_in(whole_but_unterminated, "f", complete=False)] == [1, 2]
    not_a_record = numbered('{"seq":1,"kind":"event","time":0}', '{"a":1}')
    with pytest.raises(RecordError, match="not an audit record"):  # JSON, so not torn
        list(records_in(not_a_record, "f", complete=False))


def test_leniently_every_line_that_is_no_record_is_skipped_and_a_null_time_kept() -> None:
    lines = numbered(
        '{"seq":1,"kind":"event","ti',
        '{"seq":2,"kind":"event","time":null}',
        "[1]",
        '{"a":1}',
        '{"seq":3,"kind":"event","time":"soon"}',
        '{"seq":4,"kind":"event","time":1e999}',
        '{"seq":5,"kind":"event"}',
        '{"seq":6,"kind":"event","time":6}',
    )
    recs = list(records_in(lines, "f", lenient=True))
    assert [(r.seq, r.time) for r in recs] == [(2, None), (6, 6)]
    assert recs[0].to_json() == {"seq": 2, "kind": "event", "time": None}


def test_read_records_reads_a_file(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    log.write_bytes(b'\xef\xbb\xbf{"seq":1,"kind":"event","time":0,"event":"E"}\r\n{"seq":2,"kind":"ev')
    assert [r.seq for r in read_records(log)] == [1]  # a BOM, CRLF, a torn tail
    log.write_bytes(b'{"seq":1,"kind":"event","time":0}\n{"seq":2,"kind":"event","time":1,"x":"\xff"}\n')
    with pytest.raises(RecordError, match="not UTF-8") as e:
        read_records(log)
    assert e.value.where == f"{log}:2"
    assert [r.data for r in read_records(log, lenient=True)] == [{}, {"x": "\ufffd"}]
    with pytest.raises(FileNotFoundError):
        read_records(tmp_path / "missing.jsonl")


def test_check_fields_refuses_a_record_lacking_what_its_kind_requires() -> None:
    rec = AuditRecord(seq=1, kind=Kind.CONTEXT, time=0, data={"values": [1]}, line=4)
    with pytest.raises(RecordError, match="a context record has no values: \\[1\\]") as e:
        check_fields(rec, "log")
    assert e.value.where == "log:4"
    check_fields(AuditRecord(seq=1, kind=Kind.CONTEXT, time=0, data={"values": {}}, line=4), "log")


@pytest.mark.parametrize(
    ("first", "is_log"),
    [
        ('{"seq":1,"kind":"event","time":0}', True),
        ('{"seq":1,"kind":"ev', True),  # a log whose only record was torn
        ('  {"seq":1,"ki', True),
        ('{"kind":"event","seq":1}', True),
        ('{"t":0,"event":"E"}', False),
        ('{"seq":1}', False),
        ('{"t":0,"ev', False),
        ("", False),
    ],
)
def test_the_first_line_tells_an_audit_log(first: str, is_log: bool) -> None:
    assert starts_audit_log(first) is is_log


def test_load_json_names_the_column_and_lets_a_hook_error_through() -> None:
    with pytest.raises(RecordError) as e:
        load_json('{"a": oops}', "f:3", "fix it")
    assert str(e.value).startswith("not valid JSON") and e.value.where == "f:3:7" and e.value.hint == "fix it"

    class Stop(Exception):
        pass

    def hook(pairs: list[tuple[str, Any]]) -> Any:
        raise Stop

    with pytest.raises(Stop):
        load_json('{"a": 1}', "f:3", "fix it", hook=hook)


def test_seconds_are_finite_and_minus_zero_is_zero() -> None:
    assert seconds(5, True, "f:1", "t") == 5.0 and type(seconds(5, True, "f:1", "t")) is float
    assert math.copysign(1, seconds(-0.0, True, "f:1", "t")) == 1
    with pytest.raises(RecordError, match='"t" is a number of seconds, not True'):
        seconds(True, True, "f:1", "t")
    with pytest.raises(RecordError, match='no time "t"'):
        seconds(None, False, "f:1", "t")


# ---------------------------------------------------------------------------- what a Manager writes


def fits(log: Path) -> set[Kind]:
    """Every line of ``log`` is a record of a known kind with the fields of its kind, of their
    types, and no field the definition leaves out; returns the kinds seen."""
    records = read_records(log)
    seen: set[Kind] = set()
    for rec in records:
        assert isinstance(rec.kind, Kind), rec
        seen.add(rec.kind)
        assert problem(rec.kind, rec.data, optional=True) is None, rec
        assert set(rec.data) <= {f.name for f in FIELDS[rec.kind]}, (rec.kind, set(rec.data))
        assert None not in (rec.run, rec.rules, rec.wall, rec.mono), rec
    assert [r.seq for r in records] == list(range(1, len(records) + 1))
    return seen


def curtains(log: Path, window: str, **options: Any) -> Any:
    """The curtain rules on a virtual clock, writing ``log``; apologising fails."""
    from cosleec.runtime import Manager, VirtualClock

    clock = VirtualClock(0.0)
    m = Manager.from_text(CURTAINS.format(window=window), clock=clock, audit=log, **options)

    @m.capability("OpenCurtains")
    def open_curtains(ob: Any, d: Any) -> None:
        m.event("OpenCurtains")

    @m.capability("ApologiseToUser")
    def apologise(ob: Any, d: Any) -> None:
        raise RuntimeError("no voice")

    m.start()
    m.update(night=True)
    m.event("CurtainOpenRequest")
    for t in (30.5, 120.0):
        clock.set(t)
        m.tick()
    return m


def test_every_record_a_manager_writes_is_read_strictly_and_fits_its_kind(tmp_path: Path) -> None:
    """The definition is true of the runtime: a real day's log (a restart from the journal, a
    reload, rejections included) and the curtain conflicts' (held and dispatched, in conflict,
    cancelled by a priority, a failed task, a switch of semantics)."""
    from cosleec.demo import run
    from cosleec.demo.runner import rules_path
    from cosleec.runtime import ContextError, RuleSet

    day, journal = tmp_path / "day.jsonl", tmp_path / "state.db"

    def more(m: Any) -> None:
        m.reload(RuleSet.from_file(rules_path()))
        with pytest.raises(ContextError):
            m.update(noSuchMeasure=1)

    run(audit=str(day), journal=str(journal), before_close=more)
    run(audit=str(day), journal=str(journal))
    seen = fits(day)
    assert {Kind.OPTIONS, Kind.RESTORED, Kind.DECISION, Kind.OBLIGATION, Kind.RELOADED, Kind.REJECTED} <= seen
    assert {Kind.TASK_DONE, Kind.REFUSED, Kind.CONTEXT, Kind.LAYERS, Kind.OCCURRENCE} <= seen

    curtains(tmp_path / "held.jsonl", "30 seconds").close()
    m = curtains(tmp_path / "conflict.jsonl", "10 minutes")
    m.set_semantics("nested")
    m.close()
    curtains(tmp_path / "cancelled.jsonl", "10 minutes", priorities=["R1 > R2"]).close()
    seen = set().union(*(fits(tmp_path / f"{n}.jsonl") for n in ("held", "conflict", "cancelled")))
    assert {Kind.HELD, Kind.DISPATCH, Kind.CONFLICT, Kind.CANCELLED, Kind.TASK_FAILED, Kind.SEMANTICS} <= seen


def test_the_writer_writes_a_managers_log_byte_for_byte(tmp_path: Path) -> None:
    """Each line of a real day's audit log is what :func:`audit_lines` makes of the event the
    observers heard, given the line's own header: the Manager writes through the one writer."""
    from cosleec.demo import run

    log = tmp_path / "day.jsonl"
    events = {ev.seq: ev for ev in run(audit=str(log)).events}
    heard = [(json.loads(line), line) for line in log.read_text().splitlines()]
    heard = [(head, line) for head, line in heard if head["seq"] in events]  # (options: before subscribing)
    assert len(heard) == len(events) > 100
    for head, line in heard:
        (again,) = audit_lines(
            [events[head["seq"]]], run=head["run"], rules=head["rules"], wall=head["wall"], mono=head["mono"]
        )
        assert again == line


_JSONISH = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4),
    max_leaves=20,
)


@given(st.dictionaries(st.text(max_size=8), _JSONISH | st.sets(st.integers(), max_size=3), max_size=6))
def test_the_shared_audit_encoder_writes_what_json_dumps_writes(data: dict[str, object]) -> None:
    """The shared json encoder (records a caller may have given: NaN and infinities too), and
    the fast one where neither is: the same text but for a float's exponent."""
    from cosleec.records.encode import _json, encode

    want = json.dumps(data, default=str, separators=(",", ":"))
    assert _json(data) == want
    if "NaN" not in want and "Infinity" not in want:
        assert json.loads(encode(data)) == json.loads(want)
        if not _exponents(data):
            assert encode(data) == want
