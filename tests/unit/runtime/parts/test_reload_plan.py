"""Reload alone: check, plan and apply, each on a core, never through a Manager."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pytest

from cosleec.records import Kind
from cosleec.runtime import reload as reloading
from cosleec.runtime.errors import ReloadError
from cosleec.runtime.jobs import Job
from cosleec.runtime.reload import Plan, Reloaded, carried, item_of
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.tasks import Task

from .build import DEFS, Parts, journaled, parts, ruleset

OLD = (
    "R1 when E then F within 5 seconds and not Rec within 10 seconds "
    "R2 when G then Help within 5 seconds "
    "R3 when E then G within 9 seconds"
)
# R1 edited around its items (their keys move), R2 removed, R3 given an otherwise, R4 added
NEW = (
    "R1 when E then not Rec within 10 seconds and F within 6 seconds "
    "R3 when E then G within 9 seconds otherwise Help "
    "R4 when F then E"
)
REFUSED = "reload refused, the rules in force stay: "


def plan(
    p: Parts, rules: RuleSet, given: list[str | tuple[str, str]] | None = None, held: Sequence[Job] = ()
) -> Plan:
    prio, impl = reloading.check(p.core, rules, given or [], [], {}, checked=False)
    return Plan.make(p.core, [*p.gate.held.values(), *held], rules, prio, impl)


def apply(p: Parts, made: Plan) -> None:
    with p.core.steps.step() as step:
        reloading.apply(made, p.core, p.enforcer, p.gate, step.now, step)


def in_force() -> Parts:
    """OLD in force: R1's F (1) and not Rec (2), R3's G (3), R2's Help (4, after G fulfilled 3)."""
    p = parts(OLD)
    p.fire("E")
    p.fire("G")
    return p


# ---------------------------------------------------------------------------- arguments and check


def test_reload_takes_a_rule_set_and_keeps_the_callers_priorities_unless_given() -> None:
    with pytest.raises(TypeError, match="reload needs a RuleSet, not str"):
        reloading.arguments("R1 when E then F", None, [])
    kept: list[str | tuple[str, str]] = ["R1 > R2"]
    rules = ruleset(OLD)
    assert reloading.arguments(rules, None, kept) is kept
    assert reloading.arguments(rules, [("R2", "R1")], kept) == [("R2", "R1")]
    assert reloading.arguments(rules, "R2 > R1", kept) == ["R2 > R1"]  # one string is one priority
    with pytest.raises(ReloadError, match=f"^{REFUSED}priorities must be a list"):
        reloading.arguments(rules, 42, kept)  # type: ignore[arg-type]


def test_a_priority_naming_a_rule_the_new_rules_lack_is_refused() -> None:
    p = in_force()
    with pytest.raises(ReloadError, match=f"^{REFUSED}priority R2 > R1: there is no rule 'R2'") as e:
        reloading.check(p.core, ruleset(NEW), ["R2 > R1"], [], {}, checked=False)
    assert "reload(rules, priorities=[...])" in e.value.hint


def test_the_new_priorities_keep_how_priorities_resolve() -> None:
    p = parts(OLD, priorities=("R1 > R2",), semantics="conflict-aware", lead=1.5)
    prio, _ = reloading.check(p.core, ruleset(NEW), ["R4 > R3"], [], {}, checked=False)
    assert (prio.semantics, prio.lead, prio.declared) == ("conflict-aware", 1.5, (("R4", "R3"),))


class HelpTask(Task):
    rule = "R2"

    def default(self, decision: object) -> None:
        pass


def test_a_task_of_a_rule_the_new_rules_lack_is_refused_and_kept_ones_stay_bound() -> None:
    p = in_force()
    with pytest.raises(ReloadError, match=f"^{REFUSED}"):
        reloading.check(p.core, ruleset(NEW), [], [HelpTask()], {}, checked=False)
    p.core.implementations.bind(HelpTask())
    _, kept = reloading.check(p.core, ruleset(OLD), [], [], {}, checked=False)
    _, dropped = reloading.check(p.core, ruleset(NEW), [], [], {}, checked=False)
    assert list(kept.tasks) == ["R2"] and dropped.tasks == {}


def test_a_rule_left_without_an_implementation_is_refused_once_bindings_were_checked() -> None:
    p = in_force()
    reloading.check(p.core, ruleset(NEW), [], [], {}, checked=False)
    with pytest.raises(ReloadError, match="no task and no capability"):
        reloading.check(p.core, ruleset(NEW), [], [], {}, checked=True)


