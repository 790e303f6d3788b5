"""docs/repair.md shows what ``cosleec analyse --fix`` does, so the page cannot drift from it.

The page has one worked example per operator the engine generates, each a section headed
``### `OPERATOR`: ...`` holding, in this order, a ```sleec block (the rule file, saved as
``rules.sleec``), a ```text block (``$ cosleec analyse rules.sleec --fix`` and an excerpt of
what it prints: each finding's first line and its ranked fixes, with the elisions of the
docs' console blocks, ``...`` for lines left out) and a ```diff block (the unified diff of
the finding's fix made by that operator). The section ``## Applied together`` has a rule
file, the command's excerpt, and the ```diff of the file's patch set.

Each example is run twice: the command, whose output must match the excerpt, and the
engine (:func:`cosleec.repair.repair_text`), which must give a verified fix with the
section's operator whose diff is the page's (trailing blanks aside, byte for byte).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

from cosleec.analysis import Settings
from cosleec.cli.main import main
from cosleec.repair import OPERATORS, Reading, RepairReport, repair_text
from tests.doc_blocks import matches

ROOT = Path(__file__).resolve().parents[3]
PAGE = ROOT / "docs" / "repair.md"
PATH = "rules.sleec"
"""The name every example's rule file is saved as (its diff says a/rules.sleec)."""
GENERATED = (
    "remove-rule",
    "remove-clause",
    "add-rule",
    "add-unless",
    "refine-unless",
    "refine-trigger",
    "strengthen-response",
    "change-deadline",
    "merge-rules",
    "split-rule",
    "declare-priority",
)
"""The operators the engine generates (every one of :data:`OPERATORS`), in the page's order:
one example each."""
SECTION = re.compile(r"^#{2,3} (.+?)\n(.*?)(?=^#{1,3} |\Z)", re.M | re.S)
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)


@dataclass(frozen=True)
class Example:
    """One section of the page: its heading, rule file, ```text lines and ```diff."""

    heading: str
    rules: str
    shown: tuple[str, ...]
    diff: str

    @property
    def operator(self) -> str:
        """The operator the heading names (``### `add-rule`: ...``)."""
        m = re.match(r"`([a-z-]+)`", self.heading)
        return m.group(1) if m else ""


def sections() -> dict[str, Example]:
    """The page's example sections by heading: each one's first block of each kind."""
    out = {}
    for m in SECTION.finditer(PAGE.read_text(encoding="utf-8")):
        blocks: dict[str, str] = {}
        for f in FENCE.finditer(m.group(2)):
            blocks.setdefault(f.group(1), f.group(2))
        if "sleec" in blocks:
            shown = tuple(blocks.get("text", "").rstrip("\n").split("\n"))
            out[m.group(1)] = Example(m.group(1), blocks["sleec"], shown, blocks.get("diff", ""))
    return out


def blankless(diff: str) -> str:
    """``diff`` without trailing blanks (an editor may strip the space of an empty context
    line); everything else compared byte for byte."""
    return "\n".join(line.rstrip() for line in diff.split("\n"))


def examples() -> list[Example]:
    """The sections with a worked example of one operator, in page order."""
    return [e for e in sections().values() if e.operator]


@cache
def repaired(rules: str) -> RepairReport:
    """The engine's repairs of ``rules`` (as ``cosleec analyse rules.sleec --fix`` reads them)."""
    report = repair_text(rules, Reading(PATH, Settings()))
    assert not report.failed, [d.message for d in report.diagnostics]
    return report


