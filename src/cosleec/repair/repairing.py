"""Repairing one finding: its candidates verified in turn, the verified ones measured and ranked.

What :func:`~cosleec.repair.run.repair_file` does per finding, in its own process or in a
worker's (workers.py): the candidates (candidates.py) are verified one after another
(verify.py) until enough hold or the budget is spent; each verified one gets its behavioural
diff (behaviour.py), and the fixes are ranked (fixes.py).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from cosleec.analysis import Deadline, Finding, analyse_spec
from cosleec.lang import CheckResult
from cosleec.lang import ast as A
from cosleec.repair.behaviour import Region, behaviour_change
from cosleec.repair.candidates import Candidates
from cosleec.repair.fixes import Fix, Repairs, ranked
from cosleec.repair.followups import follow_ups
from cosleec.repair.patch import unified_diff
from cosleec.repair.verify import Reading, key, verify

TRIED = 6
"""Candidates verified per finding, at most (each is a whole analysis of the patched file)."""
KEPT = 3
"""Verified fixes kept per finding: verification stops once it has this many."""


@dataclass(frozen=True)
class Budget:
    """How hard to look: candidates verified and fixes kept per finding, the run's deadline."""

    tried: int = TRIED
    kept: int = KEPT
    deadline: Deadline | None = None
    workers: int = 1  # processes repairing findings side by side (workers.py); 1: in this one


SKIPPED = "not tried: the deadline passed before its turn"
"""Why a finding has no repairs when the run's deadline passed before it was reached."""


def repairs_of(
    f: Finding, source: str, checked: CheckResult, found: list[Finding], reading: Reading, budget: Budget
) -> Repairs:
    """Verified, ranked fixes of finding ``f`` of the checked ``source``."""
    t0 = time.perf_counter()
    spec = checked.spec
    assert spec is not None and checked.symbols is not None
    if budget.deadline is not None and budget.deadline.passed():
        return Repairs(f, skipped=SKIPPED)
    out = Repairs(f)
    fixes: list[Fix] = []
    constants = dict(checked.symbols.constant_values)

    def gone(changed: A.Specification, target: Finding) -> bool:
        found, unknown = analyse_spec(changed, constants, reading.settings, [target.code], reading.coverage)
        return key(target) not in {key(x) for x in found} and not any(target.subject in u for u in unknown)

    candidates = Candidates(source, spec, gone, reading.settings.reading.untimed_seconds)
    out.cannot = candidates.unrepairable(f)
    queue = candidates.of(f)[: budget.tried]
    names = frozenset(r.name for r in spec.rules)
    second = 0  # follow-ups tried (followups.py), at most half the budget again
    while queue:
        patch = queue.pop(0)
        if len(fixes) >= budget.kept or (budget.deadline is not None and budget.deadline.passed()):
            break
        text = patch.apply(source)
        verdict = verify(reading, spec, found, text, [key(f)], budget.deadline)
        if not verdict.verified:
            out.rejected.append((patch, verdict.reasons))
            more = list(follow_ups(patch, verdict, source, names))[: max(0, budget.tried // 2 - second)]
            second += len(more)
            queue.extend(more)
            continue
        after = verdict.checked
        assert after is not None and after.spec is not None and after.symbols is not None
        change = behaviour_change(
            spec,
            after.spec,
            constants,
            dict(after.symbols.constant_values),
            reading.settings,
            regions(f, spec),
            deadline=budget.deadline,
        )
        fixes.append(Fix(patch, text, unified_diff(source, text, reading.path), verdict, change))
    out.fixes = ranked(fixes)
    out.seconds = time.perf_counter() - t0
    return out


def regions(f: Finding, spec: A.Specification) -> tuple[Region, ...]:
    """Where finding ``f`` lives: the situation of its concern or purpose, the triggers of the
    rules it is about; nowhere for a redundancy (any change is a change elsewhere)."""
    if f.code == "redundant":
        return ()
    situations = {s.name: s for s in (*spec.concerns, *spec.purposes)}
    if f.code in ("concern-raised", "purpose-blocked") and f.subject in situations:
        t = situations[f.subject].trigger
        return (Region(t.event, t.condition),)
    names = set(f.rules) | {part.split(".")[0] for part in f.subject.split("/")}
    return tuple(Region(r.trigger.event, r.trigger.condition) for r in spec.rules if r.name in names)


__all__ = ["KEPT", "SKIPPED", "TRIED", "Budget", "regions", "repairs_of"]
