"""The core alone: the state every part shares, and how it records what every part records."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.lang import CONFLICT_AWARE, HedgeSemantics, Unknowns
from cosleec.records import Kind, RuntimeEvent
from cosleec.runtime.clock import VirtualClock
from cosleec.runtime.context import Context
from cosleec.runtime.core import Core, InForce
from cosleec.runtime.layers import LayerManager, LayerSwitch
from cosleec.runtime.model import Obligation
from cosleec.runtime.obligations import FULFILLED
from cosleec.runtime.steps import Step

from .build import journaled, parts, prioritised, ruleset

RULES = "R1 when E then F within 5 seconds unless a then G within 2 seconds"


def test_a_built_core_has_no_journal_no_audit_log_and_records_nothing() -> None:
    core = Core.build(ruleset(RULES))
    assert core.steps.journal is None and core.steps.audit is None
    assert not core.journal and not core.steps.recording
    assert core.dispatch and core.decisions.maxlen == 10_000
    assert isinstance(core.steps.clock, VirtualClock)
    assert core.options_record() == {
        "semantics": "last-wins",
        "unknown": "undetermined",
        "untimed": "none",
        "priorities": [],
        "priority_semantics": "cancel",
        "priority_lead": 0.0,
    }


def test_the_options_record_says_how_the_rules_are_read() -> None:
    rs = ruleset(f"{RULES} R2 when G then not F within 1 seconds")
    core = Core.build(
        rs,
        semantics=HedgeSemantics.NESTED,
        unknown=Unknowns.TRUE,
        priorities=prioritised(rs, "R2 > R1", semantics=CONFLICT_AWARE, lead=0.5),
        untimed=3.0,
    )
    assert core.options_record() == {
        "semantics": "nested",
        "unknown": "true",
        "untimed": 3.0,
        "priorities": [["R2", "R1"]],
        "priority_semantics": CONFLICT_AWARE,
        "priority_lead": 0.5,
    }
    assert core.aware  # conflict-aware, and some rule outranks another


@pytest.mark.parametrize(
    ("pairs", "semantics", "by_instance", "keep_started", "aware"),
    [
        ((), CONFLICT_AWARE, False, False, False),  # declared, but no rule outranks another
        (("R2 > R1",), "cancel", True, False, False),
        (("R2 > R1",), CONFLICT_AWARE, True, True, True),
    ],
)
def test_the_tracker_is_indexed_as_the_priorities_need(
    pairs: tuple[str, ...], semantics: str, by_instance: bool, keep_started: bool, aware: bool
) -> None:
    rs = ruleset(f"{RULES} R2 when G then not F within 1 seconds")
    core = Core.build(rs, priorities=prioritised(rs, *pairs, semantics=semantics))
    assert (core.tracker.by_instance, core.tracker.keep_started, core.aware) == (
        by_instance,
        keep_started,
        aware,
    )


def test_decision_ids_are_used_up_from_the_steps_counter() -> None:
    core = Core.build(ruleset(RULES))
    assert [core.decider.next_id(), core.decider.next_id()] == [1, 2]
    assert core.steps.counters["decision"] == 3


class Face:
    """A façade over a core, as the Manager is."""

    spec: InForce[object] = InForce("spec", "The specification in force.")
    context: InForce[Context] = InForce("context", "The values.")

    def __init__(self, core: Core) -> None:
        self.core = core


def test_in_force_reads_what_the_core_has_now_never_a_copy() -> None:
    core = Core.build(ruleset(RULES))
    face = Face(core)
    assert face.spec is core.ruleset.spec and face.context is core.context
    new = ruleset("R9 when G then E within 1 seconds")
    core.install(new, Context(new.measures), LayerManager(new), core.priorities, core.implementations)
    assert face.spec is new.spec and face.context is core.context  # a reload is seen at once
    assert core.decider.context is core.context and core.issuer.context is core.context
    assert Face.__dict__["spec"].__doc__ == "The specification in force."


def test_in_force_is_read_only_and_documents_itself_on_the_class() -> None:
    face = Face(Core.build(ruleset(RULES)))
    assert isinstance(Face.spec, InForce)  # help(Manager), documentation tools read it on the class
    with pytest.raises(AttributeError):
        face.spec = "stale"  # would shadow the core's value for good


# ---------------------------------------------------------------------------- record


def test_a_decision_is_kept_and_counted_even_when_nobody_records() -> None:
    p = parts(RULES, listen=False)
    with p.core.steps.step() as step:
        d = p.core.decider.decide(p.core.ruleset.rule("R1"), "E", 0.0)
        assert d is not None
        assert p.core.record(d, step, queue=True) is None
        assert step.events == []
    assert list(p.core.decisions) == [d] and p.core.stats.decisions == 1


def test_a_decision_record_gets_what_the_step_adds_and_is_made_only_when_read() -> None:
    p = parts(RULES)
    p.update(a=False)
    with p.core.steps.step() as step:
        d = p.core.decider.decide(p.core.ruleset.rule("R1"), "E", 0.0)
        assert d is not None
        rec = p.core.record(d, step, queue=True)
        assert rec is not None
        rec["dispatch"] = "held"
        assert not step.changed()  # no journal: no outbox
        made = step.events[-1]
        assert "data" not in vars(made)  # nobody read it yet: not made
    assert p.heard[-1] is made and made.kind == Kind.DECISION
    assert made.data == {**d.to_json(), "dispatch": "held"}  # what the step added comes last
    assert list(made.data)[-1] == "dispatch" and made.data is made.data  # made once


def test_a_deferred_record_is_made_once_whichever_threads_read_it() -> None:
    import threading

    calls: list[int] = []
    barrier = threading.Barrier(8)

    def make() -> dict[str, object]:
        calls.append(1)
        return {"n": len(calls)}

    ev = RuntimeEvent.deferred(Kind.DECISION, 1.0, make, 5)
    seen: list[object] = []

    def read() -> None:
        barrier.wait()
        seen.append(ev.data)

    threads = [threading.Thread(target=read) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert calls == [1] and all(x is seen[0] for x in seen) and seen[0] == {"n": 1}
    assert ev == RuntimeEvent.made(Kind.DECISION, 1.0, {"n": 1}, 5)
    with pytest.raises(AttributeError, match="no attribute 'other'"):
        ev.other  # noqa: B018


@pytest.mark.parametrize("dispatch", [True, False])
def test_a_queued_decision_enters_the_outbox_whole_only_for_a_manager_node(
    tmp_path: Path, dispatch: bool
) -> None:
    p = parts(RULES)
    p.core.dispatch = dispatch
    journaled(p, tmp_path / "journal.db")
    with p.core.steps.step() as step:
        d = p.core.decider.decide(p.core.ruleset.rule("R1"), "E", 0.0)
        assert d is not None
        rec = p.core.record(d, step, queue=True)
        entry = step.change.outbox[d.id]
        other = p.core.decider.decide(p.core.ruleset.rule("R1"), "E", 0.0)
        assert other is not None
        p.core.record(other, step)
        assert other.id not in step.change.outbox  # not queued: nothing runs it later
    assert entry is not None
    assert {k: entry[k] for k in ("decision", "rule", "event")} == {
        "decision": d.id,
        "rule": "R1",
        "event": "E",
    }
    assert ("record" in entry) is (not dispatch)
    if not dispatch:
        assert entry["record"] is rec


def test_an_obligation_is_journaled_while_pending_and_leaves_when_it_ends(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    tracker = p.core.tracker
    t = tracker.start(1, 0, Obligation(event="F", within_s=5.0, rule="R1"), 0.0, 1)
    with p.core.steps.step() as step:
        p.core.track(t, step)
        assert step.change.obligations[t.id] == t.to_json()
    tracker.finish(t, FULFILLED, 1.0, "F")
    tracker.forgotten.append(77)  # a miss dropped from the late-event list meanwhile
    with p.core.steps.step() as step:
        p.core.track(t, step)
        assert step.change.obligations == {t.id: None, 77: None}
    assert tracker.forgotten == []
    assert [ev.data["status"] for ev in p.heard if ev.kind == Kind.OBLIGATION] == ["pending", "fulfilled"]


def test_a_miss_waiting_for_its_late_event_stays_in_the_journal(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    tracker = p.core.tracker
    t = tracker.start(1, 0, Obligation(event="F", within_s=5.0, rule="R1"), 0.0, 1)
    (missed,) = tracker.due(6.0).changed
    with p.core.steps.step() as step:
        p.core.track(missed, step)
        assert step.change.obligations[t.id] is not None


def test_forgotten_misses_are_cleared_even_when_nobody_records() -> None:
    core = Core.build(ruleset(RULES))
    t = core.tracker.start(1, 0, Obligation(event="F", within_s=5.0, rule="R1"), 0.0, 1)
    core.tracker.forgotten.append(5)
    core.track(t, Step())
    assert core.tracker.forgotten == []


# ---------------------------------------------------------------------------- context


def test_applied_values_switch_layers_and_are_recorded_at_the_step_time(tmp_path: Path) -> None:
    p = parts(RULES)
    journaled(p, tmp_path / "journal.db")
    p.clock.advance(3.0)
    del p.heard[:]
    with p.core.steps.step() as step:
        switches = p.core.apply(p.core.context.validate({"a": True, "s": "high"}), step)
        change = dict(step.change.context)
    assert switches == [LayerSwitch("R1", "?", "R1.1")]
    assert change == {"a": (True, 3.0), "s": ("high", 3.0)}  # as users see them (a scale by its literal)
    assert [(str(ev.kind), ev.time) for ev in p.heard] == [("context", 3.0), ("layers", 3.0)]
    assert p.heard[0].data == {"values": {"a": True, "s": "high"}, "version": 1}
    assert p.heard[1].data["switches"] == [{"rule": "R1", "from": "?", "to": "R1.1"}]


def test_a_value_set_again_records_nothing() -> None:
    p = parts(RULES)
    p.update(a=True)
    del p.heard[:]
    with p.core.steps.step() as step:
        assert p.core.apply(p.core.context.validate({"a": True}), step) == []
    assert p.heard == []


def test_no_layers_record_without_a_switch() -> None:
    p = parts(RULES)
    with p.core.steps.step() as step:
        assert p.core.switched([], step) == []
        assert step.events == []


def test_a_value_past_its_max_age_becomes_unknown_with_its_record() -> None:
    p = parts(RULES, max_age={"a": 5.0})
    core = p.core
    p.update(a=True, b=True)
    del p.heard[:]
    with core.steps.step() as step:
        core.expire(5.0, step)  # at its max_age: still known
        assert step.events == []
    with core.steps.step() as step:
        core.expire(5.5, step)
        assert step.change.context == {"a": None}
    assert core.context.values == {"b": True}
    assert [ev.kind for ev in p.heard] == [Kind.CONTEXT, Kind.LAYERS]
    assert p.heard[0].data == {"values": {"a": None}, "stale": ["a"]}
    assert p.heard[1].data["switches"] == [{"rule": "R1", "from": "R1.1", "to": "?"}]


def test_the_journal_meta_names_the_rules_the_run_the_clock_and_every_counter() -> None:
    p = parts(RULES)
    p.update(a=True)
    p.fire("E")
    meta = p.core.meta()
    assert meta["rules"] == p.core.ruleset.digest
    assert (meta["run"], meta["lineage"], meta["clock_kind"]) == ("test", "test", "VirtualClock")
    assert meta["counters"] == {
        "decision": 2,
        "seq": 2,
        "record": 5,  # context, layers, decision, obligation: the next is 5
        "obligation": 2,
        "version": 1,
        "layers": 1,
    }
