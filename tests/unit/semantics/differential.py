"""The runtime against the reference semantics: random rule sets, random timed traces.

Hypothesis builds rule sets over every construct the runtime executes (nested hedges,
``within``, intervals, ``otherwise`` chains, ``else``, ``eventually``, ``not E within``,
untimed ``not E``, measure-dependent deadlines, braced inner responses with their own
``unless``, priorities) and traces over their events and measures; the Manager on a
VirtualClock, fed the same trace, must reach exactly the reference verdicts.

Used by test_differential.py (thousands of cases in CI; ``COSLEEC_DIFF=100000`` for a long
run) and by scripts/mutants, which checks that each listed mutation of the runtime makes
this (or another) test fail.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hypothesis import strategies as st

from cosleec.lang import HedgeSemantics, Reading, parse
from cosleec.runtime import Manager
from cosleec.semantics import Step, judge

TRIGGERS = ("T0", "T1")
ACTIONS = ("A", "B")
EVENTS = TRIGGERS + ACTIONS
HEADER = """def_start
  event T0
  event T1
  event A
  event B
  measure b: boolean
  measure n: numeric
  measure s: scale(low, mid, high)
  constant K = 2
def_end
"""

conditions = st.sampled_from(
    ["{b}", "(not {b})", "({n} > K)", "({n} <= 1)", "({s} >= mid)", "({s} < high)", "({b} or ({n} = 0))"]
)
seconds = st.integers(0, 6)
deadlines = st.one_of(
    seconds.map(lambda x: f"within {x} seconds"),
    st.sampled_from(["within ({n} * 2) seconds", "within (3 - {n}) seconds"]),
    st.tuples(st.integers(0, 3), st.integers(0, 3)).map(
        lambda p: f"within [{p[0]} seconds, {p[0] + p[1]} seconds]"
    ),
    st.just("within [1 seconds, ({n} * 1) seconds]"),
    st.just("within [({n} * 1) seconds, 6 seconds]"),
    st.just("eventually"),
    st.just(""),  # untimed
)


@st.composite
def occurrences(draw: st.DrawFn) -> str:
    neg = draw(st.booleans())
    return f"{'not ' if neg else ''}{draw(st.sampled_from(ACTIONS))} {draw(deadlines)}".strip()


@st.composite
def responses(draw: st.DrawFn, depth: int = 0, braced: bool = False) -> str:
    """A response: items joined by ``and``; items may carry ``otherwise``/``else``; inner clauses."""
    items = []
    for _ in range(draw(st.integers(1, 2 if depth == 0 else 1))):
        item = draw(occurrences())
        if depth < 2 and draw(st.integers(0, 3)) == 0:
            item += f" otherwise {draw(inner(depth + 1))}"
        elif depth < 2 and not item.startswith("not ") and draw(st.integers(0, 5)) == 0:
            item += f" else {draw(inner(depth + 1))}"
        items.append(item)
    text = " and ".join(items)
    if braced:
        for _ in range(draw(st.integers(0, 2))):
            text += f" unless {draw(conditions)}"
            if draw(st.booleans()):
                text += f" then {draw(occurrences())}"
    return text


@st.composite
def inner(draw: st.DrawFn, depth: int) -> str:
    if draw(st.booleans()):
        return "{" + draw(responses(depth, braced=True)) + "}"
    if draw(st.integers(0, 4)) == 0:  # two items: an `else` of this is met only by both
        return "{" + draw(occurrences()) + " and " + draw(occurrences()) + "}"
    return draw(occurrences())


@st.composite
def rules(draw: st.DrawFn) -> str:
    out = []
    for i in range(1, draw(st.integers(1, 4)) + 1):
        trigger = draw(st.sampled_from(TRIGGERS))
        cond = draw(st.none() | conditions)
        text = f"R{i} when {trigger}{' and ' + cond if cond else ''} then {draw(responses())}"
        for _ in range(draw(st.integers(0, 3))):
            text += f" unless {draw(conditions)}"
            if draw(st.integers(0, 3)) > 0:
                text += f" then {draw(responses(1))}"
        out.append(text)
    return HEADER + "rule_start\n" + "\n".join(out) + "\nrule_end\n"


values = st.fixed_dictionaries(
    {"b": st.booleans(), "n": st.integers(-1, 4), "s": st.sampled_from(["low", "mid", "high"])}
)


@st.composite
def traces(draw: st.DrawFn) -> list[Step]:
    """All measures known from 0; then events, value changes and pauses at whole seconds
    (so that occurrences land on deadlines and interval starts exactly)."""
    steps = [Step(0, values=draw(values))]
    t = 0
    for _ in range(draw(st.integers(1, 14))):
        t += draw(st.sampled_from([0, 0, 1, 1, 2, 3, 5]))
        kind = draw(st.sampled_from(["event", "event", "event", "set", "tick"]))
        if kind == "event":
            steps.append(Step(t, event=draw(st.sampled_from(EVENTS))))
        elif kind == "set":
            new = draw(values)
            keep = draw(st.sets(st.sampled_from(sorted(new)), min_size=1))
            steps.append(Step(t, values={k: new[k] for k in sorted(keep)}))
        else:
            steps.append(Step(t))
    return steps


@dataclass(frozen=True)
class Case:
    """One differential case: rules, trace and options."""

    text: str
    trace: list[Step]
    semantics: HedgeSemantics
    priorities: tuple[tuple[str, str], ...]
    priority_semantics: str
    lead: float = 0.0


@st.composite
def cases(draw: st.DrawFn) -> Case:
    text = draw(rules())
    names = [line.split()[0] for line in text.split("rule_start\n")[1].splitlines() if line.startswith("R")]
    pri: tuple[tuple[str, str], ...] = ()
    if len(names) > 1 and draw(st.booleans()):
        h, lo = draw(st.permutations(names))[:2]
        pri = ((h, lo),)
    return Case(
        text,
        draw(traces()),
        draw(st.sampled_from(list(HedgeSemantics))),
        pri,
        draw(st.sampled_from(["cancel", "conflict-aware"])),
        draw(st.sampled_from([0.0, 0.0, 1.0, 2.5])),
    )


def reference(case: Case) -> dict[str, Any]:
    """The reference semantics' verdicts, conflicts and clause choices."""
    spec = parse(case.text)
    j = judge(
        spec,
        case.trace,
        Reading(
            semantics=case.semantics,
            priorities=frozenset(case.priorities),
            priority_semantics=case.priority_semantics,
            priority_lead=case.lead,
        ),
    )
    return {
        "verdicts": [
            (v.id, v.rule, v.key, v.start, v.window, v.status, v.at)
            for v in sorted(j.verdicts, key=lambda v: v.id)
        ],
        "conflicts": [(c.time, c.obligation, c.prohibition, c.resolution) for c in j.conflicts],
        "choices": [(f.rule, f.clause) for f in j.firings if f.fired],
    }


