"""Fail closed, stay bounded, act exactly once: the embedded runtime when it does not know.

Each test names the finding it pins down; each one failed on the code before the fix.
"""

from __future__ import annotations

import itertools
import json
import threading
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.cli.main import main
from cosleec.runtime import (
    BindingError,
    ConfigurationError,
    ContextError,
    JournalError,
    Manager,
    RuntimeEvent,
    VirtualClock,
    read_audit,
)

DEFS = "def_start event E event F event G event Rec event Help measure a : boolean measure b : boolean "


def manager(rules: str, defs: str = "", **kw: Any) -> tuple[Manager, VirtualClock]:
    clock = VirtualClock()
    text = f"{DEFS}{defs} def_end rule_start {rules} rule_end"
    return Manager.from_text(text, clock=clock, **kw), clock


# ---------------------------------------------------------------------------- unknown names


def test_a_request_for_an_undeclared_event_raises_with_the_closest_names() -> None:
    m, _ = manager("R1 when E then F")
    with pytest.raises(ContextError, match="unknown event 'Reec'") as e:
        m.request("Reec")
    assert "Rec" in e.value.hint
    assert m.stats["rejected"] == 1


def test_unknown_events_refuse_answers_false_and_records_why(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    m, _ = manager("R1 when E then F", unknown_events="refuse", audit=log)
    assert m.request("Typo").permitted is False
    assert m.event("Typo") == []
    m.close()
    rejected = [r for r in read_audit(log) if r["kind"] == "rejected"]
    assert [r["what"] for r in rejected] == ["request", "event"]
    assert all("unknown event 'Typo'" in r["reason"] for r in rejected)


def test_an_unknown_events_policy_that_does_not_exist_is_refused() -> None:
    with pytest.raises(ConfigurationError, match="unknown_events"):
        manager("R1 when E then F", unknown_events="allow")


def test_a_capability_for_an_event_no_response_names_is_refused_with_did_you_mean() -> None:
    m, _ = manager("R1 when E then F within 1 seconds otherwise Help")
    with pytest.raises(BindingError, match="did you mean Help"):
        m.capability("Hepl")
    with pytest.raises(BindingError, match="no rule's response"):
        m.capability("E")  # a trigger, never an obligation
    m.capability("Help")(lambda ob, d: None)  # an otherwise event is a response


def test_a_reason_never_echoes_a_huge_name_whole() -> None:
    m, _ = manager("R1 when E then F")
    with pytest.raises(ContextError) as e:
        m.update({"x" * 10_000_000: True})
    assert len(str(e.value)) < 300
    with pytest.raises(ContextError) as e:
        m.request("y" * 10_000_000)
    assert len(str(e.value)) < 300


# ---------------------------------------------------------------------------- Kleene


def test_or_with_an_unknown_side_is_true_whatever_the_operand_order() -> None:
    m, _ = manager("R1 when E and (a or b) then F R2 when E and (b or a) then G")
    m.update(a=True)  # b is unknown
    assert [(d.rule, d.clause) for d in m.event("E")] == [("R1", 0), ("R2", 0)]


def test_and_with_a_false_side_is_false_whatever_the_operand_order() -> None:
    m, _ = manager("R1 when E and (a and b) then F R2 when E and (b and a) then G")
    m.update(a=False)
    assert m.event("E") == []


def test_an_unknown_that_decides_the_trigger_makes_the_decision_undetermined() -> None:
    m, _ = manager("R1 when E and (a or b) then F")
    m.update(a=False)
    (d,) = m.event("E")
    assert d.undetermined and d.missing == ("b",)


def test_an_unless_over_or_is_decided_by_its_known_side() -> None:
    m, _ = manager("R1 when E then F unless (b or a) then G")
    m.update(a=True)
    (d,) = m.event("E")
    assert d.clause == 1  # before: KeyError on b, undetermined


# An independent oracle: Kleene's strong three-valued logic, from its truth tables.
K_AND = {(True, True): True, (True, None): None, (None, True): None, (None, None): None}
K_OR = {(False, False): False, (False, None): None, (None, False): None, (None, None): None}


def k_and(x: bool | None, y: bool | None) -> bool | None:
    if x is False or y is False:
        return False
    return K_AND[(x, y)]


def k_or(x: bool | None, y: bool | None) -> bool | None:
    if x is True or y is True:
        return True
    return K_OR[(x, y)]


exprs = st.recursive(
    st.sampled_from(["a", "b", "c", "true", "false"]),
    lambda inner: st.one_of(
        st.tuples(st.just("not"), inner),
        st.tuples(st.sampled_from(["and", "or"]), inner, inner),
    ),
    max_leaves=8,
)


def text(e: Any) -> str:
    if isinstance(e, str):
        return e
    if e[0] == "not":
        return f"(not {text(e[1])})"
    return f"({text(e[1])} {e[0]} {text(e[2])})"


def oracle(e: Any, env: dict[str, bool | None]) -> bool | None:
    if isinstance(e, str):
        return {"true": True, "false": False}.get(e, env.get(e))
    if e[0] == "not":
        x = oracle(e[1], env)
        return None if x is None else not x
    f = k_and if e[0] == "and" else k_or
    return f(oracle(e[1], env), oracle(e[2], env))


@settings(max_examples=300, deadline=None)
@given(exprs, st.fixed_dictionaries({n: st.sampled_from([True, False, None]) for n in "abc"}))
def test_conditions_are_kleene_three_valued(e: Any, env: dict[str, bool | None]) -> None:
    m, _ = manager(f"R1 when E then F unless {text(e)} then G", defs="measure c : boolean")
    known = {k: v for k, v in env.items() if v is not None}
    if known:
        m.update(known)
    (d,) = m.event("E")
    want = oracle(e, env)
    assert d.conditions[1][2] == want
    assert d.clause == (None if want is None else 1 if want else 0)


# ---------------------------------------------------------------------------- undetermined


def test_an_undetermined_decision_keeps_every_prohibition_a_reading_of_it_imposes() -> None:
    # R1 forbids recording unless the user consented: consent unknown must not allow recording
    m, _ = manager("R1 when E then not Rec within 10 minutes unless a then F")
    m.event("E")
    assert m.decisions[-1].undetermined
    assert m.request("Rec").permitted is False  # before: True (no obligation at all)


INNER = "R1 when E then F unless b then { not Rec within 10 minutes unless a then G }"


def test_an_undetermined_inner_unless_is_not_read_as_false() -> None:
    # the braced inner response's own unless over an unknown measure
    m, _ = manager(INNER)
    m.update(b=True)
    (d,) = m.event("E")
    assert d.undetermined and d.missing == ("a",)
    assert m.request("Rec").permitted is False  # before: the unless counted as false... and here, true
    assert d.obligations and all(o.negated for o in d.obligations)


def test_a_determined_inner_unless_takes_its_clause() -> None:
    m, _ = manager(INNER)
    m.update(b=True, a=True)
    (d,) = m.event("E")
    assert d.clause == 1 and [o.event for o in d.obligations] == ["G"]
    assert m.request("Rec").permitted is True
    m.update(a=False)
    (d,) = m.event("E")
    assert [(o.event, o.negated) for o in d.obligations] == [("Rec", True)]
    assert m.request("Rec").permitted is False


def test_an_undetermined_inner_unless_of_an_otherwise_runs_nothing() -> None:
    m, clock = manager(
        "R1 when E then F within 1 seconds otherwise { not Rec within 10 minutes unless a then G }"
    )
    ran: list[str] = []
    m.capability("F")(lambda ob, d: None)
    m.capability("G")(lambda ob, d: ran.append("G"))
    m.start()
    m.event("E")
    clock.advance(2)
    assert m.tick() == []  # no fallback dispatched
    assert ran == [] and m.request("Rec").permitted is False
    assert m.decisions[-1].event == "otherwise" and m.decisions[-1].undetermined


def test_a_prohibition_whose_deadline_is_unknown_stays_in_force(tmp_path: Path) -> None:
    m, clock = manager("R1 when E then not Rec within (n) seconds", defs="measure n : numeric")
    m.event("E")
    clock.advance(10**6)
    assert m.request("Rec").permitted is False


# ---------------------------------------------------------------------------- bad values


def test_a_number_beyond_float_range_is_rejected_and_nothing_changes(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F within (n) seconds", defs="measure n : numeric", audit=log)
    with pytest.raises(ContextError, match="finite"):
        m.update(n=10**5000)
    assert m.values()["n"] is None
    m.close()
    started, rec = read_audit(log)  # the update started the Manager: its options record first
    assert started["kind"] == "options"
    assert rec["kind"] == "rejected" and len(json.dumps(rec)) < 1000


def test_a_deadline_too_large_for_the_runtime_is_a_user_error(tmp_path: Path, capsys: Any) -> None:
    f = tmp_path / "big.sleec"
    f.write_text(
        f"def_start event E event F def_end rule_start R1 when E then F within {'9' * 400} seconds rule_end"
    )
    assert main(["decide", str(f), "--event", "E"]) == 1
    err = capsys.readouterr().err
    assert f"{f}:1:" in err and "longer than the runtime can keep" in err and len(err) < 600


def test_a_huge_measure_dependent_deadline_is_read_fail_closed() -> None:
    m, clock = manager("R1 when E then F within (n) days", defs="measure n : numeric")
    m.update(n=1e300)  # longer than the runtime keeps
    (d,) = m.event("E")
    assert d.obligations[0].within_s == 0.0  # due now: the strictest reading
    clock.advance(1)
    m.tick()
    assert m.stats["violations"] == 1


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf"), 10**400, 1e300, "3", True])
def test_the_virtual_clock_accepts_only_finite_times(bad: Any) -> None:
    c = VirtualClock(5)
    with pytest.raises(ValueError):
        c.set(bad)
    with pytest.raises(ValueError):
        c.advance(bad)
    assert c.now() == 5


def test_untimed_and_max_depth_options_are_checked() -> None:
    with pytest.raises(ConfigurationError, match="untimed"):
        manager("R1 when E then F", untimed="bogus")
    with pytest.raises(ConfigurationError, match="untimed"):
        manager("R1 when E then F", untimed=float("nan"))
    with pytest.raises(ConfigurationError, match="max_depth"):
        manager("R1 when E then F", max_depth=0)


# ---------------------------------------------------------------------------- bounded


def test_a_missed_deadline_is_reported_late_once(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, clock = manager("R1 when E then F within 1 seconds", audit=log)
    m.event("E")
    clock.advance(2)
    m.tick()
    for _ in range(50):
        clock.advance(1)
        m.event("F")
    m.close()
    records = read_audit(log)
    late = [r for r in records if r["kind"] == "obligation" and r["late"]]
    assert len(late) == 1 and late[0]["late"] == [3.0]
    assert max(len(json.dumps(r)) for r in records) < 2000


def test_tick_releases_the_lock_between_batches() -> None:
    m, clock = manager("R1 when E then F within 1 seconds")
    for _ in range(3000):
        m.event("E")
    blocked: list[tuple[bool, int]] = []

    def observer(ev: RuntimeEvent) -> None:  # runs between steps, outside the lock
        if ev.kind == "obligation" and ev.data["status"] == "violated" and not blocked:
            judged = m.stats["violations"]
            t = threading.Thread(target=m.request, args=("F",))  # it judges the rest itself
            t.start()
            t.join(5)
            blocked.append((t.is_alive(), judged))

    m.subscribe(observer)
    clock.advance(2)  # the virtual clock ticks the Manager: in batches
    assert m.tick() == []
    # after the first batch of 1000, with work left, another thread could take the lock
    assert blocked == [(False, 1000)]
    assert m.stats["violations"] == 3000


# ---------------------------------------------------------------------------- order


def test_the_audit_log_and_observers_see_records_in_the_order_they_were_made(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F within 1 seconds unless a then G", audit=log)
    seen: list[int] = []
    m.subscribe(lambda ev: seen.append(ev.seq))

    def work(i: int) -> None:
        for j in range(300):
            if j % 3 == 0:
                m.update(a=bool((i + j) % 2))
            m.event("E")

    threads = [threading.Thread(target=work, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    m.close()
    records = read_audit(log)
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1))
    assert seen == [r["seq"] for r in records]
    ids = [r["id"] for r in records if r["kind"] == "decision"]
    assert ids == sorted(ids) and len(ids) == 1800


def test_a_torn_last_line_is_set_aside_not_glued(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F", audit=log)
    m.event("E")
    m.close()
    n = len(read_audit(log))
    with log.open("a") as fh:
        fh.write('{"seq": 99, "kind": "deci')  # the process died mid-line
    m2, _ = manager("R1 when E then F", audit=log)
    assert m2.audit is not None and m2.audit.torn == '{"seq": 99, "kind": "deci'
    m2.event("E")
    m2.close()
    lines = log.read_text().splitlines()
    records = [json.loads(line) for line in lines]  # every line is whole JSON
    assert [r["seq"] for r in records] == list(range(1, len(records) + 1)) and len(records) > n
    assert (tmp_path / "a.jsonl.torn").read_text() == '{"seq": 99, "kind": "deci\n'
    assert len({r["run"] for r in records}) == 2


# ---------------------------------------------------------------------------- exactly once


def test_a_and_b_runs_both_capabilities_and_records_each_outcome(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F and G", audit=log)
    ran: list[str] = []

    @m.capability("F")
    def f(ob: Any, d: Any) -> None:
        ran.append("F")
        raise RuntimeError("no arm")

    m.capability("G")(lambda ob, d: ran.append("G"))
    m.start()
    m.event("E")
    m.close()
    assert ran == ["F", "G"]
    out = {(r["kind"], r["event"]) for r in read_audit(log) if r["kind"].startswith("task-")}
    assert out == {("task-failed", "F"), ("task-done", "G")}
    assert m.stats["task_failures"] == 1


def test_a_failing_otherwise_records_task_failed(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, clock = manager("R1 when E then F within 1 seconds otherwise Help", audit=log)
    m.capability("F")(lambda ob, d: None)

    @m.capability("Help")
    def help_(ob: Any, d: Any) -> None:
        raise RuntimeError("phone line down")

    m.start()
    m.event("E")
    clock.advance(2)
    (d,) = m.tick()
    m.close()
    failed = [r for r in read_audit(log) if r["kind"] == "task-failed"]
    assert [(r["decision"], r["event"]) for r in failed] == [(d.id, "Help")]
    assert "phone line down" in failed[0]["error"]


def test_a_capability_that_triggers_its_own_rule_is_stopped_with_a_record(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F R2 when F then G", defs="", audit=log, max_depth=5)
    calls = itertools.count()

    @m.capability("F")
    def f(ob: Any, d: Any) -> None:
        next(calls)
        m.event("F")

    @m.capability("G")
    def g(ob: Any, d: Any) -> None:
        next(calls)
        m.event("E")  # E -> F -> G -> E ... without end

    m.start()
    m.event("E")
    m.close()
    assert next(calls) == 5
    failed = [r for r in read_audit(log) if r["kind"] == "task-failed"]
    assert len(failed) == 1 and "max_depth=5" in failed[0]["error"]


def test_a_max_depth_the_stack_cannot_hold_is_refused_with_the_limit() -> None:
    from cosleec.runtime.runner import deepest as _deepest

    deepest = _deepest()
    with pytest.raises(
        ConfigurationError, match=f"max_depth must be a whole number from 1 to {deepest}"
    ) as e:
        manager("R1 when E then F", max_depth=10**9)
    assert "getrecursionlimit" in (e.value.hint or "")
    with pytest.raises(ConfigurationError, match="max_depth"):
        manager("R1 when E then F", max_depth=deepest + 1)  # the first one too deep, not only huge ones


def test_the_deepest_max_depth_allowed_ends_a_trigger_loop_with_a_record_not_recursion_error(
    tmp_path: Path,
) -> None:
    from cosleec.runtime.runner import deepest as _deepest

    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F", audit=log, max_depth=_deepest())
    m.capability("F")(lambda ob, d: m.event("E"))  # E -> F -> E ... without end
    m.start()
    m.event("E")
    m.close()
    failed = [r for r in read_audit(log) if r["kind"] == "task-failed"]
    assert len(failed) == 1 and f"max_depth={_deepest()}" in failed[0]["error"]
    assert "RecursionError" not in failed[0]["error"]


class Liar(float):
    """A float that says it is never greater than anything."""

    def __gt__(self, other: object) -> bool:
        return False


class Shouty(str):
    """A str equal to every text."""

    def __eq__(self, other: object) -> bool:
        return True

    __hash__ = str.__hash__


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (Liar(5.0), "not Liar"),
        (type("Count", (int,), {})(3), "not Count"),
    ],
)
def test_a_number_that_brings_its_own_comparisons_is_refused(value: Any, message: str) -> None:
    m, _ = manager("R1 when E and x > 1 then F", defs="measure x : numeric")
    with pytest.raises(ContextError, match=message) as e:
        m.update(x=value)
    assert e.value.hint == "pass float(value)"
    assert m.values()["x"] is None  # nothing changed


def test_a_scale_value_that_brings_its_own_equality_is_refused() -> None:
    m, _ = manager("R1 when E and s = high then F", defs="measure s : scale(low, high)")
    with pytest.raises(ContextError, match="plain str, not Shouty"):
        m.update(s=Shouty("low"))
    m.update(s="high")
    assert m.values()["s"] == "high"


def test_a_numpy_float_is_stored_as_the_plain_float_it_holds() -> None:
    np = pytest.importorskip("numpy")
    m, _ = manager("R1 when E and x > 1 then F", defs="measure x : numeric")
    m.update(x=np.float64(2.5))
    assert type(m.context.values["x"]) is float and m.values()["x"] == 2.5


def test_an_exception_inside_a_step_keeps_the_record_of_every_change_made(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # before: an OverflowError half-way through a trigger dropped the records of the
    # changes already made (the decision), which stayed in force unrecorded
    log, db = tmp_path / "a.jsonl", tmp_path / "j.db"
    m, _ = manager("R1 when E then F within 1 seconds", audit=log, journal=db)

    def boom(*args: Any, **kw: Any) -> Any:
        raise OverflowError("a bug of ours")

    monkeypatch.setattr(m.tracker, "start", boom)
    with pytest.raises(OverflowError):
        m.event("E")
    assert [d.id for d in m.decisions] == [1]
    kinds = [r["kind"] for r in read_audit(log)]
    assert kinds[-2:] == ["event", "decision"]
    with pytest.raises(JournalError, match="in use by another Manager"):
        manager("R1 when E then F within 1 seconds", journal=db)
    m.close()
    m2, _ = manager("R1 when E then F within 1 seconds", journal=db)
    (d,) = m2.event("E")
    assert d.id == 2  # the journal has the decision too: its id is not given again


def test_a_fallback_carries_its_rule_and_clause_however_old_its_decision() -> None:
    # before (in the first runtime): the clause was looked up in the last-10,000 window, so
    # the fallback of an old decision reached no task node
    m, clock = manager(
        "R1 when E then F within 1 seconds otherwise Help unless a then G", history=1, dispatch=False
    )
    m.update(a=False)
    m.event("E")
    m.update(a=True)
    for _ in range(5):
        m.event("E")  # pushes the first decision out of the history
    m.update(a=False)
    clock.advance(2)
    fallbacks = m.tick()
    assert [(d.rule, d.clause, d.violated) for d in fallbacks][:1] == [("R1", 0, 1)]
    assert [d.id for d in m.decisions] == [fallbacks[-1].id]


def test_an_undetermined_decision_keeps_the_prohibitions_its_otherwise_would_start() -> None:
    # nothing runs, so A may be missed: the otherwise's `not B` could apply from 5 s on
    m, clock = manager(
        "R1 when E then F within 5 seconds otherwise not Rec within 60 seconds unless a then F within 100 seconds"
    )
    (d,) = m.event("E")
    assert d.undetermined and [o.describe() for o in d.obligations] == ["not Rec within [5 s, 65 s]"]
    assert "meanwhile not Rec within [5 s, 65 s]" in d.explanation
    assert m.request("Rec").permitted is True  # before the fallback could start
    clock.advance(6)
    assert m.request("Rec").permitted is False  # before: True (the otherwise's prohibition was not kept)
    clock.advance(60)
    assert m.request("Rec").permitted is True


def test_an_undetermined_decision_keeps_prohibitions_down_an_otherwise_chain() -> None:
    m, clock = manager(
        "R1 when E then F within 5 seconds otherwise G within 10 seconds otherwise not Rec within 60 seconds "
        "unless a then F within 100 seconds",
        defs="event G",
    )
    (d,) = m.event("E")
    assert [o.describe() for o in d.obligations] == ["not Rec within [15 s, 75 s]"]
    clock.advance(16)
    assert m.request("Rec").permitted is False


# ---------------------------------------------------------------------------- review findings


def test_an_update_that_notices_a_deadline_runs_its_otherwise() -> None:
    m, clock = manager("R1 when E then F within 1 seconds otherwise Help")
    helped: list[int] = []
    m.capability("F")(lambda ob, d: None)
    m.capability("Help")(lambda ob, d: helped.append(d.id))
    m.start()
    m.event("E")
    clock.advance(2)
    m.update(a=True)  # before: the fallback this update decided was never run
    assert helped == [2]


def test_a_prohibition_in_an_unknown_unless_clause_is_enforced() -> None:
    m, _ = manager("R1 when E then F unless a then not Rec within 10 minutes")
    (d,) = m.event("E")
    assert d.undetermined and m.request("Rec").permitted is False


@pytest.mark.parametrize("cond", ["not (n > 3)", "(({n} + 1) > 3)", "(({n} * 2) = 4)", "not (3 < n)"])
def test_comparisons_and_arithmetic_over_an_unknown_are_unknown(cond: str) -> None:
    m, _ = manager(
        f"R1 when E then F unless {cond} then not Rec within 10 minutes", defs="measure n : numeric"
    )
    (d,) = m.event("E")
    assert d.conditions[1][2] is None and d.undetermined and m.request("Rec").permitted is False


def test_the_unknown_policy_also_reads_trigger_conditions() -> None:
    m, _ = manager("R1 when E and a then F", unknown="false")
    assert m.event("E") == []  # before: undetermined whatever the policy
    m, _ = manager("R1 when E and a then F", unknown="true")
    (d,) = m.event("E")
    assert d.clause == 0


def test_tick_alone_judges_every_batch() -> None:
    m, clock = manager("R1 when E then F within 1 seconds")
    for _ in range(2500):
        m.event("E")
    clock.advance(2)
    m.tick()
    assert m.stats["violations"] == 2500 and m.outstanding() == []


def test_an_obligation_whose_interval_start_is_unknown_is_due_now() -> None:
    m, clock = manager("R1 when E then F within [{n} seconds, 100 seconds]", defs="measure n : numeric")
    (d,) = m.event("E")
    assert d.obligations[0].within_s == 0.0
    clock.advance(1)
    m.event("F")  # would have counted under an interval starting at 0
    m.tick()
    assert m.stats["violations"] == 1


def test_a_prohibition_in_an_else_never_fulfils() -> None:
    m, clock = manager("R1 when E then F within 5 seconds else not Rec within 10 seconds")
    m.event("E")
    clock.advance(1)
    m.event("Rec")  # before: the forbidden event fulfilled the obligation
    assert [t.event for t in m.outstanding()] == ["F"]


@pytest.mark.parametrize("age", [float("nan"), "5", None, -1, 0, float("inf")])
def test_max_age_must_be_a_positive_finite_number(age: Any) -> None:
    with pytest.raises(ContextError, match="max_age of a"):
        manager("R1 when E then F", max_age={"a": age})


def test_a_capability_whose_error_cannot_be_shown_does_not_stop_the_next() -> None:
    m, _ = manager("R1 when E then F and G")
    ran: list[str] = []

    def bad(ob: Any, d: Any) -> None:
        raise KeyError(10**5000)

    m.capability("F")(bad)
    m.capability("G")(lambda ob, d: ran.append("G"))
    m.start()
    m.event("E")
    assert ran == ["G"] and m.stats["task_failures"] == 1


def test_bad_arguments_are_user_errors_and_a_closed_manager_refuses() -> None:
    m, _ = manager("R1 when E then F")
    with pytest.raises(ContextError, match="named by a string"):
        m.event(None)  # type: ignore[arg-type]
    with pytest.raises(ContextError, match="named by a string"):
        m.update({1: True})  # type: ignore[dict-item]
    with pytest.raises(ConfigurationError, match="history"):
        manager("R1 when E then F", history=-1)
    m.close()
    m.close()  # twice is harmless
    assert m.request("F").permitted is False
    with pytest.raises(ConfigurationError, match="closed"):
        m.update(a=True)
    assert m.values()["a"] is None  # nothing changed


def test_switching_semantics_is_recorded(tmp_path: Path) -> None:
    log = tmp_path / "a.jsonl"
    m, _ = manager("R1 when E then F unless a then G unless b then Help", audit=log)
    m.update(a=False, b=True)
    assert m.active_layers() == ["R1.2"]
    m.set_semantics("nested")
    m.close()
    (rec,) = [r for r in read_audit(log) if r["kind"] == "semantics"]
    assert rec["before"] == ["R1.2"] and rec["active"] == [] and rec["semantics"] == "nested"


def test_obligations_fulfilled_early_do_not_keep_their_deadlines_in_memory() -> None:
    m, _ = manager("R1 when E then F within 1 days")
    for _ in range(5000):
        m.event("E")
        m.event("F")
    assert len(m.tracker._heap) < 2000  # before: 5000 entries until a day had passed