# ---------------------------------------------------------------------------- carried values


def other(defs: str, rules: str = "R1 when E then F") -> RuleSet:
    return RuleSet.from_text(f"def_start event E event F {defs} def_end rule_start {rules} rule_end")


def test_values_are_carried_a_scale_value_by_its_literal() -> None:
    p = parts(OLD)
    p.update(a=True, n=2.5, s="high")
    new = other("measure a : boolean measure n : numeric measure s : scale(high, mid, low)")
    assert carried(p.core.context, new) == {"a": True, "n": 2.5, "s": 0}
    assert carried(p.core.context, other("measure a : boolean")) == {"a": True}  # the others dropped


def test_a_value_that_changes_type_or_loses_its_literal_is_refused() -> None:
    p = parts(OLD)
    p.update(a=True, s="high")
    with pytest.raises(ReloadError) as e:
        carried(p.core.context, other("measure a : numeric measure s : scale(low, mid)"))
    assert e.value.message == (
        f"{REFUSED}measure a holds True as a boolean, and the new rules make it numeric; "
        "measure s holds 'high', a literal its new scale (low, mid) does not have"
    )
    assert carried(p.core.context, other("measure b : numeric")) == {}  # b holds no value: nothing to read


# ---------------------------------------------------------------------------- items


def test_an_obligation_finds_its_item_by_key_or_as_the_one_item_with_its_event_and_sense() -> None:
    p = in_force()
    f, rec = sorted(p.core.tracker.active, key=lambda t: t.id)[:2]
    same = ruleset(OLD)
    assert item_of(f, same) is same.items["R1:0"]
    edited = ruleset(NEW)
    assert item_of(f, edited) is edited.items["R1:1"]  # moved: found by event and sense
    assert item_of(rec, edited) is edited.items["R1:0"]
    two = ruleset("R1 when E then not Rec within 1 seconds and F within 5 seconds and F within 6 seconds")
    assert item_of(f, two) is None  # which one?
    assert item_of(f, ruleset("R1 when E then not F within 5 seconds")) is None  # another sense
    assert item_of(f, ruleset("R9 when E then F within 5 seconds")) is None  # its rule is gone


# ---------------------------------------------------------------------------- the plan


def test_the_plan_keeps_relinks_and_withdraws_by_item() -> None:
    p = in_force()
    made = plan(p, ruleset(NEW))
    assert [(t.id, item.key) for t, item in made.kept] == [(1, "R1:1"), (2, "R1:0")]
    assert [t.id for t in made.withdrawn] == [4]  # R2's Help: its rule is gone
    assert made.result == Reloaded(
        previous_hash=p.core.ruleset.digest,
        current_hash=ruleset(NEW).digest,
        added=("R4",),
        removed=("R2",),
        changed=("R1", "R3"),
        withdrawn=(4,),
    )
    record = made.record(p.core)
    assert (record["relinked"], record["withheld"], record["measures_added"], record["measures_removed"]) == (
        [1, 2],
        [],
        [],
        [],
    )


def test_a_rule_written_otherwise_but_the_same_is_not_changed() -> None:
    p = in_force()
    respaced = OLD.replace(" then ", "   then\n ")
    assert plan(p, ruleset(respaced)).result.changed == ()


def test_the_plan_withholds_the_held_and_due_decisions_of_removed_rules() -> None:
    p = parts(f"{OLD} R5 when Help then not Rec within 1 seconds")
    p.fire("E")
    with p.core.steps.step() as step:
        due = p.trigger("G", step)
    made = plan(p, ruleset(NEW), held=due)
    assert [job.decision.rule for job in made.gone] == ["R2"]
    assert made.record(p.core)["withheld"] == [due[0].decision.id]


def test_the_plan_forgets_the_misses_of_removed_rules() -> None:
    p = parts(OLD)
    p.fire("G")
    p.clock.set(6.0)
    with p.core.steps.step() as step:
        p.enforcer.advance(step.now, step)
    (miss,) = p.core.tracker.misses()
    assert plan(p, ruleset(NEW)).forgotten == [miss]
    assert plan(p, ruleset(OLD)).forgotten == []


# ---------------------------------------------------------------------------- apply


