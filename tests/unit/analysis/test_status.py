"""Proved or up to a bound: an answer is a proof unless the unfolding of obligations stopped."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.analysis import BOUNDED, DEFAULT_BOUND, PROVED
from cosleec.cli.main import main

from .support import of, run, write

ACYCLIC = (
    "R1 when A then B within 5 seconds\nR2 when A then B within 3 seconds\nR3 when B then C within 2 seconds\n"
    "R4 when C then not D within 1 seconds\nR5 when A then not C within 1 seconds"
)
# R1 re-triggers itself (A owes a later A) unless x: the chain of A's can go on for ever
CYCLIC = "R1 when A then A within [1 seconds, 2 seconds] unless {x}\n" + ACYCLIC.replace("R1 ", "R9 ", 1)
CONCERN = "concern_start\nc1 when A and {m} then B within 4 seconds\nconcern_end"


def test_an_acyclic_rule_set_gives_proofs(tmp_path: Path) -> None:
    r = run(tmp_path, ACYCLIC, CONCERN)
    assert {(f.code, f.subject) for f in r.findings} >= {("redundant", "R1"), ("concern-raised", "c1")}
    for f in r.findings:
        assert f.status == PROVED and f.bound is None, f
        assert f.proof == "proved"


@pytest.mark.parametrize("bound", [3, DEFAULT_BOUND])
def test_a_self_triggering_rule_makes_unsat_answers_bounded(tmp_path: Path, bound: int) -> None:
    r = run(tmp_path, CYCLIC, CONCERN, bound=bound)
    red = of(r, "redundant")
    assert red["R9"].rules == ("R2",)
    assert red["R9"].status == BOUNDED and red["R9"].bound == bound
    assert red["R9"].proof == f"up to bound {bound}"
    # a trace found is a proof at any bound
    concern = of(r, "concern-raised")["c1"]
    assert concern.status == PROVED and concern.bound is None
    # an answer about an event the cycle never reaches stays proved
    assert of(r, "redundant").get("R4") is None or of(r, "redundant")["R4"].status == PROVED


def test_a_cycle_elsewhere_does_not_weaken_a_proof(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A then B within 3 seconds\n"
        "R3 when C then C within [1 seconds, 2 seconds] unless {x}",
        checks="redundant",
    )
    f = of(r, "redundant")["R1"]
    assert f.rules == ("R2",) and f.status == PROVED


def test_an_endless_chain_conflicts_only_up_to_the_bound(tmp_path: Path) -> None:
    """Every A owes a later A: no finite trace has an A and meets R1, at any bound tried."""
    for bound in (1, 2, 5):
        r = run(
            tmp_path, "R1 when A then A within [1 seconds, 2 seconds]", checks="vacuous-conflict", bound=bound
        )
        f = of(r, "vacuous-conflict")["R1"]
        assert (f.status, f.bound, f.rules) == (BOUNDED, bound, ("R1",))


def test_the_cli_prints_and_writes_the_bound(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, CYCLIC)
    assert main(["analyse", "--check", "redundant", "--bound", "4", str(path)]) == 1
    out = capsys.readouterr().out
    assert "rule R9 is redundant: the other rules already imply it: R2 [up to bound 4]" in out
    assert main(["analyse", "--json", "--check", "redundant", "--bound", "4", str(path)]) == 1
    (doc,) = json.loads(capsys.readouterr().out)["files"]
    r9 = next(f for f in doc["findings"] if f["subject"] == "R9")
    assert (r9["status"], r9["bound"]) == ("bounded", 4)
    path = write(tmp_path, ACYCLIC)
    assert main(["analyse", "--check", "redundant", str(path)]) == 1
    out = capsys.readouterr().out
    assert "[proved]" in out and "up to bound" not in out


def test_one_event_owed_by_four_rules_is_still_proved(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A then B within 4 seconds\n"
        "R3 when A then B within 3 seconds\nR4 when A then B within 2 seconds",
        checks="redundant",
    )
    assert {k: (f.rules, f.status) for k, f in of(r, "redundant").items()} == {
        "R1": (("R2",), PROVED),
        "R2": (("R3",), PROVED),
        "R3": (("R4",), PROVED),
    }


def test_three_rules_owing_one_event_fit_the_default_bound(tmp_path: Path) -> None:
    r = run(
        tmp_path,
        "R1 when A then B within 5 seconds\nR2 when A then B within 4 seconds\nR3 when A then B within 3 seconds",
        checks="redundant",
    )
    assert {k: (f.rules, f.status) for k, f in of(r, "redundant").items()} == {
        "R1": (("R2",), PROVED),
        "R2": (("R3",), PROVED),
    }
