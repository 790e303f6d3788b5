"""The reference semantics judges long traces in time linear in their length (issue 28,
finding 8: ``cosleec conforms`` on a 1M-line trace ran for minutes).

Each step used to scan every obligation in force, so a trace that leaves obligations
pending (an untimed response the robot never gives) took time quadratic in its length.
Measured as a ratio within one test -- four times the trace against the same machine at
the same moment -- never against a wall-clock figure.
"""

from __future__ import annotations

import time

import pytest

from cosleec.lang import Reading, parse
from cosleec.semantics import Step, judge

RULES = """def_start
    event Ask event Open event Refuse event Explain event Warn event Stop
    measure undressed : boolean
    measure distressed : boolean
def_end
rule_start
    R1 when Ask then Open within 30 seconds
        unless undressed then Refuse and Explain
        unless distressed then Warn and Open within 10 seconds
    R2 when Ask and distressed then not Stop within 20 seconds
    R3 when Ask then Explain within 1 minutes unless undressed then not Open within 5 seconds
rule_end
"""


def day(requests: int) -> list[Step]:
    """``requests`` requests 10 s apart; every other one leaves ``Refuse and Explain`` pending
    for ever (untimed), the rest are answered."""
    steps = []
    for n in range(requests):
        t = 10.0 * n
        undressed = n % 2 == 1
        steps.append(Step(t, values={"undressed": undressed, "distressed": n % 3 == 0}))
        steps.append(Step(t, event="Ask"))
        if not undressed:
            steps.append(Step(t + 5, event="Open"))
            steps.append(Step(t + 6, event="Explain"))
    steps.append(Step(10.0 * requests + 100))
    return steps


@pytest.mark.parametrize(
    "options",
    [
        Reading(),
        Reading(priorities=frozenset({("R2", "R3")})),
        Reading(priorities=frozenset({("R2", "R3")}), priority_semantics="conflict-aware"),
    ],
    ids=["plain", "cancel", "conflict-aware"],
)
def test_judging_takes_time_linear_in_the_trace(options: Reading) -> None:
    spec = parse(RULES)

    def seconds(requests: int) -> float:
        steps = day(requests)
        t = time.process_time()  # this process's CPU: what other processes do counts little
        j = judge(spec, steps, options)
        took = time.process_time() - t
        assert sum(1 for v in j.verdicts if v.status == "pending") >= requests // 2  # Refuse, Explain
        return took

    seconds(50)  # warm up
    small = min(seconds(600) for _ in range(2))
    large = min(seconds(2400) for _ in range(2))
    assert large < 8 * small, (small, large)  # linear: 4x; scanning every pending item: 16x


def own_events(rules: int) -> str:
    """``rules`` rules, each triggered by an event of its own."""
    defs = " ".join(f"event E{i} event A{i}" for i in range(rules))
    body = "\n".join(f"R{i} when E{i} then A{i} within 10 seconds" for i in range(rules))
    return f"def_start {defs} def_end\nrule_start\n{body}\nrule_end\n"


def test_an_occurrence_costs_the_rules_it_triggers_not_every_rule() -> None:
    """`conforms` of 100,000 rules looked at every rule at every occurrence (10,000 lines:
    156 s): eight times the rules, the same trace, about the same time."""
    steps = [Step(float(t), event=f"{'E' if t % 2 == 0 else 'A'}{(t // 2) % 100}") for t in range(4000)]

    def seconds(rules: int) -> float:
        spec = parse(own_events(rules))
        t = time.process_time()
        judge(spec, steps)
        return time.process_time() - t

    seconds(100)  # warm up
    small = min(seconds(500) for _ in range(2))
    large = min(seconds(4000) for _ in range(2))
    assert large < 3 * small, (small, large)  # a scan of every rule: 8x
