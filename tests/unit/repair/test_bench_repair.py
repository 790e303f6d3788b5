"""The ``repair_case_studies`` benchmark's own computations (benchmarks/repair_case_studies.py):
which rules the experts changed, when a top fix agrees with them, how reasons group, the
summary's figures and targets, and one whole file run through it (a small file written here,
so that no case study runs in the unit tests)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from cosleec.analysis import Settings
from cosleec.repair import Edit, Patch

ROOT = Path(__file__).resolve().parents[3]


def _load() -> ModuleType:
    sys.path.insert(0, str(ROOT / "benchmarks"))  # it imports _common, beside it
    try:
        spec = importlib.util.spec_from_file_location(
            "bench_repair", ROOT / "benchmarks" / "repair_case_studies.py"
        )
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules["bench_repair"] = module  # dataclasses look their module up
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))


br = _load()

DEFS = (
    "def_start\n  event A\n  event B\n  event C\n  event D\n  measure x : boolean\n"
    "  measure y : boolean\ndef_end\n"
)


def text(rules: str, extra: str = "") -> str:
    return f"{DEFS}rule_start\n{rules}\nrule_end\n{extra}"


INITIAL = text(
    "  R1 when A then B within 5 seconds\n"
    "  R2 when C then D within 5 seconds\n"
    "  R4 when D then not B within 2 seconds"
)


# ------------------------------------------------------------------------- expert changes


def test_the_experts_changes_are_removed_added_and_edited_rules_by_name() -> None:
    corrected = text(
        "  // layout and comments do not count\n"
        "  R1 when A\n     then B within 5 seconds\n"
        "  R2 when C then D within 6 seconds\n"  # one digit: edited
        "  R3 when A and {x} then C"  # added; R4 removed
    )
    changes = br.expert_changes(INITIAL, corrected)
    assert changes.rules == frozenset({"R2", "R3", "R4"})
    assert changes.events == frozenset({"C", "A", "D"})  # R2's, R3's, R4's triggers


def test_an_unchanged_file_has_no_changes_and_a_trigger_edit_counts() -> None:
    assert br.expert_changes(INITIAL, INITIAL).rules == frozenset()
    edited = INITIAL.replace("R1 when A then", "R1 when A and {y} then")
    changes = br.expert_changes(INITIAL, edited)
    assert changes.rules == frozenset({"R1"}) and changes.events == frozenset({"A"})
    negated = INITIAL.replace("then not B", "then B")  # a prohibition made an obligation
    assert br.expert_changes(INITIAL, negated).rules == frozenset({"R4"})


def test_a_file_that_does_not_check_is_an_error_not_an_empty_change() -> None:
    with pytest.raises(ValueError, match="does not check"):
        br.expert_changes(INITIAL, INITIAL.replace("R2 when C", "R2 when Nowhere"))


def test_added_triggers_are_the_events_of_rules_only_the_fixed_text_has() -> None:
    before = br.spec_of(INITIAL, "a.sleec")
    after = br.spec_of(
        INITIAL.replace("rule_end", "  R9 when C then not A\n  R1b when B then A\nrule_end"), "b"
    )
    assert br.added_triggers(before, after) == frozenset({"C", "B"})
    assert br.added_triggers(before, before) == frozenset()
    renamed = br.spec_of(INITIAL.replace("R2 when", "R2x when"), "c")
    assert br.added_triggers(before, renamed) == frozenset({"C"})


def patch(operator: str, rules: tuple[str, ...]) -> Patch:
    return Patch(operator, "a patch", rules, (Edit(0, 0, ""),))


def test_a_top_fix_agrees_when_it_names_a_changed_rule() -> None:
    changes = br.Changes(frozenset({"R2", "R3"}), frozenset({"C"}))
    none: frozenset[str] = frozenset()
    assert br.agrees(patch("remove-rule", ("R2",)), none, changes)
    assert br.agrees(patch("merge-rules", ("R1", "R3")), none, changes)
    assert not br.agrees(patch("remove-rule", ("R1",)), none, changes)
    assert not br.agrees(patch("remove-rule", ()), none, changes)


def test_an_added_rule_agrees_by_its_trigger_event_and_only_for_add_rule() -> None:
    changes = br.Changes(frozenset({"R2"}), frozenset({"C"}))
    assert br.agrees(patch("add-rule", ()), frozenset({"C"}), changes)
    assert br.agrees(patch("add-rule", ("R7",)), frozenset({"A", "C"}), changes)
    assert not br.agrees(patch("add-rule", ()), frozenset({"A"}), changes)
    # another operator's added rule (a split) is judged by the rules it names only
    assert not br.agrees(patch("split-rule", ("R1",)), frozenset({"C"}), changes)


# ------------------------------------------------------------------------------ reasons


def test_reasons_group_without_their_names_and_counts() -> None:
    a = "3 candidates, none verified: new finding: redundant R5; redundant R2 is still reported"
    b = "1 candidate, none verified: concern-raised c1 is still reported; new finding: redundant R9"
    assert (
        br.reason_kind(a)
        == br.reason_kind(b)
        == ("none verified: new finding: redundant; the finding is still reported")
    )
    c = "2 candidates, none verified: new finding: concern-raised c4"
    assert br.reason_kind(c) == "none verified: new finding: concern-raised"
    assert br.reason_kind("2 candidates, none verified: not settled: redundancy of R1 (timeout)") == (
        "none verified: not settled by the solver"
    )
    assert br.reason_kind("4 candidates, none verified: the patched file does not check: 3:4: x") == (
        "none verified: the patched file does not check"
    )
    plain = "no repair operator applies to a concern-raised finding of this form"
    assert br.reason_kind(plain) == plain
    assert br.reason_kind("2 candidates, none verified: it changes the concerns") == (
        "none verified: it changes the concerns"
    )


# ------------------------------------------------------------------------------ summary


def finding(
    seconds: float, repaired: bool, agrees: bool | None = None, code: str = "redundant"
) -> dict[str, Any]:
    top = None if not repaired else {"operator": "remove-rule", "agrees": agrees}
    why = "" if repaired else "1 candidate, none verified: new finding: redundant R1"
    return {"code": code, "subject": "R", "repaired": repaired, "seconds": seconds, "why": why, "top": top}


def file_row(findings: list[dict[str, Any]], new: int = 0, verified: bool | None = True) -> dict[str, Any]:
    return {
        "file": "NickF0211__LEGOS-SLEEC__X__x.sleec",
        "analysis_s": 1.0,
        "repair_s": 4.0,
        "findings": findings,
        "other_findings": [finding(0.1, True)],
        "set": {"new_findings": ["redundant R9"] * new, "verified": verified, "left_of_kinds": []},
    }


def test_the_summary_counts_and_the_targets_hold_at_their_bounds() -> None:
    rows = [finding(5.0, True, True)] * 8 + [finding(60.0, True, False), finding(1.0, False)]
    s = br.summary([file_row(rows[:5]), file_row(rows[5:])])
    assert (s["findings"], s["repaired"], s["repaired_percent"]) == (10, 9, 90.0)
    assert s["median_s_per_finding"] == 5.0 and s["worst_s_per_finding"] == 60.0
    assert s["expert_agreement"] == round(8 / 9, 3)
    assert s["expert_agreement_counts"] == {"agree": 8, "top_fixes": 9}
    assert (s["total_s"], s["analysis_s"], s["repair_over_analysis"]) == (8.0, 2.0, 4.0)
    assert (s["other_findings"], s["other_repaired"]) == (2, 2)
    assert s["meets_targets"] is True  # 90 %, 5 s and 60 s are all within the targets
    assert s["unrepaired"] == [
        {
            "file": "NickF0211__LEGOS-SLEEC__X__x.sleec",
            "code": "redundant",
            "subject": "R",
            "why": rows[-1]["why"],
        }
    ]
    assert s["unrepaired_by_reason"] == {"none verified: new finding: redundant": ["X: redundant R"]}


@pytest.mark.parametrize(
    "rows, new, verified",
    [
        (
            [finding(5.0, True, True)] * 8 + [finding(60.0, True), finding(1.0, False)] * 1,
            1,
            True,
        ),  # a new finding
        (
            [finding(5.0, True, True)] * 8 + [finding(60.0, True), finding(1.0, False)],
            0,
            False,
        ),  # set refused
        ([finding(5.0, True)] * 7 + [finding(60.0, True)] + [finding(1.0, False)] * 2, 0, True),  # 80 %
        ([finding(5.01, True)] * 9 + [finding(1.0, False)], 0, True),  # median over 5 s
        ([finding(1.0, True)] * 9 + [finding(60.01, True)], 0, True),  # worst over 60 s
    ],
)
def test_each_target_missed_is_a_miss(rows: list[dict[str, Any]], new: int, verified: bool) -> None:
    assert br.summary([file_row(rows, new, verified)])["meets_targets"] is False


def test_a_file_with_nothing_to_fix_has_a_trivially_verified_set() -> None:
    s = br.summary([file_row([finding(1.0, True, None)], verified=None)])
    assert (s["sets_verified"], s["sets_empty"], s["sets_refused"]) == (0, 1, 0)
    assert s["meets_targets"] is True
    assert s["expert_agreement"] is None  # no corrected file: nothing to agree with


# ---------------------------------------------------------------------------- one file


def test_one_small_file_runs_through_the_benchmark(tmp_path: Path) -> None:
    """R2 is implied by R1 (redundant), and the concern c1 is allowed: the benchmark's file
    run repairs both, re-analyses the patch set itself, and judges agreement against a
    corrected file that removes R2."""
    rules = "  R1 when A then B within 5 seconds\n  R2 when A then B within 9 seconds"
    concern = "concern_start\n  c1 when C and {x} then D\nconcern_end\n"
    initial = tmp_path / "tiny.sleec"
    initial.write_text(text(rules, concern), encoding="utf-8")
    (tmp_path / "tiny-corrected.sleec").write_text(text(rules.split("\n")[0], concern), encoding="utf-8")
    row = br.run_file(initial, Settings())
    assert row["expert_changed"] == ["R2"]
    by = {(x["code"], x["subject"]): x for x in row["findings"]}
    assert ("redundant", "R2") in by and ("concern-raised", "c1") in by, list(by)
    red = by["redundant", "R2"]
    assert red["repaired"] and red["why"] == "" and red["seconds"] > 0
    assert red["top"]["agrees"] is (
        "R2" in red["top"]["rules"] or bool(set(red["top"]["added_triggers"]) & {"A"})
    )
    assert row["set"]["new_findings"] == [] and row["set"]["verified"] is True
    s = br.summary([row])
    for k in (
        "repaired_percent",
        "median_s_per_finding",
        "worst_s_per_finding",
        "total_s",
        "repair_over_analysis",
        "new_findings_with_sets",
        "expert_agreement",
        "unrepaired_by_reason",
    ):
        assert k in s


def test_rejections_count_every_reason_of_every_refused_candidate_by_operator() -> None:
    refused = finding(1.0, False)
    refused["candidates_rejected"] = [
        {
            "operator": "add-rule",
            "reasons": ["concern-raised c1 is still reported", "new finding: redundant R_c1"],
        },
        {"operator": "add-rule", "reasons": ["concern-raised c1 is still reported"]},
        {"operator": "add-unless", "reasons": ["new finding: runtime-conflict R3.2/R3.1"]},
    ]
    assert br.rejections([refused, finding(1.0, True)]) == {
        "add-rule": {"the finding is still reported": 2, "new finding: redundant": 1},
        "add-unless": {"new finding: runtime-conflict": 1},
    }
