"""The repair engine on small files: each operator's candidate is verified (or rejected,
with why), fixes are ranked, and the file's patch set holds together."""

from __future__ import annotations

import pytest

from cosleec.analysis import Settings
from cosleec.repair import Budget, Reading, RepairReport, repair_text
from cosleec.repair.repairing import repairs_of
from cosleec.repair.run import SIDE_BY_SIDE_FROM
from cosleec.repair.verify import key, untouched, verify

HEAD = """def_start
    event E
    event X
    event Y
    measure m : boolean
    measure n : boolean
def_end
"""


def rules(body: str, tail: str = "") -> str:
    return f"{HEAD}rule_start\n{body}rule_end\n{tail}"


def repaired(text: str, budget: Budget | None = None) -> RepairReport:
    return repair_text(text, Reading("t.sleec", Settings()), budget or Budget())


def fixes_of(report: RepairReport, code: str, subject: str) -> list[str]:
    r = next(r for r in report.repairs if (r.finding.code, r.finding.subject) == (code, subject))
    return [f.patch.operator for f in r.fixes]


def test_a_redundant_rule_is_removed_and_the_removal_is_proved() -> None:
    text = rules("    R1 when E then X\n    R2 when E and m then X\n")
    report = repaired(text)
    (r,) = report.repairs
    assert key(r.finding) == ("redundant", "R2")
    (fix,) = r.fixes
    assert fix.patch.operator == "remove-rule" and fix.rank == 1
    assert fix.verdict.verified and fix.verdict.proof == "proved"
    assert fix.text == rules("    R1 when E then X\n")
    assert "-    R2 when E and m then X\n" in fix.diff


def test_two_rules_that_imply_each_other_lose_only_one_together() -> None:
    text = rules("    R1 when E then X\n    R2 when E then X\n")
    report = repaired(text)
    assert {key(r.finding) for r in report.repairs} == {("redundant", "R1"), ("redundant", "R2")}
    assert all(r.fixes for r in report.repairs)  # each removal verifies alone
    plan = report.plan
    assert plan is not None and len(plan.fixes) == 1
    assert plan.text.count("when E then X") == 1  # never both
    assert [key(f) for f, _ in plan.along] == [("redundant", "R2")] and not plan.unrepaired


def test_a_concern_of_a_late_obligation_gets_the_largest_deadline_that_removes_it() -> None:
    text = rules(
        "    R1 when E then X within 12 minutes\n",
        "concern_start\n    c1 when E then not X within 5 minutes\nconcern_end\n",
    )
    report = repaired(text)
    r = report.repairs[0]
    assert key(r.finding) == ("concern-raised", "c1")
    deadline = next(f for f in r.fixes if f.patch.operator == "change-deadline")
    assert "R1 when E then X within 5 minutes" in deadline.text  # not 4, not 6
    assert deadline.verdict.verified


def test_the_deadline_search_works_in_the_concerns_unit() -> None:
    text = rules(
        "    R1 when E then X\n",
        "concern_start\n    c1 when E then not X within 40 seconds\nconcern_end\n",
    )
    r = repaired(text).repairs[0]
    deadline = next(f for f in r.fixes if f.patch.operator == "change-deadline")
    assert "R1 when E then X within 40 seconds" in deadline.text


def test_a_concern_with_no_rule_gets_a_rule_that_forbids_it() -> None:
    text = rules(
        "    R1 when E then Y\n",
        "concern_start\n    c1 when E and {m} then X\nconcern_end\n",
    )
    r = repaired(text).repairs[0]
    assert "add-rule" in [f.patch.operator for f in r.fixes]
    add = next(f for f in r.fixes if f.patch.operator == "add-rule")
    assert "R_c1 when E and {m} then not X" in add.text


def test_a_blocked_purpose_gets_the_blocking_rule_to_step_aside() -> None:
    text = rules(
        "    R1 when E then not Y within 10 minutes\n",
        "purpose_start\n    p1 when E and {m} then Y within 5 minutes\npurpose_end\n",
    )
    r = repaired(text).repairs[0]
    assert key(r.finding) == ("purpose-blocked", "p1")
    ops = [f.patch.operator for f in r.fixes]
    assert {"add-unless", "refine-trigger"} <= set(ops)
    best = r.fixes[0].text
    assert "unless {m}" in best or "(not {m})" in best


def test_a_clause_never_selected_is_removed() -> None:
    text = rules("    R1 when E then X unless {m} then Y unless {m} then X\n")
    report = repaired(text)
    ops = fixes_of(report, "unselectable-clause", "R1.1")
    assert ops == ["remove-clause"]


def test_a_fix_that_makes_a_new_finding_is_rejected_with_why() -> None:
    text = rules("    R1 when E then X\n    R2 when E and m then X\n")
    reading = Reading("t.sleec", Settings())
    checked = reading.check(text)
    assert checked.spec is not None
    found, _, _ = reading.analyse(checked)
    worse = rules("    R1 when E then X\n    R2 when E and m then X\n    R3 when E then X\n")
    v = verify(reading, checked.spec, found, worse, [("redundant", "R2")])
    assert not v.verified
    assert "redundant R2 is still reported" in v.reasons
    assert any(r.startswith("new finding: redundant R") for r in v.reasons)


def test_a_fix_that_does_not_check_is_rejected() -> None:
    reading = Reading("t.sleec", Settings())
    checked = reading.check(rules("    R1 when E then X\n"))
    assert checked.spec is not None
    v = verify(reading, checked.spec, [], rules("    R1 when E then Z\n"), [])
    assert not v.verified and "does not check" in v.reasons[0]


