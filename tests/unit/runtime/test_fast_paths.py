"""The runtime's hot-path shortcuts make exactly what the plain constructions make.

Each shortcut (issue 16) trades a general construction for a cheaper one on the decision
path; these tests pin the shortcut to the construction it replaces, so that a field added
to one and not the other, a different default, or a memo served for the wrong response
fails here rather than in a run.
"""

from __future__ import annotations

import copy
import dataclasses
import inspect
import pickle

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.lang import HedgeSemantics, Unknowns
from cosleec.runtime import Manager, VirtualClock
from cosleec.runtime.decision import Decision
from cosleec.runtime.model import Fixed, Obligation


def test_decision_made_takes_exactly_the_fields_with_their_defaults() -> None:
    made = inspect.signature(Decision.made).parameters
    fields = [f for f in dataclasses.fields(Decision) if f.init]
    assert list(made) == [f.name for f in fields]
    for f in fields:
        expected = inspect.Parameter.empty if f.default is dataclasses.MISSING else f.default
        assert made[f.name].default == expected, f.name


@given(
    clause=st.none() | st.integers(0, 4),
    values=st.dictionaries(st.sampled_from(["a", "b", "c"]), st.none() | st.booleans() | st.integers()),
    missing=st.lists(st.sampled_from(["a", "b"])).map(tuple),
    reason=st.text(max_size=5),
    version=st.integers(0, 9),
    violated=st.none() | st.integers(1, 9),
    unknown=st.sampled_from(list(Unknowns)),
)
def test_decision_made_equals_the_constructor(
    clause: int | None,
    values: dict[str, object],
    missing: tuple[str, ...],
    reason: str,
    version: int,
    violated: int | None,
    unknown: Unknowns,
) -> None:
    kw = dict(
        id=3,
        time=1.5,
        event="E",
        rule="R1",
        clause=clause,
        layer=None if not clause else f"R1.{clause}",
        semantics=HedgeSemantics.NESTED,
        values=values,
        conditions=((0, "true", True), (1, "a", False)),
        obligations=(Obligation(event="A", within_s=2.0, rule="R1"),),
        missing=missing,
        reason=reason,
        context_version=version,
        violated=violated,
        unknown=unknown,
    )
    fast, plain = Decision.made(**kw), Decision(**kw)  # type: ignore[arg-type]
    assert fast == plain
    assert repr(fast) == repr(plain)
    assert fast.to_json() == plain.to_json()
    assert fast.explanation == plain.explanation
    assert vars(fast).keys() == vars(plain).keys()
    minimal: dict[str, object] = dict(  # every defaulted field left out
        id=1,
        time=0.0,
        event="E",
        rule="R",
        clause=0,
        layer=None,
        semantics=HedgeSemantics.LAST_WINS,
        values={},
        conditions=(),
        obligations=(),
    )
    assert Decision.made(**minimal) == Decision(**minimal)  # type: ignore[arg-type]


RULES = """def_start event E event A event B event C measure m : numeric measure s : scale(lo, hi)
constant K = 4 def_end
rule_start
R1 when E then A within 3 seconds and not B within K seconds
   unless (m > 2) then C within m seconds
   unless (s = hi) then {A within 1 minutes otherwise C}
R2 when E then B within [1 seconds, 2 seconds] else {C within 5 seconds}
rule_end"""


def test_fixed_responses_are_made_once_and_variable_ones_each_time() -> None:
    m = Manager.from_text(RULES, clock=VirtualClock())
    r1, r2 = m.ruleset.rule("R1"), m.ruleset.rule("R2")
    assert r1.default.fixed  # constant windows: the same obligations every time
    assert isinstance(r1.default.items[1].hi, Fixed)
    assert r1.clauses[0].response is not None and not r1.clauses[0].response.fixed  # reads m
    assert r1.clauses[1].response is not None and r1.clauses[1].response.fixed
    assert not r2.default.fixed  # an else: its branches are windows from now
    m.capability("A")(lambda o, d: None)
    m.capability("B")(lambda o, d: None)
    m.capability("C")(lambda o, d: None)
    m.start()
    m.update(m=1, s="lo")
    first = m.event("E")
    m.clock.advance(10)  # type: ignore[attr-defined]
    m.tick()
    second = m.event("E")
    assert first[0].obligations == second[0].obligations
    assert first[0].obligations[0] is second[0].obligations[0]  # made once, shared
    assert first[1].obligations == second[1].obligations  # the else, made again, equal
    m.update(m=3)
    third, _ = m.event("E")
    assert third.clause == 1 and third.obligations[0].within_s == 3.0
    m.update(m=5)
    fourth, _ = m.event("E")
    assert fourth.obligations[0].within_s == 5.0  # a window that reads m is read each time
    m.update(m=0, s="hi")
    fifth, _ = m.event("E")
    assert fifth.clause == 2 and fifth.obligations[0].within_s == 60.0
    assert fifth.obligations[0].otherwise is not None


