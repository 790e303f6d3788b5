"""Repairs for what ``cosleec analyse`` finds: verified, ranked patches, and a set per file that
holds together (``cosleec analyse --fix``).

Built on :mod:`cosleec.analysis` (z3 stays the only solver): the operators derive candidate
edits from each finding's cause and situation (operators.py), verification re-runs the
whole analysis on the patched text (verify.py), the solver measures what else each
verified patch changes in the robot's behaviour (behaviour.py), and the best fixes are
combined into one patch set that verifies applied together (together.py).

Typical use::

    from cosleec.analysis import Settings
    from cosleec.repair import repair_file
    report = repair_file("rules.sleec", Settings(), legos_compat=True)
    for r in report.repairs:
        for fix in r.fixes:
            print(fix.rank, fix.patch.summary)
            print(fix.diff)
    print(report.plan.diff if report.plan else "")
"""

from __future__ import annotations

from cosleec.repair.behaviour import BehaviourChange, Region
from cosleec.repair.fixes import Fix, Repairs
from cosleec.repair.patch import OPERATORS, Edit, Patch
from cosleec.repair.repairing import Budget
from cosleec.repair.run import RepairReport, repair_file, repair_text
from cosleec.repair.sarif import with_fixes
from cosleec.repair.together import PatchSet
from cosleec.repair.verify import Reading, Verdict

__all__ = [
    "OPERATORS",
    "BehaviourChange",
    "Budget",
    "Edit",
    "Fix",
    "Patch",
    "PatchSet",
    "Reading",
    "Region",
    "RepairReport",
    "Repairs",
    "Verdict",
    "repair_file",
    "repair_text",
    "with_fixes",
]
