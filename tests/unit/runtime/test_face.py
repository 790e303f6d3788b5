"""The runtime's face lists only public API (issue 29, part 5): what a user needs, not the
parts the Manager is built from; the internals cosleec's own packages import are named apart."""

from __future__ import annotations

import ast
from pathlib import Path

import cosleec.runtime

SRC = Path(cosleec.runtime.__file__).resolve().parent.parent

PUBLIC = {
    "MAX_WINDOW_S", "SCAFFOLD_STYLES", "AuditLog", "BindingError", "Capability", "Clock",
    "ConfigurationError", "ContextError", "DeadlineError", "Decision", "DecisionOrigin",
    "Explanations", "ExplanationsError", "HedgeSemantics", "Journal",
    "JournalError", "LayerState", "LayerSwitch", "Manager", "MonotonicClock", "Obligation", "Options",
    "Permission", "PossibleConflict", "ReloadError", "Reloaded", "Reporter", "RuleSet", "RuntimeEvent",
    "Stats", "Task", "Tracked", "UnknownEvents", "Unknowns", "Value", "VirtualClock", "hedge",
    "read_audit", "scaffold",
}  # fmt: skip
PARTS = {
    "Core",
    "Steps",
    "Step",
    "Issuer",
    "Decider",
    "Enforcer",
    "Gate",
    "Runner",
    "Timer",
    "Job",
    "Answers",
}


def test_the_face_lists_exactly_the_public_api() -> None:
    assert set(cosleec.runtime.__all__) == PUBLIC
    assert all(hasattr(cosleec.runtime, n) for n in PUBLIC | set(cosleec.runtime.INTERNALS))


def test_no_part_of_the_manager_is_offered_on_the_face() -> None:
    assert not PARTS & set(dir(cosleec.runtime)), PARTS & set(dir(cosleec.runtime))
    assert not set(cosleec.runtime.INTERNALS) & PUBLIC


def test_what_other_packages_import_from_the_face_is_api_or_a_named_internal() -> None:
    allowed = PUBLIC | set(cosleec.runtime.INTERNALS)
    problems = []
    for path in sorted(SRC.rglob("*.py")):
        if path.is_relative_to(SRC / "runtime"):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module == "cosleec.runtime":
                problems += [
                    f"{path.relative_to(SRC)}: {a.name}" for a in node.names if a.name not in allowed
                ]
    assert not problems, problems