@pytest.mark.parametrize(
    ("changed", "part"),
    [
        (HEAD.replace("event Y\n", "event Y\n    event Z\n"), "declarations"),
        (HEAD.replace("boolean", "numeric"), "declarations"),
    ],
)
def test_a_fix_may_not_touch_the_declarations(changed: str, part: str) -> None:
    reading = Reading("t.sleec", Settings())
    before = reading.check(rules("    R1 when E then X\n")).spec
    after = reading.check(changed + "rule_start\n    R1 when E then X\nrule_end\n").spec
    assert before is not None and after is not None
    assert untouched(before, after) == [part]
    assert untouched(before, before) == []


def test_the_budget_bounds_the_candidates_tried() -> None:
    text = rules("    R1 when E then Y\n", "concern_start\n    c1 when E and {m} then X\nconcern_end\n")
    r = repaired(text, Budget(tried=1, kept=1)).repairs[0]
    assert len(r.fixes) + len(r.rejected) == 1


def test_a_file_that_does_not_check_is_reported_not_repaired() -> None:
    report = repaired("rule_start\n    R1 when\nrule_end\n")
    assert report.failed and not report.repairs and report.plan is None


def test_windows_that_clash_move_apart_by_the_exact_step() -> None:
    text = rules("    R1 when E then X within 5 minutes\n    R2 when E then not X within 10 minutes\n")
    reading = Reading("t.sleec", Settings())
    checked = reading.check(text)
    found, _, _ = reading.analyse(checked)
    r = repairs_of(found[0], text, checked, found, reading, Budget(tried=8, kept=3))
    assert key(r.finding) == ("vacuous-conflict", "R1")
    moved = {p.apply(text): why for p, why in r.rejected if p.operator == "change-deadline"}
    shrunk = text.replace("not X within 10", "not X within 4")  # the largest window that works
    waits = text.replace("X within 5", "X within 11")  # the smallest deadline that works
    assert set(moved) == {shrunk, waits}
    # each removes the conflict at the first trigger, but a second E inside the window clashes:
    assert all(why == ("new finding: situational-conflict R2",) for why in moved.values())
    assert {f.patch.summary.split(" (")[0] for f in r.fixes} >= {"declare R1 > R2", "declare R2 > R1"}


def test_a_concern_can_be_repaired_by_splitting_the_rule_at_its_condition() -> None:
    text = rules("    R1 when E then Y\n", "concern_start\n    c1 when E and {m} then X\nconcern_end\n")
    r = repaired(text, Budget(tried=30, kept=30)).repairs[0]
    split = next(f for f in r.fixes if f.patch.operator == "split-rule")
    assert "R1 when E and (not {m}) then Y" in split.text
    assert "R1_split when E and {m} then Y and (not X)" in split.text or "then Y and not X" in split.text


def test_a_redundant_rule_can_be_merged_into_the_rule_that_implies_it() -> None:
    text = rules("    R1 when E and m then X\n    R2 when E and m and n then X\n")
    r = repaired(text, Budget(tried=30, kept=30)).repairs[0]
    assert key(r.finding) == ("redundant", "R2")
    merged = next(f for f in r.fixes if f.patch.operator == "merge-rules")
    assert merged.text == rules(
        "    R1 when E and m or (m and n) then X\n"
    )  # (the trigger's condition is the `or`)
    assert next(f.patch.operator for f in r.fixes) == "remove-rule"  # the smaller edit first


def test_a_clause_that_clashes_with_another_rule_is_narrowed_where_that_rule_applies() -> None:
    text = rules(
        "    R1 when E then not X within 5 minutes unless m then X within 5 minutes\n    R2 when E and n then not X within 5 minutes\n"
    )
    report = repaired(text, Budget(tried=30, kept=30))
    r = next(r for r in report.repairs if r.finding.code == "runtime-conflict" and "R2" in r.finding.subject)
    narrowed = [
        p for p in [f.patch for f in r.fixes] + [p for p, _ in r.rejected] if p.operator == "refine-unless"
    ]
    assert narrowed, [p.summary for p, _ in r.rejected]
    assert "unless m and not n then X within 5 minutes" in narrowed[0].apply(text)


def test_strengthening_never_turns_an_obligation_into_its_opposite() -> None:
    text = rules(
        "    R1 when E then X within 1 minutes\n",
        "concern_start\n    c1 when E and {m} then X within 1 minutes\nconcern_end\n",
    )
    r = repaired(text, Budget(tried=30, kept=30)).repairs[0]
    tried = [f.patch for f in r.fixes] + [p for p, _ in r.rejected]
    assert "strengthen-response" not in [p.operator for p in tried]


def test_findings_repaired_side_by_side_give_what_one_process_gives() -> None:
    text = rules(
        "    R1 when E then X\n    R2 when E and {m} then X\n    R3 when E then Y\n",
        "concern_start\n    c1 when E and {m} then not Y within 5 minutes\n    c2 when E then X\n"
        "    c3 when E and {n} then not Y\nconcern_end\n",
    )

    def seen(report: RepairReport) -> list[object]:
        return [
            (key(r.finding), [(f.rank, f.patch, f.text, f.behaviour) for f in r.fixes])
            for r in report.repairs
        ]

    alone = repaired(text)
    together = repaired(text, Budget(workers=2))
    assert len(alone.repairs) >= SIDE_BY_SIDE_FROM
    assert seen(together) == seen(alone)
    assert together.plan is not None and alone.plan is not None and together.plan.text == alone.plan.text


def test_a_concern_about_what_the_world_does_says_why_no_rule_repairs_it() -> None:
    text = rules("    R1 when E then X\n", "concern_start\n    c1 exists E and {m}\nconcern_end\n")
    r = repaired(text).repairs[0]
    assert key(r.finding) == ("concern-raised", "c1")
    assert not r.fixes and not r.rejected
    assert r.why_none.startswith("concern c1 says only that E can happen in that state")
