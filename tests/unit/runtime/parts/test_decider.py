"""The decider alone: a trigger becomes a decision (or none), a missed deadline its ``otherwise``."""

from __future__ import annotations

import pytest

from cosleec.lang import Unknowns
from cosleec.runtime.decision import Decision
from cosleec.runtime.obligations import Tracked

from .build import Parts, parts

RULE = "R1 when E and a then F within 5 seconds otherwise Help unless b then not Rec within 3 seconds"


def decide(p: Parts, rule: str = "R1", at: float = 0.0) -> Decision | None:
    return p.core.decider.decide(p.core.ruleset.rule(rule), "E", at)


def described(d: Decision) -> list[str]:
    return [o.describe() for o in d.obligations]


def test_a_false_trigger_decides_nothing_and_uses_no_id() -> None:
    p = parts(RULE)
    p.update(a=False)
    assert decide(p) is None
    assert p.core.steps.counters["decision"] == 1
    assert p.core.stats.undetermined == 0


def test_an_unknown_trigger_is_undetermined_naming_what_it_lacks() -> None:
    p = parts(RULE)
    d = decide(p, at=2.0)
    assert d is not None
    assert (d.clause, d.layer, d.missing, d.time, d.event) == (None, None, ("a",), 2.0, "E")
    assert d.conditions[0] == (0, "a", None)
    # nothing runs; what any clause could forbid is enforced (here b is unknown too: both)
    assert described(d) == ["not Rec within 3 s"]
    assert p.core.stats.undetermined == 1


@pytest.mark.parametrize(("policy", "fires"), [(Unknowns.TRUE, True), (Unknowns.FALSE, False)])
def test_the_unknowns_policy_reads_an_unknown_trigger(policy: Unknowns, fires: bool) -> None:
    p = parts(RULE, unknown=policy)
    p.update(b=False)
    d = decide(p)
    if not fires:
        assert d is None
        return
    assert d is not None
    assert (d.clause, d.missing, d.unknown) == (0, (), policy)
    assert d.conditions == ((0, "a", True), (1, "b", False))
    assert described(d) == ["F within 5 s"]
    assert p.core.stats.undetermined == 0


def test_a_fired_rule_whose_clause_is_unknown_is_undetermined_naming_the_clause_measures() -> None:
    p = parts(RULE)
    p.update(a=True)
    d = decide(p)
    assert d is not None
    assert (d.clause, d.missing) == (None, ("b",))
    assert d.conditions == ((0, "a", True), (1, "b", None))
    assert described(d) == ["not Rec within 3 s"]
    assert p.core.stats.undetermined == 1


@pytest.mark.parametrize(
    ("b", "clause", "layer", "want"),
    [(False, 0, None, "F within 5 s"), (True, 1, "R1.1", "not Rec within 3 s")],
)
def test_the_active_clause_decides_the_obligations_and_the_layer(
    b: bool, clause: int, layer: str | None, want: str
) -> None:
    p = parts(RULE)
    p.update(a=True, b=b)
    d = decide(p)
    assert d is not None
    assert (d.clause, d.layer, d.missing, d.rule) == (clause, layer, (), "R1")
    assert described(d) == [want]
    assert d.context_version == p.core.context.version == 1


def test_an_undetermined_inner_choice_makes_the_decision_undetermined() -> None:
    p = parts("R1 when E then F unless b then { not Rec within 10 minutes unless a then G }")
    p.update(b=True)
    d = decide(p)
    assert d is not None
    assert (d.clause, d.missing) == (None, ("a",))
    assert described(d) == ["not Rec within 600 s"]
    assert p.core.stats.undetermined == 1


def test_a_decision_shows_scale_values_by_their_literal_and_unknown_ones_as_none() -> None:
    p = parts("R1 when E and s = high then F unless a then G")
    p.update(s="high")
    d = decide(p)
    assert d is not None
    assert d.values == {"a": None, "s": "high"}


def test_decisions_take_consecutive_ids() -> None:
    p = parts("R1 when E then F R2 when E then G")
    ids = [d.id for d in (decide(p, "R1"), decide(p, "R2"), decide(p, "R1")) if d is not None]
    assert ids == [1, 2, 3]


# ---------------------------------------------------------------------------- otherwise


def missed(p: Parts, rule: str = "R1") -> Tracked:
    """The first obligation of ``rule``'s decision now, started at 0."""
    d = decide(p, rule)
    assert d is not None
    return p.core.tracker.start(d.id, d.clause, d.obligations[0], 0.0, 1)


def test_a_missed_deadline_decides_its_otherwise() -> None:
    p = parts(RULE)
    p.update(a=True, b=False)
    t = missed(p)
    d, determined = p.core.decider.fallback(p.core.ruleset.rule("R1"), t, 5.0)
    assert determined
    assert (d.id, d.event, d.time, d.clause, d.layer, d.violated, d.values) == (
        2,
        "otherwise",
        5.0,
        0,
        None,
        t.id,
        {},
    )
    assert described(d) == ["Help"]
    assert d.explanation == "R1: F within 5 s was violated; otherwise Help"
    # it says it is an otherwise, and which obligation it answers (not a default decision)
    assert (d.origin, d.fallback, d.missed) == ("otherwise", True, t.obligation)
    assert d.for_people == "I did not f in time, so I will help."


def test_an_otherwise_whose_inner_choice_is_unknown_only_forbids() -> None:
    p = parts(
        "R1 when E then F within 5 seconds otherwise { not Rec within 2 seconds unless a then G within 3 seconds }"
    )
    t = missed(p)
    d, determined = p.core.decider.fallback(p.core.ruleset.rule("R1"), t, 5.5)
    assert not determined
    assert (d.clause, d.missing) == (None, ("a",))
    assert described(d) == ["not Rec within 2 s"]
    assert d.explanation == (
        "R1: F within 5 s was violated; otherwise undetermined (no value for a); meanwhile not Rec within 2 s"
    )
    assert d.origin == "otherwise" and d.for_people == (
        "I did not f in time, and I can't decide what to do next: I don't know a."
    )
    # only a trigger's undetermined decision is counted (as before the split): pinned here
    assert p.core.stats.undetermined == 0


def test_an_otherwise_whose_clause_requires_nothing_says_so() -> None:
    p = parts("R1 when E then F within 5 seconds otherwise { G within 1 seconds unless a }")
    p.update(a=True)
    d, determined = p.core.decider.fallback(p.core.ruleset.rule("R1"), missed(p), 5.0)
    assert determined and d.obligations == ()
    assert d.explanation.endswith("otherwise nothing is required")
