"""Focused tests for one-token mutants of the runtime's pieces that the rest of the suite let live.

``scripts/mutants`` runs random one-token mutants of the runtime (issue 29, part 7): a
comparison operator moved to its neighbour, ``and``/``or`` swapped, a ``not`` removed, a
constant flipped. Each test here names the mutant it is there for (``file:line:col:change``
when it was written; ``scripts/mutants --only NAME`` runs it) and says what the mutant
would break. Each builds the piece it tests on its own where it can; the Manager is used
where the mutant is in what the Manager itself does (``start``, a restart on a journal).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from itertools import product
from pathlib import Path
from typing import Any

import pytest

from cosleec.lang import analyse
from cosleec.lang import ast as A
from cosleec.records import Kind
from cosleec.runtime import ConfigurationError, Manager, MonotonicClock, RuleSet, VirtualClock, read_audit
from cosleec.runtime import core as core_module
from cosleec.runtime import restore as restore_module
from cosleec.runtime.compile import MAX_NEST, Compiler, _Program
from cosleec.runtime.core import Core
from cosleec.runtime.implementations import Implementations, Ran
from cosleec.runtime.model import Obligation
from cosleec.runtime.priorities import Priorities, forced
from cosleec.runtime.reload import Plan
from cosleec.runtime.runner import Runner
from cosleec.runtime.steps import Step, Steps

from .lookalike import Lookalike
from .parts.build import parts, ruleset

# ---------------------------------------------------------------------------- steps: a fresh step


def test_a_step_begins_with_nothing_left_for_a_next_batch() -> None:
    """steps.py:62:21:False-True (``self.more = False``): a step that began with ``more`` set
    would make ``Manager.tick`` take batch after batch forever -- a hang the rest of the
    suite only ends by its per-test timeout. (First in this file: the tests below tick.)"""
    assert Step(5.0).more is False
    with Steps(VirtualClock(), run_id="test").step() as step:
        assert step.more is False


# ---------------------------------------------------------------------------- restore: a reboot


class SetClock:
    """A clock of another kind than VirtualClock (as the monotonic clock is), set by the test:
    a restore reads it as a real clock, which a reboot starts again."""

    def __init__(self, t: float) -> None:
        self.t = t

    def now(self) -> float:
        return self.t


BAN = (
    "def_start event Watch event Rec def_end rule_start R when Watch then not Rec within 10 minutes rule_end"
)


def restart_after(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, boot_now: str) -> tuple[Manager, SetClock]:
    """A Manager on a real-kind clock at 1000 s puts ``not Rec`` in force until 1600 and closes
    (on boot ``boot-1``); a new one starts on its journal 100 s later, on boot ``boot_now``."""
    monkeypatch.setattr(core_module, "boot", lambda: "boot-1")  # what the journal keeps
    files: dict[str, Any] = {"journal": tmp_path / "state.db", "audit": tmp_path / "audit.jsonl"}
    m = Manager.from_text(BAN, clock=SetClock(1000.0), **files).start()
    m.event("Watch")
    m.close()
    monkeypatch.setattr(restore_module, "boot", lambda: boot_now)  # what the restore compares it to
    clock = SetClock(1100.0)
    return Manager.from_text(BAN, clock=clock, **files).start(), clock


def test_a_restart_within_the_same_boot_shifts_no_saved_time(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """restore.py:142:67:ne-eq (``saved.boot != boot()``): the same boot read as a reboot
    would shift every saved time by the clock's progress, and a prohibition would outlast
    its window by the time the Manager was down."""
    m, clock = restart_after(tmp_path, monkeypatch, "boot-1")
    (restored,) = [r for r in read_audit(tmp_path / "audit.jsonl") if r["kind"] == "restored"][-1:]
    assert restored["shift"] == 0.0
    clock.t = 1600.0
    assert m.request("Rec").permitted is False  # its last instant
    clock.t = 1650.0
    assert m.request("Rec").permitted is True  # ended at 1600, as decided
    m.close()


def test_a_restart_on_another_boot_holds_a_prohibition_for_its_whole_window(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same mutant's other side: after a reboot, the monotonic clock's origin moved, so a
    prohibition is held as if no time had passed while down (the stricter reading)."""
    m, clock = restart_after(tmp_path, monkeypatch, "boot-2")
    (restored,) = [r for r in read_audit(tmp_path / "audit.jsonl") if r["kind"] == "restored"][-1:]
    assert restored["shift"] > 50.0  # obligations: as if all 100 s passed (the wall clock says ~0 s)
    clock.t = 1650.0
    assert m.request("Rec").permitted is False  # held until 1700: 600 s from the restart's reading of it
    m.close()