class HandClock:
    """A clock set by hand that tells no Manager it moved. A VirtualClock's moves judge what
    fell due before they return; a robot's real clock moves between the timer's ticks, so a
    step can meet deadlines not yet judged (``Manager._catch_up``). The runs here meet them
    so (the mutant occurrence-numbered-before-time-passes needs it)."""

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t

    def set(self, t: float) -> None:
        self.t = t


def runtime(case: Case) -> dict[str, Any]:
    """The same, as the Manager records it (on a clock set by hand between the steps)."""
    clock = HandClock()
    m = Manager.from_text(
        case.text,
        clock=clock,
        dispatch=False,
        semantics=case.semantics,
        priorities=list(case.priorities),
        priority_semantics=case.priority_semantics,
        priority_lead=case.lead,
    )
    final: dict[int, dict[str, Any]] = {}
    conflicts: list[tuple[Any, ...]] = []
    choices: list[tuple[str, int | None]] = []

    def seen(ev: Any) -> None:
        d = ev.data
        if ev.kind == "obligation":
            final[d["id"]] = d
        elif ev.kind == "conflict":
            conflicts.append((d["at"], d["obligation"], d["prohibition"], d["resolution"]))
        elif ev.kind == "decision" and d["event"] != "otherwise":
            choices.append((d["rule"], d["clause"]))

    m.subscribe(seen)
    m.start()
    try:
        for step in case.trace:
            clock.set(float(step.t))
            if step.values:
                m.update({k: v for k, v in step.values.items()})
            if step.event is not None:
                m.event(step.event)
            if not step.values and step.event is None:
                m.tick()
        m.tick()
    finally:
        m.close()
    return {
        "verdicts": [
            (
                d["id"],
                d["rule"],
                d["obligation"]["item"],
                d["start"],
                (d["window"][0], d["window"][1]),
                d["status"],
                d["at"],
            )
            for _, d in sorted(final.items())
        ],
        "conflicts": conflicts,
        "choices": choices,
    }
