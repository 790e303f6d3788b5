"""One way from rules to a running rule set, and the records it produces (the "simpler core" issue)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.errors import UserError
from cosleec.lang import SleecError, parse
from cosleec.lang.hedges import HedgeSemantics
from cosleec.runtime import ConfigurationError, Decision, Manager, Obligation, RuleSet, VirtualClock

RULES = """
def_start
  event CurtainOpenRequest event OpenCurtains event Refuse event HelpOffered event CallSupport
  measure userUndressed : boolean
def_end
rule_start
  R1 when CurtainOpenRequest then OpenCurtains within 30 seconds
     unless userUndressed then Refuse within 5 seconds otherwise CallSupport within 60 seconds
rule_end
"""


def test_every_source_gives_the_same_rule_set(tmp_path: Path) -> None:
    path = tmp_path / "a when b.sleec"  # the old positional guess read such a path as rule text
    path.write_text(RULES)
    from_file = RuleSet.from_file(path)
    from_text = RuleSet.from_text(RULES)
    spec = parse(RULES)
    from_spec = RuleSet.from_spec(spec)
    assert from_spec.spec is spec  # checked as it is, not printed and parsed again
    for rs in (from_file, from_text, from_spec):
        assert [r.name for r in rs.rules] == ["R1"]
        assert rs.rule("R1") is rs.rules[0] and rs.by_trigger["CurtainOpenRequest"] == rs.rules
        with pytest.raises(KeyError):
            rs.rule("R2")
    assert Manager.from_file(path).ruleset.rule("R1").name == "R1"


def test_manager_takes_a_rule_set_not_a_guess() -> None:
    with pytest.raises(TypeError, match=r"Manager.from_file"):
        Manager(RULES)  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match="'last-wins', 'nested'"):
        Manager.from_text(RULES, semantics="nestd")
    assert Manager.from_text(RULES, semantics="nested").semantics is HedgeSemantics.NESTED


def test_infer_defs_is_honoured_for_a_specification() -> None:
    fragment = parse("rule_start R1 when A then B rule_end", infer_defs=True)
    bare = dataclasses.replace(fragment, definitions=())
    with pytest.raises(SleecError, match="no def block"):
        RuleSet.from_spec(bare)
    assert [r.name for r in RuleSet.from_spec(bare, infer_defs=True).rules] == ["R1"]


def test_each_rule_owns_its_layers_and_compositions() -> None:
    rule = RuleSet.from_text(RULES).rule("R1")
    (layer,) = rule.layers
    assert layer.name == "R1.1" and layer.group is not None
    assert [c.layers for c in rule.compositions] == [(), (layer,)]


def test_a_fallback_keeps_its_clause_after_the_decision_left_the_history() -> None:
    clock = VirtualClock()
    m = Manager.from_text(RULES, clock=clock, history=1, dispatch=False)
    m.update(userUndressed=True)
    (d,) = m.event("CurtainOpenRequest")
    assert d.clause == 1
    m.update(userUndressed=False)
    m.event("CurtainOpenRequest")  # pushes the first decision out of the 1-entry history
    clock.advance(6)
    (fallback,) = m.tick()  # Refuse was never reported: otherwise CallSupport
    assert fallback.event == "otherwise" and fallback.clause == 1 and fallback.violated is not None


# ---------------------------------------------------------------- records: keyword-only, one wire format


def test_records_are_built_by_keyword() -> None:
    with pytest.raises(TypeError):
        Obligation("E")  # type: ignore[misc]
    with pytest.raises(TypeError):
        Decision(1, 0.0, "E", "R1", 0, None, HedgeSemantics.LAST_WINS, {}, (), ())  # type: ignore[misc]


obligations = st.builds(
    Obligation,
    event=st.from_regex(r"[A-Z][a-z]{0,6}", fullmatch=True),
    negated=st.booleans(),
    within_s=st.none() | st.floats(0, 1e6, allow_nan=False),
    from_s=st.floats(0, 1e3, allow_nan=False),
    eventually=st.booleans(),
    alternatives=st.lists(
        st.lists(
            st.tuples(st.sampled_from(["A", "B"]), st.floats(0, 1e3), st.none() | st.floats(0, 1e6)),
            min_size=1,
            max_size=2,
        ).map(tuple),
        max_size=1,
    ).map(tuple),
    rule=st.sampled_from(["R1", "R2"]),
)
values = st.dictionaries(
    st.sampled_from(["m", "n"]), st.none() | st.booleans() | st.integers() | st.sampled_from(["low"])
)
decisions = st.builds(
    Decision,
    id=st.integers(1, 10**6),
    time=st.floats(0, 1e6, allow_nan=False),
    event=st.sampled_from(["E", "otherwise"]),
    rule=st.sampled_from(["R1", "R2"]),
    clause=st.none() | st.integers(0, 5),
    layer=st.none() | st.sampled_from(["R1.1"]),
    semantics=st.sampled_from(list(HedgeSemantics)),
    values=values,
    conditions=st.lists(
        st.tuples(st.integers(0, 5), st.sampled_from(["m", "n > 2"]), st.none() | st.booleans())
    ).map(tuple),
    obligations=st.lists(obligations, max_size=3).map(tuple),
    missing=st.lists(st.sampled_from(["m", "n"]), max_size=2).map(tuple),
    reason=st.sampled_from(["", "R1: because"]),
    context_version=st.integers(0, 100),
    violated=st.none() | st.integers(1, 100),
)


@given(decisions)
def test_decisions_round_trip_through_their_wire_format(d: Decision) -> None:
    """Any decision, even one no Manager would make (a record read from the wire may be odd)."""
    back = Decision.from_json(d.to_json())
    assert back == d
    assert back.explanation == d.explanation


def test_a_rule_file_error_says_where_and_how_to_fix(tmp_path: Path) -> None:
    path = tmp_path / "bad.sleec"
    text = "def_start event A def_end rule_start R1 when A then B rule_end"
    path.write_text(text)
    with pytest.raises(SleecError) as info:
        RuleSet.from_file(path)
    error = info.value
    assert isinstance(error, UserError)
    assert error.where == f"{path}:1:{text.index(' B ') + 2}"  # the undeclared response `B`
    assert "B" in str(error)


def test_a_received_decision_whose_clause_and_layer_disagree_runs_nothing() -> None:
    from cosleec.runtime import Implementations

    rules = RuleSet.from_text(RULES)
    impl = Implementations(rules)
    ran: list[str] = []
    impl.capability("Refuse")(lambda ob, d: ran.append("Refuse"))
    impl.capability("OpenCurtains")(lambda ob, d: ran.append("OpenCurtains"))
    rule = rules.rule("R1")
    good = Decision(
        id=1,
        time=0.0,
        event="CurtainOpenRequest",
        rule="R1",
        clause=1,
        layer="R1.1",
        semantics=HedgeSemantics.LAST_WINS,
        values={},
        conditions=(),
        obligations=(Obligation(event="Refuse", rule="R1"),),
    )
    assert all(r.ok for r in impl.dispatch(rule, good)) and ran == ["Refuse"]
    bad = dataclasses.replace(good, id=2, layer=None)  # says clause 1 but names the default
    assert not any(r.ok for r in impl.dispatch(rule, bad)) and ran == ["Refuse"] and impl.failures == 1


def test_obligation_records_round_trip_through_their_wire_format() -> None:
    from cosleec.runtime import Tracked

    clock = VirtualClock()
    m = Manager.from_text(RULES, clock=clock, dispatch=False)
    m.update(userUndressed=True)
    m.event("CurtainOpenRequest")
    clock.advance(6)
    m.tick()  # Refuse violated, its otherwise started
    m.event("Refuse")  # late
    records = [*m.tracker.closed, *m.tracker.active]
    assert {t.status for t in records} >= {"violated", "pending"}
    for t in records:
        back = Tracked.from_json(t.to_json())
        assert back == t and back.obligation.otherwise is None  # the compiled fallback stays here


def test_the_layers_record_is_one_record_for_the_manager_and_the_node() -> None:
    from cosleec.runtime import LayerState

    m = Manager.from_text(RULES, dispatch=False)
    seen = []
    m.subscribe(lambda ev: seen.append(ev) if ev.kind == "layers" else None)
    m.update(userUndressed=True)
    m.update(userUndressed=False)
    states = [LayerState.from_json(ev.data) for ev in seen]
    assert [s.active for s in states] == [("R1.1",), ()]
    assert [s.version for s in states] == [1, 2]
    assert [(sw.before, sw.after) for s in states for sw in s.switches] == [("?", "R1.1"), ("R1.1", None)]
    for s in states:
        assert LayerState.from_json(s.to_json()) == s


@pytest.mark.parametrize(
    ("rule", "message"),
    [
        ("op", "`=>` is not a SLEEC operator"),
        ("name", "`R 1` is not a SLEEC name"),
    ],
)
def test_a_specification_built_in_python_is_held_to_the_syntax(rule: str, message: str) -> None:
    """What the parser would never produce is still rejected when a Specification comes from code."""
    from cosleec.lang import ast as A

    defs = (A.EventDecl("T"), A.EventDecl("A"), A.MeasureDecl("n", A.NumericType()))
    occ = A.ResponseItem(A.Occurrence("A"))
    if rule == "op":
        built = A.Rule("R1", A.Trigger("T", A.Compare("=>", A.Name("n"), A.IntLit(1))), A.Response((occ,)))
    else:
        built = A.Rule("R 1", A.Trigger("T"), A.Response((occ,)))
    with pytest.raises(SleecError, match=message):
        RuleSet.from_spec(A.Specification(defs, (built,)))


def test_a_clause_implemented_twice_is_refused() -> None:
    from cosleec.runtime import BindingError, Task, hedge

    class Twice(Task):
        rule = "R1"

        def default(self, d: Decision) -> None: ...

        @hedge(1)
        def a(self, d: Decision) -> None: ...

        @hedge("R1.1")
        def b(self, d: Decision) -> None: ...

    m = Manager.from_text(RULES)
    with pytest.raises(BindingError, match="clause 1 is implemented twice"):
        m.bind(Twice())


@pytest.mark.parametrize("clause", [True, "1", 1.5])
def test_a_decision_from_the_wire_needs_a_whole_clause(clause: object) -> None:
    d = Decision(
        id=1,
        time=0.0,
        event="E",
        rule="R1",
        clause=1,
        layer="R1.1",
        semantics=HedgeSemantics.LAST_WINS,
        values={},
        conditions=(),
        obligations=(),
    ).to_json()
    with pytest.raises(ValueError, match="whole number"):
        Decision.from_json({**d, "clause": clause})