MEASURES = "def_start event E event F measure a : boolean measure b : boolean def_end rule_start R when E then F rule_end"


def test_a_value_a_restart_dropped_leaves_the_journal_and_a_kept_one_stays(tmp_path: Path) -> None:
    """restore.py:258:21:not-in-in (``if name not in values``): a restart under rules that no
    longer declare a measure drops its value from the journal, and keeps the others -- the
    other way round, the next restart would forget what was kept and drop the same value
    again (only the slow kill campaign saw it)."""
    files: dict[str, Any] = {"journal": tmp_path / "state.db", "audit": tmp_path / "audit.jsonl"}
    m = Manager.from_text(MEASURES, clock=VirtualClock(), **files)
    m.update(a=True, b=False)
    m.close()
    fewer = MEASURES.replace(" measure b : boolean", "")
    for _ in range(2):
        m = Manager.from_text(fewer, clock=VirtualClock(), **files)
        assert m.values() == {"a": True}
        m.close()
    dropped = [r["what"] for r in read_audit(tmp_path / "audit.jsonl") if r["kind"] == "dropped"]
    assert dropped == ["measure b: the rules no longer declare it"]  # once: then the journal forgot it


def test_a_refused_manager_frees_the_audit_log_it_opened(tmp_path: Path) -> None:
    """manager.py:136:54:is-not-is (``self.audit is not o.audit``): a Manager refused while it
    restores closes the audit log it opened itself -- its lock held, the next Manager on the
    same log would be refused too (only the slow journal tests saw it)."""
    files: dict[str, Any] = {"journal": tmp_path / "state.db", "audit": tmp_path / "audit.jsonl"}
    Manager.from_text(MEASURES, clock=VirtualClock(), **files).close()
    with pytest.raises(ConfigurationError, match="nothing to reset") as refused:
        Manager.from_text(MEASURES, clock=VirtualClock(), reset_journal=True, **files)
    Manager.from_text(
        MEASURES, clock=VirtualClock(), **files
    ).close()  # while the refused one is still referenced
    assert refused.value is not None


# ---------------------------------------------------------------------------- core: the tracker's indexes

PRIORITISED = "R1 when E then F within 5 seconds R2 when E then not F within 3 seconds"


@pytest.mark.parametrize(
    ("semantics", "pairs", "kept"),
    [("cancel", ["R1 > R2"], False), ("conflict-aware", [], False), ("conflict-aware", ["R1 > R2"], True)],
)
def test_what_started_is_kept_only_for_conflict_aware_priorities_that_act(
    semantics: str, pairs: list[str], kept: bool
) -> None:
    """core.py:127:81:and-or (``CONFLICT_AWARE and above``): only conflict-aware priorities
    between rules read (and clear) what started since; kept for cancellation priorities or
    for no priority at all, the list would grow with every obligation for as long as the
    runtime runs."""
    rules = ruleset(PRIORITISED)
    core = Core.build(rules, priorities=Priorities.build(["R1", "R2"], pairs, semantics, 0.0))
    started = [
        core.tracker.start(i, None, Obligation(event="F", within_s=5.0, rule="R1"), 0.0, i)
        for i in range(1, 4)
    ]
    assert core.tracker.started == (started if kept else [])


# ---------------------------------------------------------------------------- gate: the next opening


