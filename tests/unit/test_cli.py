"""The CLI contract: exit codes, JSON shape, canonical printing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosleec.cli.main import main

GOOD = "def_start event E event F measure a : boolean def_end rule_start R1 when E then F unless a rule_end\n"
BAD = "def_start event E def_end rule_start R1 when E then G rule_end\n"


@pytest.fixture
def files(tmp_path: Path) -> tuple[Path, Path]:
    good, bad = tmp_path / "good.sleec", tmp_path / "bad.sleec"
    good.write_text(GOOD)
    bad.write_text(BAD)
    return good, bad


def test_check_exit_codes(files: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    good, bad = files
    assert main(["check", str(good)]) == 0
    assert main(["check", str(good), str(bad)]) == 1
    out = capsys.readouterr().out
    assert f"{bad}:1:{BAD.index(' G ') + 2}: error: response `G` is not declared as an event" in out
    assert "^" in out
    assert main(["check"]) == 2
    assert main(["check", "--dialect", "nope", str(good)]) == 2


def test_check_json(files: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    good, bad = files
    assert main(["check", "--json", str(good), str(bad)]) == 1
    doc = json.loads(capsys.readouterr().out)
    g, b = doc["files"]
    assert g == {
        "path": str(good),
        "ok": True,
        "dialect": "tk",
        "rules": 1,
        "events": 2,
        "measures": 1,
        "diagnostics": [],
    }
    assert (
        b["ok"] is False and b["diagnostics"][0]["line"] == 1 and b["diagnostics"][0]["severity"] == "error"
    )
    assert set(b["diagnostics"][0]) >= {"line", "col", "severity", "message"}


def test_unreadable_and_non_utf8_files_are_diagnostics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    latin = tmp_path / "latin.sleec"
    latin.write_bytes(b"def_start event \xe9 def_end")
    assert main(["check", str(latin), str(tmp_path / "missing.sleec")]) == 1
    out = capsys.readouterr().out
    assert "not UTF-8" in out and "cannot read file" in out


def test_fmt_converts_dialects(files: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    good, _ = files
    assert main(["fmt", str(good), "--dialect", "legos"]) == 0
    out = capsys.readouterr().out
    assert "R1 when E then F unless {a}" in out
    assert main(["fmt", str(files[1])]) == 1


def test_a_bad_choice_lists_the_choices_as_the_user_types_them(capsys) -> None:  # type: ignore[no-untyped-def]
    from cosleec.cli.main import main

    assert main(["decide", "examples/curtains.sleec", "--event", "X", "--semantics", "nestd"]) == 2
    err = capsys.readouterr().err
    assert "(choose from 'last-wins', 'nested')" in err and "HedgeSemantics" not in err


def test_hostile_rule_files_are_user_errors_not_internal_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["check", str(empty)]) == 1  # before: 0, nothing checked
    assert "no .sleec file" in capsys.readouterr().err
    deep = tmp_path / "deep.sleec"
    deep.write_text(
        "def_start event E event F measure m : boolean def_end rule_start R1 when E and "
        + "not " * 20_000
        + "m then F rule_end"
    )
    assert main(["check", str(deep)]) == 0  # before: 70, RecursionError; then 1, "too deep"; now read
    assert "ok" in capsys.readouterr().out
    long = tmp_path / "long.sleec"
    long.write_text(
        f"def_start event E event F def_end rule_start R1 when E then F within {'9' * 5000} seconds rule_end"
    )
    assert main(["check", str(long)]) == 1  # before: 70, Python's int() digit limit
    assert "4,300 digits" in capsys.readouterr().err


DUPLICATE = "def_start event E event F def_end rule_start R1 when E then F\nR1 when F then E rule_end\n"


def test_check_legos_compat(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    dup = tmp_path / "dup.sleec"
    dup.write_text(DUPLICATE)
    assert main(["check", str(dup)]) == 1
    assert "error: rule `R1` is defined twice" in capsys.readouterr().out
    assert main(["check", "--legos-compat", str(dup)]) == 0
    out = capsys.readouterr().out
    assert f"{dup}:2:1: warning: rule `R1` is defined twice" in out and "`R1__2`" in out
    assert "hint: give each rule a name of its own" in out and "ok (tk, 2 rules" in out
    assert main(["check", "--legos-compat", "--json", str(dup)]) == 0
    (doc,) = json.loads(capsys.readouterr().out)["files"]
    assert doc["ok"] is True and doc["diagnostics"][0]["severity"] == "warning"


def test_fmt_refuses_a_name_legos_would_cut_in_two(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tmp_path / "cut.sleec"
    f.write_text("def_start event E event notStop def_end rule_start\nR1 when E then notStop\nrule_end\n")
    assert main(["fmt", str(f), "--dialect", "legos"]) == 1
    err = capsys.readouterr().err
    assert f"{f}:2:16: error: the response event `notStop` begins with the keyword `not`" in err
    assert "reads it as `not Stop`" in err
    assert main(["fmt", str(f), "--dialect", "tk"]) == 0  # SLEEC-TK reserves its keywords: no cut
    assert "R1 when E then notStop" in capsys.readouterr().out