def test_a_reload_forgets_the_old_rules_fixed_obligations() -> None:
    m = Manager.from_text(RULES, clock=VirtualClock())
    m.start(check=False)
    m.update(m=0, s="lo")
    before = m.event("E")[0].obligations
    m.reload(
        Manager.from_text(
            RULES.replace("A within 3 seconds", "A within 7 seconds"), clock=VirtualClock()
        ).ruleset
    )
    after = m.event("E")[0].obligations
    assert before[0].within_s == 3.0 and after[0].within_s == 7.0


CLAUSES = 6
CHAIN = (
    "def_start event E event A "
    + " ".join(f"measure c{j} : boolean" for j in range(CLAUSES))
    + " def_end rule_start R when E then A "
    + " ".join(f"unless c{j} then A within {j + 1} seconds" for j in range(CLAUSES))
    + " rule_end"
)


@given(
    values=st.lists(st.booleans(), min_size=CLAUSES, max_size=CLAUSES),
    semantics=st.sampled_from(list(HedgeSemantics)),
    unknown=st.sampled_from(list(Unknowns)),
)
def test_the_layer_manager_chooses_as_choose_does(
    values: list[bool], semantics: HedgeSemantics, unknown: Unknowns
) -> None:
    """Every value known: the shortcut for last-wins picks what :func:`choose` picks (the
    last clause that holds, not the first; 0 when none holds), whatever the policy."""
    from cosleec.lang import choose

    m = Manager.from_text(CHAIN, clock=VirtualClock(), semantics=semantics, unknown=unknown)
    m.update({f"c{j}": v for j, v in enumerate(values)})
    status = m.layer_manager.status[0]
    assert status.values == tuple(values)
    assert status.clause == choose(values, semantics, unknown)
    expected = [f"R.{status.clause}"] if status.clause else []
    assert m.active_layers() == expected


def test_runtime_event_made_equals_the_constructor() -> None:
    from cosleec.runtime import RuntimeEvent

    fast, plain = RuntimeEvent.made("decision", 1.5, {"a": 1}, 7), RuntimeEvent("decision", 1.5, {"a": 1}, 7)
    assert fast == plain and repr(fast) == repr(plain) and hash(fast.kind) == hash(plain.kind)
    assert vars(fast) == vars(plain)
    assert [f.name for f in dataclasses.fields(RuntimeEvent)] == list(
        inspect.signature(RuntimeEvent.made).parameters
    )


TIMED = """def_start event Short event Long event Done measure m : boolean def_end
rule_start
RS when Short then Done within 1 seconds
RL when Long then Done within 30 seconds
rule_end"""


def test_the_deadline_timer_is_woken_only_for_a_deadline_earlier_than_its_sleep() -> None:
    """A step wakes the timer when it leaves a deadline earlier than the one the timer
    sleeps until -- so a short deadline is judged on time, not at the next half-second
    poll -- and not when the new deadline is later (waking a thread for nothing costs a
    trigger as much as publishing its decision)."""
    import time as wall

    from cosleec.runtime import MonotonicClock

    m = Manager.from_text(TIMED, clock=MonotonicClock())
    m.start(check=False, timer=True)
    try:
        pokes: list[float] = []
        real = m._timer.wake.notify_all

        def counted() -> None:
            pokes.append(wall.monotonic())
            real()

        m._timer.wake.notify_all = counted  # type: ignore[method-assign]
        m.event("Long")  # nothing was due: the timer sleeps with no deadline -> woken
        deadline = wall.monotonic() + 2
        while m._timer.due == float("inf") and wall.monotonic() < deadline:
            wall.sleep(0.005)  # until the timer sleeps until RL's deadline
        assert len(pokes) == 1 and m._timer.due < float("inf")
        m.event("Long")  # 30 s later than what it sleeps until: not woken
        assert len(pokes) == 1
        started = wall.monotonic()
        m.event("Short")  # 1 s: earlier -> woken, and judged at its deadline
        assert len(pokes) == 2
        while m.stats["violations"] == 0 and wall.monotonic() < started + 3:
            wall.sleep(0.01)
        took = wall.monotonic() - started
        assert m.stats["violations"] == 1
        assert took < 1.4, f"judged after {took:.2f} s: the timer slept through the short deadline"
    finally:
        m.close()


SCALED = """def_start
  event T
  event A
  measure b: boolean
  measure n: numeric
  measure s: scale(low, mid, high)
def_end
rule_start
R1 when T and {b} then A within 2 seconds unless ({s} >= mid) then A within 1 seconds unless ({n} > 2)
rule_end
"""


def trigger_keywords(
    clause: int | None,
    *,
    obligations: tuple[Obligation, ...],
    missing: tuple[str, ...] = (),
    semantics: HedgeSemantics = HedgeSemantics.LAST_WINS,
    unknown: Unknowns = Unknowns.UNDETERMINED,
) -> dict[str, object]:
    """``Decision.at_trigger``'s keywords besides the rule and what it read, for R1 at ``T``."""
    return dict(
        id=4,
        time=2.0,
        event="T",
        clause=clause,
        semantics=semantics,
        obligations=obligations,
        missing=missing,
        context_version=7,
        unknown=unknown,
        explanations=None,
    )


