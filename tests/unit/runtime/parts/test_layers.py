"""LayerManager.update: the shortcut for measures one rule alone reads against every rule judged again.

An update of measures that only one rule's clauses read re-evaluates that rule without
walking the index (the usual update: a rule's own context). On generated rule sets --
measures read by one rule, by several, by none -- and generated updates, the statuses and
the layer switches ``update`` returns must be those of judging every rule again from the
same values (``recompute_all``), in rule order; an update that names a shared measure, or a
measure of another rule, must still reach every rule that reads it.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from cosleec.lang import HedgeSemantics
from cosleec.runtime.layers import LayerManager, LayerState, LayerSwitch
from cosleec.runtime.ruleset import RuleSet

MEASURES = ("a", "b", "c", "d", "e")  # each rule reads some; a measure may be shared, or read by none


@st.composite
def rule_sets(draw: st.DrawFn) -> str:
    rules = []
    for i in range(draw(st.integers(1, 4))):
        reads = draw(st.lists(st.sampled_from(MEASURES), min_size=1, max_size=3))
        clauses = " ".join(f"unless {{{m}}} then B within {j + 1} seconds" for j, m in enumerate(reads))
        rules.append(f"R{i} when E then A within 9 seconds {clauses}")
    defs = " ".join(f"measure {m} : boolean" for m in MEASURES)
    return f"def_start event E event A event B {defs} def_end rule_start {' '.join(rules)} rule_end"


def judged_again(rules: RuleSet, values: dict[str, object], semantics: HedgeSemantics) -> LayerManager:
    lm = LayerManager(rules, semantics)
    lm.recompute_all(values)
    return lm


UPDATES = st.dictionaries(st.sampled_from(MEASURES), st.booleans(), min_size=1, max_size=5)


@settings(max_examples=300, deadline=None)
@given(rule_sets(), st.lists(UPDATES, min_size=1, max_size=6), st.sampled_from(list(HedgeSemantics)))
def test_an_update_judges_the_rules_it_touches_as_judging_every_rule_does(
    text: str, updates: list[dict[str, bool]], semantics: HedgeSemantics
) -> None:
    rules = RuleSet.from_text(text)
    lm = LayerManager(rules, semantics)
    values: dict[str, object] = {}
    for update in updates:
        before = judged_again(rules, values, semantics).status
        values.update(update)
        switches = lm.update(list(update), values)
        want = judged_again(rules, values, semantics)
        assert lm.status == want.status, update
        assert lm.active_layers() == want.active_layers()
        names = [r.layer_names for r in rules.rules]
        expected = [
            LayerSwitch(
                r.name,
                "?" if old.clause is None else names[r.index][old.clause],
                "?" if new.clause is None else names[r.index][new.clause],
            )
            for r, old, new in zip(rules.rules, before, want.status)
            if old.clause != new.clause
        ]
        assert switches == expected, update


def test_a_measure_read_by_two_rules_reaches_both_and_one_read_by_one_only_that_one() -> None:
    rules = RuleSet.from_text(
        "def_start event E event A event B measure a : boolean measure b : boolean measure c : boolean "
        "def_end rule_start R1 when E then A within 9 seconds unless {a} then B within 1 seconds "
        "unless {c} then B within 2 seconds "
        "R2 when E then A within 9 seconds unless {b} then B within 1 seconds unless {c} then B within 2 seconds "
        "rule_end"
    )
    lm = LayerManager(rules)
    values: dict[str, object] = {"a": False, "b": False, "c": False}
    lm.recompute_all(values)
    values["a"] = True  # a: R1's alone
    assert lm.update(["a"], values) == [LayerSwitch("R1", None, "R1.1")]
    values["b"] = True  # b: R2's alone -- not R1's, though R1 reads c as R2 does
    assert lm.update(["b"], values) == [LayerSwitch("R2", None, "R2.1")]
    values["c"] = True  # c: both
    assert lm.update(["c"], values) == [LayerSwitch("R1", "R1.1", "R1.2"), LayerSwitch("R2", "R2.1", "R2.2")]
    values["a"] = False  # a and c together: a is R1's alone, c is not -- both rules judged
    values["c"] = False
    assert lm.update(["a", "c"], values) == [
        LayerSwitch("R1", "R1.2", None),
        LayerSwitch("R2", "R2.2", "R2.1"),
    ]


@settings(max_examples=200, deadline=None)
@given(rule_sets(), st.lists(UPDATES, min_size=1, max_size=6), st.sampled_from(list(HedgeSemantics)))
def test_a_deferred_layers_record_is_the_state_then(
    text: str, updates: list[dict[str, bool]], semantics: HedgeSemantics
) -> None:
    """``LayerManager.record_of`` (the hot path's ``layers`` record, made when read) reads,
    after every later update, as ``state(switches).to_json()`` read at once: the same
    active layers, switches and a version of its own."""
    rules = RuleSet.from_text(text)
    lm = LayerManager(rules, semantics)
    values: dict[str, object] = {}
    made = []
    for update in updates:
        values.update(update)
        switches = lm.update(list(update), values)
        later = lm.record_of(switches)
        now = LayerState(
            active=tuple(lm.active_layers()),
            switches=tuple(switches),
            semantics=semantics,
            version=lm.version,
        ).to_json()
        switches.append(LayerSwitch("R9", "x", "y"))  # (the caller's list: the record kept its own)
        made.append((later, now))
    assert [later() for later, _ in made] == [now for _, now in made]
    assert [now["version"] for _, now in made] == list(range(1, len(updates) + 1))