def test_apply_puts_the_plan_in_force_each_change_with_its_record(tmp_path: Path) -> None:
    p = in_force()
    p.update(a=True, n=3)
    journaled(p, tmp_path / "journal.db")
    new = RuleSet.from_text(f"{DEFS.replace('measure n : numeric ', '')} def_end rule_start {NEW} rule_end")
    made = plan(p, new)
    record = made.record(p.core)
    del p.heard[:]
    p.clock.set(1.0)
    with p.core.steps.step() as step:
        reloading.apply(made, p.core, p.enforcer, p.gate, step.now, step)
        change = step.change
    assert p.core.ruleset is new and p.core.context.values == {"a": True}
    assert p.kinds()[0] == "reloaded" and p.heard[0].data == record
    assert (record["relinked"], record["measures_removed"]) == ([1, 2], ["n"])
    assert [(d["id"], d["status"]) for d in p.of(Kind.OBLIGATION)] == [(4, "withdrawn")]
    assert p.of(Kind.DROPPED) == [{"what": "measure n: the rules no longer declare it"}]
    assert p.of(Kind.LAYERS) == []  # no rule has clauses: no layer switched
    assert {t.id: t.obligation.item for t in p.core.tracker.active} == {1: "R1:1", 2: "R1:0"}
    assert change.context == {"n": None}
    assert change.obligations[4] is None  # withdrawn: leaves the journal
    assert change.obligations[1] is not None and change.obligations[1]["obligation"]["item"] == "R1:1"


def test_layers_are_recomputed_a_rule_added_switching_from_the_base_and_one_removed_to_it() -> None:
    p = parts("R5 when E then F unless a then G R7 when E then F unless b then G")
    p.update(a=True, b=True)
    del p.heard[:]
    apply(p, plan(p, ruleset("R7 when E then F unless b then G R6 when G then E unless a then F")))
    (layers,) = p.of(Kind.LAYERS)
    assert layers["switches"] == [
        {"rule": "R6", "from": None, "to": "R6.1"},
        {"rule": "R5", "from": "R5.1", "to": None},
    ]
    assert layers["active"] == ["R7.1", "R6.1"]


def test_carried_values_keep_their_age_and_the_context_its_version() -> None:
    p = parts(OLD, max_age={"a": 5.0})
    p.clock.set(2.0)
    p.update(a=True, b=False)
    version = p.core.context.version
    p.clock.set(4.0)
    apply(p, plan(p, ruleset(OLD)))
    assert p.core.context.stamps == {"a": 2.0, "b": 2.0}
    assert p.core.context.version == version
    assert p.core.context.next_expiry() == 7.0


def test_a_kept_obligation_takes_its_new_items_otherwise() -> None:
    p = parts(OLD)
    p.fire("E")
    apply(p, plan(p, ruleset(NEW)))
    (g,) = [t for t in p.core.tracker.active if t.event == "G"]
    assert g.obligation.otherwise is not None and g.obligation.otherwise.events() == ("Help",)


def test_apply_withholds_a_held_decision_of_a_removed_rule() -> None:
    p = parts(f"{OLD} R6 when F then not Help within 3 seconds")
    p.fire("F")
    with p.core.steps.step() as step:
        assert p.gate.ready(p.trigger("G", step), step.now, step) == []
    assert list(p.gate.held) == [2]
    apply(p, plan(p, ruleset(f"{NEW} R6 when F then not Help within 3 seconds")))
    assert p.gate.held == {}
    assert p.of(Kind.WITHHELD) == [
        {"decision": 2, "rule": "R2", "reason": "its rule R2 was removed by a reload"}
    ]


def test_activations_a_new_cancellation_priority_orders_meet_at_the_reload() -> None:
    p = parts(OLD)
    p.fire("G")
    p.fire("E")
    apply(p, plan(p, ruleset(OLD), given=["R1 > R3"]))
    (cancelled,) = p.of(Kind.CANCELLED)
    assert (cancelled["rule"], cancelled["by"]) == ("R3", "R1")


@pytest.mark.parametrize("banned", [False, True])
def test_swap_returns_what_may_run_of_the_decisions_due_now(banned: bool) -> None:
    p = parts(OLD if banned else OLD.replace(" and not Rec within 10 seconds", ""))
    with p.core.steps.step() as step:
        due = p.trigger("G", step) + p.trigger("E", step)
    prio, impl = reloading.check(p.core, ruleset(NEW), [], [], {}, checked=False)
    with p.core.steps.step() as step:
        result, ready = reloading.swap(p.core, p.enforcer, p.gate, (ruleset(NEW), prio, impl), due, step)
    assert result.removed == ("R2",)
    assert sorted(job.decision.rule for job in ready) == ["R1", "R3"]
    (withheld,) = p.of(Kind.WITHHELD)  # R2's, once: its rule was removed
    assert withheld["reason"] == "its rule R2 was removed by a reload"