def test_an_action_held_only_by_a_prohibition_waits_for_no_interval_to_open() -> None:
    """gate.py:79:69:gt-ge (``t.lo > now``): an action whose interval is open already
    (``lo == now``) but which a prohibition forbids would make its own start the next
    opening -- a timer told to wake now, at every step, while the prohibition holds."""
    p = parts("R1 when E then not Rec within 10 seconds R2 when G then Rec within 60 seconds")
    with p.core.steps.step() as step:
        p.gate.ready(p.trigger("E", step), step.now, step)
    with p.core.steps.step() as step:  # the same instant: Rec's window is open, and Rec forbidden
        assert p.gate.ready(p.trigger("G", step), step.now, step) == []
    assert list(p.gate.held) == [2]
    assert p.gate.opening is None


# ---------------------------------------------------------------------------- runner: failures counted


@pytest.mark.parametrize(
    ("errors", "failures"), [((None, None), 0), (("boom", "bang"), 2), ((None, "boom"), 1)]
)
def test_task_failures_count_the_outcomes_that_failed(errors: tuple[str | None, ...], failures: int) -> None:
    """runner.py:89:59:drop-not (``if not r.ok``): the failures would count the outcomes that
    succeeded -- which the suite's one-failed-one-done cases cannot tell apart."""
    p = parts("R2 when G then Rec within 60 seconds")
    (job,) = p.fire("G")
    Runner(p.core, p.gate).run(job.rule, job.decision, lambda: [Ran("capability", "Rec", e) for e in errors])
    assert p.core.stats.task_failures == failures
    assert len(p.of(Kind.TASK_FAILED)) == failures and len(p.of(Kind.TASK_DONE)) == 2 - failures


def test_an_outcome_run_without_an_admission_names_no_record_as_checked() -> None:
    """runner.py:78:24:0-1 (``checked: int = 0``): run directly (not through a dispatch that
    admitted it), an outcome claims no record was checked before it started -- not record
    1, which says something else (records are numbered from 1)."""
    p = parts("R2 when G then Rec within 60 seconds")
    (job,) = p.fire("G")
    Runner(p.core, p.gate).run(job.rule, job.decision, lambda: [Ran("capability", "Rec")])
    (done,) = p.of(Kind.TASK_DONE)
    assert done["checked"] == 0


# ---------------------------------------------------------------------------- reload: relinked


def test_the_reloaded_record_names_the_obligations_whose_item_moved_and_only_those() -> None:
    """reload.py:314:77:ne-eq (``t.obligation.item != item.key``): the ``reloaded`` record's
    ``relinked`` would name the obligations whose item stayed where it was instead of those
    that were found again at another item."""
    core = Core.build(ruleset("R4 when E then F within 5 seconds R5 when G then Rec within 5 seconds"))
    for n, name in enumerate(("R4", "R5"), start=1):
        (ob,) = core.issuer.issue(core.ruleset.rule(name).response_of(0), name).obligations
        core.tracker.start(n, 0, ob, 0.0, n)
    new = ruleset(
        "R4 when E then G within 5 seconds and F within 5 seconds R5 when G then Rec within 5 seconds"
    )
    plan = Plan.make(core, [], new, core.priorities, Implementations(new))
    assert [(t.id, item.key) for t, item in plan.kept] == [(1, "R4:1"), (2, "R5:0")]
    assert plan.record(core)["relinked"] == [1]


# ---------------------------------------------------------------------------- compile: the nesting bound


def nested(n: int, wrap: Callable[[int, str], str], inner: str = "a") -> str:
    """``inner`` wrapped ``n`` times, the ``i``-th time as ``wrap(i, so_far)``."""
    for i in range(n):
        inner = wrap(i, inner)
    return inner


@pytest.mark.parametrize(("terms", "folded"), [(MAX_NEST + 1, False), (MAX_NEST + 2, True)])
def test_an_arithmetic_chain_stays_plain_python_up_to_max_nest_operators(terms: int, folded: bool) -> None:
    """compile.py:111:26:le-lt (``len(tail) <= MAX_NEST``): a chain of exactly ``MAX_NEST``
    operators would be folded by ``functools.reduce`` instead of staying the Python chain
    the docstring promises (the value is the same either way: checked too)."""
    chain = nested(terms - 1, lambda i, s: f"({s} + n)", "n")  # LEGOS: (((n + n) + n) + ...)
    result = analyse(
        "def_start event E event F measure n : numeric def_end "
        f"rule_start R when E and ({chain} > 0) then F rule_end"
    )
    assert result.ok and result.spec is not None and result.symbols is not None
    condition = result.spec.rules[0].trigger.condition
    assert isinstance(condition, A.Compare)
    compiler = Compiler(result.symbols)
    source = compiler.source(condition.left, set())
    assert ("reduce" in source) is folded
    assert compiler.lambda_(source, "<test>")({"n": 2}) == 2 * terms


