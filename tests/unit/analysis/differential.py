"""The differential check of a rule file against the reference semantics, for property tests.

:func:`agrees` asks the encoding, for each rule, for a trace in which the rule fires and every
rule holds, and has :func:`cosleec.semantics.judge` (the independent oracle) judge it; it runs
the analysis and has every witness confirmed; and it takes traces the test generated as
refutations: one the oracle accepts in which a rule fires refutes a vacuous conflict of that
rule, one in which exactly one rule is broken refutes its redundancy.

Times are kept to multiples of 1/64 s where the check picks them: the witness's times are
floats, and a rational time such as 51/14 plus a deadline can land one rounding step past
the float deadline the oracle computes (a limit of :func:`cosleec.analysis.witness.steps`,
not of the encoding); a finding's witness with other times is not judged here for that reason.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import z3

from cosleec.analysis import CHECKS, Settings, analyse_file
from cosleec.analysis.checks import Analysis
from cosleec.analysis.witness import final_breaches, witness
from cosleec.lang import load
from cosleec.semantics import Step, judge


def agrees(path: Path, s: Settings, traces: Iterable[list[Step]]) -> None:
    """The analysis of ``path`` with settings ``s`` agrees with the oracle (module docstring)."""
    spec = load(path)
    a = Analysis(spec, {}, s)
    text = path.read_text(encoding="utf-8")
    for rule in spec.rules:  # every trace found for "the rule fires, every rule holds" is accepted
        enc, x = a.encoding(rule.trigger.event, s.bound)
        goal = enc.fresh("goal")
        enc.solver.add(z3.Implies(goal, enc.fires(rule, x)))
        dyadic = [z3.IsInt(slot.t * 64) for slot in enc.slots]
        if enc.check([goal, *dyadic, *enc.rule_lit.values()]) == z3.sat:
            w = witness(enc, enc.solver.model(), s.reading)
            assert w.confirmed, (text, s, rule.name, w.timeline)
    report = analyse_file(path, s, list(CHECKS))
    assert not report.failed, [d.message for d in report.diagnostics]
    for f in report.findings:
        if f.witness is not None and all(float(st.t * 64).is_integer() for st in f.witness.steps):
            assert f.witness.confirmed, (text, s, f.code, f.witness.timeline)
    vacuous = {f.subject for f in report.findings if f.code == "vacuous-conflict"}
    redundant = {f.subject for f in report.findings if f.code == "redundant"}
    for trace in traces:
        j = judge(spec, trace, s.reading)
        broken = {v.rule for v in final_breaches(spec, j)}
        fired = {f.rule for f in j.firings if f.fired and f.instance is not None}
        if not broken:  # a trace the oracle accepts: no rule it fires conflicts vacuously
            assert not (fired & vacuous), (text, s, trace, vacuous)
        if len(broken) == 1:  # the others met and this one broken: it is not redundant
            assert not (broken & redundant), (text, s, trace, redundant)
