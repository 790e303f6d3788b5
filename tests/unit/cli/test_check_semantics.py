"""``cosleec check`` and the clause semantics a file declares (issue 33, item 6)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from cosleec.cli import check

TEXT = (
    "def_start\n  event A\n  event B\n  event C\n  measure x: boolean\ndef_end\n"
    "rule_start\n  R1 when A then B unless x then C unless x then B\nrule_end\n"
    "semantics_start\n  unless nested\nsemantics_end\n"
)


def run(*argv: str) -> int:
    parser = argparse.ArgumentParser()
    check.add_parser(parser.add_subparsers())
    args = parser.parse_args(["check", *argv])
    code: int = args.run(args)
    return code


def test_check_uses_the_files_semantics_and_rejects_a_contradiction(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "r.sleec"
    f.write_text(TEXT)
    assert run(str(f)) == 0
    assert "under nested semantics" in capsys.readouterr().out  # the file's, not the default last-wins
    assert run("--semantics", "nested", str(f)) == 0
    capsys.readouterr()
    assert run("--semantics", "last-wins", str(f)) == 1
    out = capsys.readouterr().out
    assert f"{f}:11:3: error: --semantics last-wins contradicts the rule file" in out
    assert "`unless nested`" in out and "hint: leave out --semantics" in out
    plain = tmp_path / "plain.sleec"
    plain.write_text(TEXT.split("semantics_start")[0])
    assert run("--semantics", "nested", str(plain)) == 0
    assert "under nested semantics" in capsys.readouterr().out
    assert run(str(plain)) == 0
    assert "under last-wins semantics" in capsys.readouterr().out