def value(n: int, step: Callable[[int, Any], Any], inner: Any) -> Any:
    """What :func:`nested` means: ``inner`` stepped ``n`` times, computed in Python."""
    for i in range(n):
        inner = step(i, inner)
    return inner


Shape = tuple[Callable[[int], str], Callable[[int, dict[str, Any]], Any], int]
# each shape: the SLEEC text n deep, its value on v, and the deepest that stays Python source
SHAPES: dict[str, Shape] = {
    "comparisons-left": (
        lambda n: nested(n, lambda i, s: f"({s} = b)"),
        lambda n, v: value(n, lambda i, x: x == v["b"], v["a"]),
        MAX_NEST,
    ),
    "comparisons-right": (
        lambda n: nested(n, lambda i, s: f"(b = {s})"),
        lambda n, v: value(n, lambda i, x: v["b"] == x, v["a"]),
        MAX_NEST,
    ),
    "and-or": (
        lambda n: nested(n, lambda i, s: f"({'ab'[i % 2]} {('and', 'or')[i % 2]} {s})"),
        lambda n, v: value(n, lambda i, x: (v["a"] and x) if i % 2 == 0 else (v["b"] or x), v["a"]),
        MAX_NEST,
    ),
    "arithmetic": (
        lambda n: "(" + nested(n, lambda i, s: f"(k {'+*'[i % 2]} {s})", "k") + " > 3)",
        lambda n, v: value(n, lambda i, x: v["k"] + x if i % 2 == 0 else v["k"] * x, v["k"]) > 3,
        MAX_NEST - 1,
    ),
    "negations": (  # two levels a step
        lambda n: nested(n, lambda i, s: f"(b and (not {s}))"),
        lambda n, v: value(n, lambda i, x: v["b"] and not x, v["a"]),
        MAX_NEST // 2,
    ),
}


@pytest.mark.parametrize("shape", SHAPES)
def test_an_expression_is_python_up_to_max_nest_levels_and_a_program_beyond(shape: str) -> None:
    """compile.py:106:63:1-2 and compile.py:118:59:1-0 (a ``level + 1`` of
    ``Compiler._source``): each operand is one level deeper than its operator, so an
    expression ``MAX_NEST`` levels deep is still Python source (fast), and one more level
    is evaluated by a ``_Program`` (no recursion) -- both in the fast and the three-valued
    form, each with the value the expression means. Miscounted, an expression half as deep
    would be slow, or one deeper than CPython's parser allows would be handed to it."""
    build, meaning, plain = SHAPES[shape]
    for depth, deep in ((plain, False), (plain + 1, True)):
        result = analyse(
            "def_start event E event F measure a : boolean measure b : boolean measure k : numeric def_end "
            f"rule_start R when E and {build(depth)} then F rule_end"
        )
        assert result.ok and result.spec is not None and result.symbols is not None
        condition = result.spec.rules[0].trigger.condition
        assert condition is not None
        compiler = Compiler(result.symbols)
        source = compiler.source(condition, set())
        kleene = compiler.kleene(condition)
        assert ("_DEEP" in source, isinstance(getattr(kleene, "__self__", None), _Program)) == (deep, deep)
        fast = compiler.lambda_(source, "<test>")
        for v in product((True, False), (True, False), (-1, 0, 1)):
            values = dict(zip("abk", v))
            assert fast(values) == kleene(values) == meaning(depth, values), values  # whichever form


# ---------------------------------------------------------------------------- enforcer: conflict-aware ties