def cli(rules: str, where: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """What ``cosleec analyse rules.sleec --fix`` prints for ``rules``, run in ``where``."""
    (where / PATH).write_text(rules, encoding="utf-8")
    here = Path.cwd()
    os.chdir(where)
    try:
        capsys.readouterr()
        main(["analyse", PATH, "--fix"])
    finally:
        os.chdir(here)
    return capsys.readouterr().out


def shows_the_command(example: Example, where: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The ```text block is ``$ cosleec analyse rules.sleec --fix`` and (an excerpt of) what
    it prints, with the elisions of the docs' console blocks (tests/doc_blocks.py)."""
    assert example.shown[0] == f"$ cosleec analyse {PATH} --fix", example.shown[0]
    shown = list(example.shown[1:])
    literal = [line for line in shown if line.strip() and not line.rstrip().endswith(("...", "…"))]
    assert len(literal) >= 3, f"docs/repair.md, {example.heading}: the excerpt checks too little"
    out = cli(example.rules, where, capsys)
    assert matches(shown, out), (
        f"docs/repair.md, {example.heading}: `cosleec analyse {PATH} --fix` printed\n{out}\n"
        "-- but the page shows --\n" + "\n".join(shown)
    )


def test_one_example_per_operator_the_engine_generates() -> None:
    assert [e.operator for e in examples()] == list(GENERATED)
    assert sorted(GENERATED) == sorted(OPERATORS), "an operator without a worked example, or one gone"


def test_the_page_says_no_operator_is_left_ungenerated() -> None:
    assert "not generated yet" not in PAGE.read_text(encoding="utf-8")


def rejected(rules: str, operator: str) -> list[tuple[str, ...]]:
    """Why the engine rejected each ``operator`` candidate for ``rules`` (the reasons of each)."""
    return [tuple(why) for r in repaired(rules).repairs for p, why in r.rejected if p.operator == operator]


def test_the_split_example_leaves_room_for_the_split_by_a_purpose() -> None:
    """What the page says of split-rule: strengthening R1 for every fall blocks the purpose,
    and without the purpose that verified candidate fills the three fixes kept, before the
    split is tried."""
    rules = sections()["`split-rule`: a rule in two at the concern's condition"].rules
    assert rejected(rules, "strengthen-response") == [("new finding: purpose-blocked p1",)]
    without = rules[: rules.index("purpose_start")]
    ops = [f.patch.operator for r in repaired(without).repairs for f in r.fixes]
    assert "split-rule" not in ops and "strengthen-response" in ops


def test_the_refine_unless_example_needs_its_relations() -> None:
    """What the page says of refine-unless: without the relations another bell within R2's
    minute meets the narrowed clause, so the runtime conflict stays and the clause is rejected."""
    rules = sections()["`refine-unless`: a clause narrowed where another rule applies"].rules
    without = rules[: rules.index("relation_start")]
    assert ("runtime-conflict R2/R1.1 is still reported",) in rejected(without, "refine-unless")
    assert not [f for r in repaired(without).repairs for f in r.fixes if f.patch.operator == "refine-unless"]


def test_the_page_names_every_operator() -> None:
    text = PAGE.read_text(encoding="utf-8")
    missing = [op for op in OPERATORS if f"`{op}`" not in text]
    assert not missing, f"docs/repair.md does not say what these operators do: {missing}"


@pytest.mark.parametrize("example", examples(), ids=lambda e: e.operator)
def test_the_example_is_what_the_engine_gives(
    example: Example, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shows_the_command(example, tmp_path, capsys)
    fixes = [
        f for r in repaired(example.rules).repairs for f in r.fixes if f.patch.operator == example.operator
    ]
    assert fixes, f"no verified {example.operator} fix"
    assert blankless(example.diff) in [blankless(f.diff) for f in fixes], (
        f"docs/repair.md, {example.heading}: the diff shown is not the fix's\n"
        + "\n".join(f.diff for f in fixes)
    )


def test_the_patch_set_example_removes_one_of_two_rules_that_imply_each_other(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    example = sections()["Applied together"]
    report = repaired(example.rules)
    assert [f.code for f in report.findings] == ["redundant", "redundant"]
    assert all(r.fixes and r.fixes[0].patch.operator == "remove-rule" for r in report.repairs)
    plan = report.plan
    assert plan is not None and plan.verdict is not None and plan.verdict.verified
    assert [f.patch.operator for f in plan.fixes] == ["remove-rule"]
    assert not plan.unrepaired and len(plan.along) == 1
    assert blankless(example.diff) == blankless(plan.diff)
    shows_the_command(example, tmp_path, capsys)
