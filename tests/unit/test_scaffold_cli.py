"""`cosleec scaffold` through the real CLI: the module it writes, and its refusals."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from cosleec.cli.main import main
from cosleec.runtime import Manager, VirtualClock

ROOT = Path(__file__).resolve().parents[2]
RULES = str(ROOT / "examples" / "assistive_care" / "rules.sleec")


@pytest.mark.parametrize("style", ["task", "capability"])
def test_the_written_module_implements_the_rules_as_it_is(style: str, tmp_path: Path) -> None:
    out = tmp_path / "tasks.py"
    assert main(["scaffold", RULES, "--style", style, "-o", str(out)]) == 0
    spec = importlib.util.spec_from_file_location(f"tasks_{style}", out)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    m = Manager.from_file(RULES, clock=VirtualClock())
    module.install(m)
    m.start()  # the completeness check passes: every clause has its method or capability
    m.update(userUndressed=True, userDistressed="low")
    m.event("CurtainOpenRequest")  # the scaffold reports what it is obliged to: nothing owed
    assert [t.rule for t in m.outstanding()] == []


def test_one_rule_to_stdout_with_its_clauses_documented(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scaffold", RULES, "--rule", "R1"]) == 0
    text = capsys.readouterr().out
    assert "class R1(Task):" in text and "class R2(Task):" not in text
    assert '"""R1.1: unless userUndressed: Refuse; ExplainWhy."""' in text
    assert '"""R1.2: unless userDistressed >= high: WarnUser; OpenCurtains."""' in text
    assert "    @hedge(2)\n    def clause_2(self, decision: Decision) -> None:" in text


def test_it_never_overwrites_a_module(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "tasks.py"
    out.write_text("# my code\n")
    assert main(["scaffold", RULES, "-o", str(out)]) == 1
    assert out.read_text() == "# my code\n"
    assert "never overwrites" in capsys.readouterr().err


def test_an_unknown_rule_is_named_with_a_suggestion(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scaffold", RULES, "--rule", "R11"]) == 1
    assert "no rule 'R11'" in capsys.readouterr().err