@given(
    b=st.none() | st.booleans(),
    n=st.none() | st.integers(-3, 5),
    s=st.none() | st.integers(0, 2),
    fired=st.none() | st.booleans(),
    status=st.tuples(st.none() | st.booleans(), st.none() | st.booleans()),
    clause=st.none() | st.integers(0, 2),
    read_first=st.sampled_from(["values", "conditions", "json", "eq"]),
)
def test_a_decision_made_at_a_trigger_is_the_one_made_whole(
    b: bool | None,
    n: int | None,
    s: int | None,
    fired: bool | None,
    status: tuple[bool | None, bool | None],
    clause: int | None,
    read_first: str,
) -> None:
    from cosleec.runtime.ruleset import RuleSet

    rule = RuleSet.from_text(SCALED).rules[0]
    stored = {"b": b, "n": n, "s": s}  # a scale is stored as its position
    read = tuple(stored[name] for name in rule.value_names)
    common = trigger_keywords(
        clause, obligations=(Obligation(event="A", within_s=2.0, rule="R1"),), missing=("n",)
    )
    lazy = Decision.at_trigger(rule=rule, fired=fired, read=read, status=status, **common)  # type: ignore[arg-type]
    assert "values" not in vars(lazy) and "conditions" not in vars(lazy)  # nothing made yet
    literal = {"b": b, "n": n, "s": None if s is None else ("low", "mid", "high")[s]}
    whole = Decision.made(
        rule="R1",
        layer=rule.layer_of(clause) if clause else None,
        values={k: literal[k] for k in rule.value_names},
        conditions=(
            (0, rule.trigger_text, fired),
            (1, rule.clause_texts[0], status[0]),
            (2, rule.clause_texts[1], status[1]),
        ),
        **common,  # type: ignore[arg-type]
    )
    first = {
        "values": lambda d: d.values,
        "conditions": lambda d: d.conditions,
        "json": lambda d: d.to_json(),
        "eq": lambda d: d == whole,
    }[read_first]
    first(lazy)
    assert lazy == whole and repr(lazy) == repr(whole)
    assert lazy.to_json() == whole.to_json()
    assert lazy.explanation == whole.explanation and lazy.for_people == whole.for_people
    assert vars(lazy)["values"] is lazy.values  # made once, then kept
    for again in (pickle.loads(pickle.dumps(lazy)), copy.deepcopy(lazy), dataclasses.replace(lazy)):
        assert again == whole and "_parts" not in vars(again)
    with pytest.raises(AttributeError, match="no attribute 'valuez'"):
        lazy.valuez  # noqa: B018 - any other missing attribute is still an AttributeError


MEASURED = """def_start
  event T
  event A
  measure b1: boolean
  measure b2: boolean
  measure b3: boolean
  measure n: numeric
def_end
rule_start
R1 when T then A within 2 seconds unless {b1} then A within 1 seconds unless ({n} > 2) then A
  unless {b2} then A within 3 seconds unless {b3}
rule_end
"""


@given(
    status=st.tuples(*[st.none() | st.booleans()] * 4),
    clause=st.none() | st.integers(0, 4),
    semantics=st.sampled_from(list(HedgeSemantics)),
    unknown=st.sampled_from(list(Unknowns)),
    n=st.none() | st.integers(0, 5),
    reason=st.sampled_from(["", "held back"]),
)
def test_an_explanation_made_once_per_clause_is_the_one_made_in_full(
    status: tuple[bool | None, ...],
    clause: int | None,
    semantics: HedgeSemantics,
    unknown: Unknowns,
    n: int | None,
    reason: str,
) -> None:
    """``_made_once`` (last-wins, the deciding conditions all measures: kept per rule, clause
    and values) says what the general path says, read first or from the rule's memo, for
    every clause, value, semantics and unknown policy; the memo
    holds only what it may."""
    from cosleec.runtime.ruleset import RuleSet

    rule = RuleSet.from_text(MEASURED).rules[0]
    stored = {"b1": status[0], "b2": status[2], "b3": status[3], "n": n}
    read = tuple(stored[name] for name in rule.value_names)
    obligations = (Obligation(event="A", within_s=2.0, rule="R1"),) if clause != 3 else ()
    common = trigger_keywords(clause, obligations=obligations, semantics=semantics, unknown=unknown)
    for _ in range(2):  # the second time from the rule's memo, when it kept it
        lazy = Decision.at_trigger(rule=rule, fired=True, read=read, status=status, **common)  # type: ignore[arg-type]
        if reason:
            lazy = dataclasses.replace(lazy, reason=reason)
        whole = dataclasses.replace(lazy)  # made from its fields: no parts, the general path
        assert "_parts" not in vars(whole)
        assert lazy.explanation == whole.explanation
        assert lazy.explain(30) == whole.explain(30)
    deciding = rule.clause_texts[(clause or 1) - 1 :] if clause is not None else ()
    kept = (clause, status[(clause or 1) - 1 :]) in rule.reasons
    assert kept == (
        not reason
        and clause is not None
        and clause <= 4
        and semantics == HedgeSemantics.LAST_WINS
        and "n > 2" not in deciding
    )