def test_a_cancellation_forced_by_two_higher_rules_at_once_is_the_older_prohibitions() -> None:
    """enforcer.py:239:79:lt-le (``(found[0], found[1].id) < (kept[0], kept[1].id)``): when a
    prohibition that starts later forces the same cancellation at the same time as one
    already weighed, the one weighed first stays the cause -- as a computation of
    everything in force finds it -- and is what the ``cancelled`` record names."""
    p = parts(
        "L when E then F within 10 seconds H1 when G then not F within 20 seconds "
        "H2 when Z then not F within 20 seconds",
        " event Z",
        priorities=("H1 > L", "H2 > L"),
        semantics="conflict-aware",
    )

    def at(t: float, *events: str) -> None:
        p.clock.set(t)
        with p.core.steps.step() as step:
            p.enforcer.advance(step.now, step)
            for event in events:
                p.trigger(event, step)

    at(0.0, "E")
    at(1.0, "G")  # H1's prohibition: L's obligation is cancelled at its deadline (10)
    at(2.0, "Z")  # H2's forces the very same cancellation, at the same time
    at(3.0)  # weighed as it started, against the answer kept for the rest
    cut = p.enforcer.forced()
    full = forced(p.core.tracker, p.core.priorities)
    assert cut is not None and full is not None and (cut[0], cut[1].id, cut[2]) == (full[0], full[1].id, "H1")
    at(10.0)
    (cancelled,) = p.of(Kind.CANCELLED)
    assert (cancelled["rule"], cancelled["by"], cancelled["at"]) == ("L", "H1", 10.0)


# ---------------------------------------------------------------------------- Manager.start: the lead warning

WARNED = "priority_lead=0 on a real clock"


@pytest.mark.parametrize(("clock", "warned"), [(VirtualClock(), False), (MonotonicClock(), True)])
def test_start_warns_of_a_missing_priority_lead_on_a_real_clock_only(
    clock: Any, warned: bool, caplog: pytest.LogCaptureFixture
) -> None:
    """manager.py:237:36:drop-not (``not isinstance(self.clock, VirtualClock)``): the warning
    that conflict-aware priorities act too late without ``priority_lead`` would be given on
    simulated time, where nothing is late, and not on the real clock it is for."""
    m = Manager(
        RuleSet.from_text(f"def_start event E event F def_end rule_start {PRIORITISED} rule_end"),
        clock=clock,
        priorities=["R1 > R2"],
        priority_semantics="conflict-aware",
    )
    with caplog.at_level(logging.WARNING, logger="cosleec.runtime"):
        m.start(check=False)
    assert any(WARNED in r.getMessage() for r in caplog.records) is warned
    m.close()


# ---------------------------------------------------------------------------- Manager.note: what it counts


def test_a_noted_rejection_is_counted_and_a_reload_attempt_is_not() -> None:
    """manager.py:484:45:1-0 (``stats.rejected += 1``): a front end's rejected input, noted,
    is counted in ``stats["rejected"]`` as the Manager's own rejections are; a reload
    attempt is only recorded."""
    m = Manager.from_text(f"def_start event E event F def_end rule_start {PRIORITISED} rule_end")
    heard: list[str] = []
    m.subscribe(lambda ev: heard.append(str(ev.kind)))
    m.note("reload-attempt", {"allowed": False})
    assert m.stats["rejected"] == 0
    m.note("rejected", {"reason": "not a number"})
    m.note("rejected", {"reason": "not a number"})
    assert m.stats["rejected"] == 2
    assert heard == ["reload-attempt", "rejected", "rejected"]
    m.close()


# ---------------------------------------------------------------------------- express: a quiet update


def _quiet_manager(text: str, clock: SetClock, calls: list[str], events: str = "AB") -> Manager:
    """A Manager on a clock that tells it nothing (a VirtualClock's moves judge what fell
    due before they return: the update would find nothing due)."""
    m = Manager.from_text(text, clock=clock)
    for event in events:
        m.capability(event)(lambda ob, d, e=event: calls.append(e))
    m.start()
    return m


