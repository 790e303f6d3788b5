"""`cosleec decide` and `cosleec demo`: the CLI contract and the scripted scenario."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.cli.main import main
from cosleec.demo.assistive_care.scenario import EXPECTED, STEPS, outcomes
from cosleec.demo.runner import rules_path, run
from cosleec.runtime.decision import shorten

from .test_manager import FIREFIGHTER


def test_decide_json_shape(capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(
            [
                "decide",
                rules_path(),
                "--event",
                "CurtainOpenRequest",
                "--set",
                "userUndressed=true",
                "--set",
                "userDistressed=low",
                "--json",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc == {
        "event": "CurtainOpenRequest",
        "decisions": [
            {
                "rule": "R1",
                "clause": 1,
                "layer": "R1.1",
                "obligations": [
                    {
                        "event": "Refuse",
                        "negated": False,
                        "within_s": None,
                        "from_s": 0.0,
                        "eventually": False,
                        "alternatives": [],
                        "rule": "R1",
                        "item": "R1.1:0",
                        "otherwise": None,
                    },
                    {
                        "event": "ExplainWhy",
                        "negated": False,
                        "within_s": None,
                        "from_s": 0.0,
                        "eventually": False,
                        "alternatives": [],
                        "rule": "R1",
                        "item": "R1.1:1",
                        "otherwise": None,
                    },
                ],
                "explanation": "R1: Refuse and ExplainWhy [clause 1 (unless userUndressed)], because "
                "userUndressed was true; userDistressed >= high was false (userDistressed = low)",
                "for_people": "I will refuse and explain why, because user undressed is yes and user distressed is low.",
            }
        ],
        "conflicts": [],
        "cancelled": [],
    }


def test_decide_otherwise_and_prohibition_objects(capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["decide", rules_path(), "--event", "DressingAbandoned", "--set", "userAssent=true", "--json"])
        == 0
    )
    (d,) = json.loads(capsys.readouterr().out)["decisions"]
    assert d["obligations"] == [
        {
            "event": "RetryAgreed",
            "negated": False,
            "within_s": 120.0,
            "from_s": 0.0,
            "eventually": False,
            "alternatives": [],
            "rule": "R3",
            "item": "R3:0",
            "otherwise": {"event": "SupportCalled", "negated": False, "within_s": 60.0, "otherwise": None},
        }
    ]
    assert (
        main(
            [
                "decide",
                rules_path(),
                "--event",
                "UserFallen",
                "--set",
                "userConscious=true",
                "--set",
                "userConsent=false",
                "--json",
            ]
        )
        == 0
    )
    decisions = json.loads(capsys.readouterr().out)["decisions"]
    assert [d["rule"] for d in decisions] == ["R4", "R6"]
    assert decisions[1]["obligations"][0] == {
        "event": "RecordVideo",
        "negated": True,
        "within_s": 600.0,
        "from_s": 0.0,
        "eventually": False,
        "alternatives": [],
        "rule": "R6",
        "item": "R6:0",
        "otherwise": None,
    }


def test_decide_semantics_and_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rules = tmp_path / "ff.sleec"
    rules.write_text(FIREFIGHTER)
    args = [
        "decide",
        str(rules),
        "--event",
        "CameraStart",
        "--set",
        "personNearby=false",
        "--set",
        "temperature=40",
        "--json",
    ]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["decisions"][0]["clause"] == 2
    assert main([*args, "--semantics", "nested"]) == 0
    assert json.loads(capsys.readouterr().out)["decisions"][0]["clause"] == 0
    assert main(["decide", str(rules), "--event", "CameraStart", "--set", "personNearby=false"]) == 2
    assert "temperature" in capsys.readouterr().err
    assert main(["decide", str(rules), "--event", "CameraStart", "--set", "personNearby=maybe"]) == 2
    assert main(["decide", str(rules), "--event", "Nope"]) == 2
    assert main(["decide", str(rules), "--event", "CameraStart", "--set", "x=1"]) == 2


HUGE = 10_000


def test_decide_text_shortens_a_huge_condition_and_json_keeps_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A generated rule whose condition has 10,000 terms: one short line of text (the
    condition cut at 100 characters, the count of terms left out, eight values named), and
    JSON with the whole explanation. The values are found in one pass over the condition."""
    measures = "\n".join(f"  measure m{i} : boolean" for i in range(HUGE))
    condition = " or ".join(f"m{i}" for i in range(HUGE))
    rules = tmp_path / "huge.sleec"
    rules.write_text(
        f"def_start\n  event A\n  event B\n  event C\n{measures}\ndef_end\n"
        f"rule_start\n  R1 when A then B unless {condition} then C\nrule_end\n"
    )
    args = ["decide", str(rules), "--event", "A", "--set", "m5=true"]
    assert main(args) == 0
    out = capsys.readouterr().out
    shown = (
        "m0 or m1 or m2 or m3 or m4 or m5 or m6 or m7 or m8 or m9 or m10 or m11 or m12 or m13 or m14 or m15"
    )
    values = ", ".join(f"m{i} = unknown" for i in ("0", "1", "10", "100", "1000", "1001", "1002", "1003"))
    assert out == (
        f"R1: C [clause 1 (unless {shown} … (9,984 more terms))], because {shown} … (9,984 more terms) "
        f"was true ({values}, … (9,992 more))\n"
    )
    assert main([*args, "--json"]) == 0
    (d,) = json.loads(capsys.readouterr().out)["decisions"]
    assert d["explanation"].startswith(
        f"R1: C [clause 1 (unless {condition})], because {condition} was true ("
    )
    assert d["explanation"].count(" = unknown") == HUGE - 1
    assert main(args[:-2]) == 2  # no values: the names it needs, the first dozen
    needed = ", ".join(f"m{i}" for i in ("0", "1", "10", "100", *(str(1000 + k) for k in range(8))))
    assert capsys.readouterr().err == (
        f"cosleec decide: no value for {needed}, ... (9,988 more) (needed by R1); give it with --set\n"
    )


def test_shorten_cuts_at_a_word_and_counts_the_terms_left_out() -> None:
    assert shorten("a and b", 7) == "a and b"
    assert shorten("speed + 2 > limit and not {x}", 10) == "speed + 2 … (2 more terms)"
    assert shorten("alpha or beta", 3) == "alp … (2 more terms)"  # no space to cut at
    assert shorten("a or bb", 5) == "a or … (1 more term)"


def test_demo_scenario_exercises_every_clause_as_expected(tmp_path: Path) -> None:
    log = tmp_path / "audit.jsonl"
    r = run(audit=str(log))
    got = outcomes(r.decisions())
    assert got == EXPECTED
    rules = r.manager.ruleset.rules
    covered = {(rule, clause) for rule, clause in got if isinstance(clause, int)}
    for rule in rules:
        for clause in range(len(rule.clauses) + 1):
            assert (rule.name, clause) in covered, f"{rule.name} clause {clause} is not exercised"
    assert r.manager.stats["violations"] == 2 and r.manager.stats["refused"] == 1
    assert "refrains from RecordVideo (forbidden)" not in r.robot.log  # the request came from outside
    # every record observers heard is in the log, which also has the options start() recorded first
    assert len(log.read_text().splitlines()) == len(r.events) + 1
    assert any(s[0] == "advance" for s in STEPS)


def test_demo_command_text_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "R1 [R1.1] → Refuse and ExplainWhy" in out and "⛔ RecordVideo refused by R6" in out
    assert main(["demo", "--json"]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert sum(x["kind"] == "decision" for x in lines) == len(EXPECTED)
