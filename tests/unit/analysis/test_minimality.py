"""Cores are minimal and sufficient: checked by analysing the files again without each rule.

Each file below has exactly one cause per finding, so the core is known; and every rule of
it matters: without any one of them (the rest of the file kept), the finding disappears.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.analysis import Finding

from .support import analyse, sleec

CHAIN = """
R1 when A then B within 5 seconds
R2 when B then C within 2 seconds
R3 when A then not C within 10 seconds
R4 when A then D within 3 seconds
R5 when D then not E within 1 seconds
R6 when E then B within 1 seconds
"""
IMPLIED = """
R1 when A then C within 4 seconds
R2 when A then B within 2 seconds
R3 when B then C within 2 seconds
R4 when A then D within 1 seconds
R5 when C then E within 1 seconds
"""
BLOCKED = """
R1 when B then D within 0 seconds
R2 when A then not D within 1 seconds
R3 when A then E within 5 seconds
R4 when E then not C within 1 seconds
"""
PURPOSE = "purpose_start\np1 exists A and {m} while B\npurpose_end"
FALLBACK = """
R1 when A then B within 5 seconds otherwise C within 2 seconds
R2 when A then not B within 10 seconds
R3 when A then not C within 7 seconds
R4 when C then D within 1 seconds
"""
SITUATION = """
R1 when A then B within [6 seconds, 7 seconds]
R2 when A then not B within 5 seconds
R3 when B then C within 1 seconds
"""

CASES = {
    "chain": (
        CHAIN,
        "",
        {
            ("vacuous-conflict", "R1"): ("R1", "R2", "R3"),
            ("vacuous-conflict", "R3"): ("R1", "R2", "R3"),
            ("vacuous-conflict", "R4"): ("R1", "R2", "R3"),
            ("redundant", "R4"): ("R1", "R2", "R3"),
        },
    ),
    "implied": (IMPLIED, "", {("redundant", "R1"): ("R2", "R3")}),
    "blocked": (BLOCKED, PURPOSE, {("purpose-blocked", "p1"): ("R1", "R2")}),
    "fallback": (
        FALLBACK,
        "",
        {(c, r): ("R1", "R2", "R3") for c in ["vacuous-conflict"] for r in ("R1", "R2", "R3")},
    ),
}
# every finding of these, whatever its subject, must lose it without any rule of its core
EVERY = {**{k: (rules, extra) for k, (rules, extra, _) in CASES.items()}, "situation": (SITUATION, "")}
CORED = {"vacuous-conflict", "redundant", "purpose-blocked", "situational-conflict", "runtime-conflict"}


def _without(rules: str, names: set[str]) -> str:
    return "\n".join(line for line in rules.strip().splitlines() if line.split()[0] not in names)


def _only(rules: str, names: set[str]) -> str:
    return "\n".join(line for line in rules.strip().splitlines() if line.split()[0] in names)


def _analyse(tmp_path: Path, name: str, rules: str, extra: str, code: str) -> dict[tuple[str, str], Finding]:
    path = tmp_path / name
    path.write_text(sleec(rules, extra), encoding="utf-8")
    return {(f.code, f.subject): f for f in analyse(path, [code]).findings}


@pytest.mark.parametrize("case", sorted(CASES))
def test_each_core_is_the_cause_and_every_rule_of_it_matters(tmp_path: Path, case: str) -> None:
    rules, extra, expected = CASES[case]
    path = tmp_path / "full.sleec"
    path.write_text(sleec(rules, extra), encoding="utf-8")
    report = analyse(path, sorted({code for code, _ in expected}))
    got = {(f.code, f.subject): f.rules for f in report.findings if f.code in {c for c, _ in expected}}
    assert got == expected
    for (code, subject), core in expected.items():
        # sufficient: the core alone (with the rule the finding is about) still has the finding
        kept = set(core) | ({subject} if subject.startswith("R") else set())
        alone = _analyse(tmp_path, "core.sleec", _only(rules, kept), extra, code)
        assert alone.get((code, subject)) is not None, (code, subject)
        assert alone[(code, subject)].rules == core
        # minimal: the whole file but one rule of the core no longer has it
        for name in core:
            reduced = _analyse(tmp_path, f"without-{name}.sleec", _without(rules, {name}), extra, code)
            assert (code, subject) not in reduced, (code, subject, name)


@pytest.mark.parametrize("case", sorted(EVERY))
def test_every_finding_with_a_core_loses_it_without_any_core_rule(tmp_path: Path, case: str) -> None:
    """Every check this time, every finding that names rules (runtime conflicts included)."""
    rules, extra = EVERY[case]
    path = tmp_path / "full.sleec"
    path.write_text(sleec(rules, extra), encoding="utf-8")
    findings = [f for f in analyse(path).findings if f.code in CORED and f.rules]
    assert findings
    for f in findings:
        assert all(n.startswith("R") for n in f.rules)
        order = [line.split()[0] for line in rules.strip().splitlines()]
        assert sorted(f.rules, key=order.index) == list(f.rules) or f.code == "runtime-conflict"
        for name in f.rules:
            reduced = _analyse(tmp_path, f"without-{name}.sleec", _without(rules, {name}), extra, f.code)
            assert (f.code, f.subject) not in reduced, (f.code, f.subject, name)


def test_the_core_prefers_the_earlier_rules_when_two_causes_exist(tmp_path: Path) -> None:
    """Two prohibitions each conflict with R1: the core names the first, every run."""
    rules = (
        "R1 when A then B within 5 seconds\nR2 when A then not B within 10 seconds\n"
        "R3 when A then not B within 20 seconds"
    )
    path = tmp_path / "two.sleec"
    path.write_text(sleec(rules), encoding="utf-8")
    found = {f.subject: f.rules for f in analyse(path, ["vacuous-conflict"]).findings}
    # R3's trigger is impossible because of R1 and R2 already: the earlier cause is named
    assert found == {"R1": ("R1", "R2"), "R2": ("R1", "R2"), "R3": ("R1", "R2")}