def test_an_update_after_a_deadline_passed_judges_the_deadline_first() -> None:
    """express-update-ignores-a-due-deadline: an update taken by the express lane while a
    deadline is due would apply its values before the violation (and its ``otherwise``)
    that came first; the violation is there as soon as the update returns."""
    text = (
        "def_start event C event A event B measure b : boolean def_end rule_start "
        "R1 when C then B within 1 seconds otherwise A "
        "R2 when A then B within 9 seconds unless {b} then A within 9 seconds rule_end"
    )
    clock, calls = SetClock(0.0), []
    m = _quiet_manager(text, clock, calls)
    m.update({"b": False})
    m.event("C")
    clock.t = 3.0
    m.update({"b": True})
    assert m.stats["violations"] == 1 and calls[-1] == "A"  # the otherwise ran at the update
    m.close()


@pytest.mark.parametrize("watched", [False, True])
def test_an_update_after_a_held_action_s_interval_opened_dispatches_it(watched: bool) -> None:
    """express-update-ignores-held (and, with an observer, express-recorded-update-ignores-held):
    an update taken by the express lane while an action is held would leave it held past the
    opening of its interval, which the update's step notices (no timer runs on a virtual
    clock)."""
    text = (
        "def_start event C event A event B measure b : boolean def_end rule_start "
        "R1 when C then B within [2 seconds, 5 seconds] rule_end"
    )
    clock, calls = SetClock(0.0), []
    m = _quiet_manager(text, clock, calls, "B")
    if watched:  # records read: the lane's update in a step of its own
        m.subscribe(lambda ev: None)
    m.update({"b": False})
    m.event("C")
    assert calls == []  # held until its interval opens
    clock.t = 2.5
    m.update({"b": True})
    assert calls == ["B"]
    m.close()


def test_a_trigger_that_also_fulfils_an_obligation_fulfils_it() -> None:
    """express-ignores-what-is-awaited: a trigger that the express lane took while an
    obligation in force awaits its event would decide its rule and leave that obligation
    owed (the lane does not meet an occurrence with what is in force)."""
    text = (
        "def_start event C event A event B measure b : boolean def_end rule_start "
        "R1 when C then A within 5 seconds R2 when A then B within 5 seconds rule_end"
    )
    clock, calls = SetClock(0.0), []
    m = _quiet_manager(text, clock, calls)
    m.update({"b": False})
    m.event("C")
    clock.t = 1.0
    m.event("A")
    assert [(t.rule, t.event) for t in m.outstanding()] == [("R2", "B")]
    m.close()


def test_an_event_named_by_a_lookalike_of_a_string_is_refused() -> None:
    """express-takes-any-name: the express lane would put a trigger in force for a name that
    only compares equal to a declared event; the general path refuses it (fail closed)."""
    text = "def_start event C event A measure b : boolean def_end rule_start R1 when C then A within 5 seconds rule_end"
    clock, calls = SetClock(0.0), []
    m = _quiet_manager(text, clock, calls, "A")
    m.update({"b": False})
    with pytest.raises(Exception, match="string"):
        m.event(Lookalike("C"))  # type: ignore[arg-type]
    assert m.outstanding() == [] and m.stats["rejected"] == 1
    m.close()


def test_an_action_fulfilled_between_its_decision_and_its_start_is_not_run() -> None:
    """plans-admit-without-check: an action whose obligation ended after the decision put it
    in force and before its implementation started (here the robot reports the event in
    that gap, where the timer is told of the new deadline) would still be run; the check
    where it starts leaves it out, on the plan's path as on the general one."""
    text = "def_start event C event A def_end rule_start R1 when C then A within 50 seconds rule_end"
    calls: list[str] = []
    m = Manager.from_text(text, clock=MonotonicClock())
    m.capability("A")(lambda ob, d: calls.append("A"))
    m.start(timer=True)  # (the timer is told of each new deadline)
    timer = m._timer
    notify = timer.notify

    def meanwhile(due: float | None = None) -> None:
        timer.notify = notify  # type: ignore[method-assign]  # (once)
        m.event("A")  # the robot did A already: nothing is owed when the dispatch starts
        notify(due)

    timer.notify = meanwhile  # type: ignore[method-assign]
    m.event("C")
    assert timer.notify is notify  # the gap was reached (a deadline to tell the timer of)
    assert calls == [] and m.outstanding() == []
    m.close()
