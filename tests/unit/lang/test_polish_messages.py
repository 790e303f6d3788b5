"""`cosleec check` as SLEEC experts expect it: units and OTHERWISE in the paper notation, the
unit case rule in TK/LEGOS, wrong scale literals, unclosed `(`, "did you mean" for names.

Each test drives the real CLI and pins the whole message: where (file:line:col, caret),
what, the hint, and exit code 1 with no traceback.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.cli.main import main
from cosleec.runtime import Manager


def check(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, name: str, *args: str
) -> tuple[int, str]:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    rc = main(["check", *args, str(path)])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert err == ""  # diagnostics go to stdout
    return rc, out.replace(str(path), name)


# ---------------------------------------------------------------- 1. the paper notation

PAPER = (
    "R1: WHEN CurtainOpenRequest THEN OpenCurtains WITHIN 1 MINUTES OTHERWISE CallSupport WITHIN 10 Seconds\n"
)


def test_paper_units_are_case_insensitive_and_otherwise_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, out = check(tmp_path, capsys, PAPER, "p.txt")
    assert rc == 0
    assert "p.txt: ok (paper, 1 rules, 3 events, 0 measures)" in out
    path = tmp_path / "p.txt"
    assert main(["fmt", "--dialect", "tk", str(path)]) == 0
    assert (
        "R1 when CurtainOpenRequest then OpenCurtains within 1 minutes "
        "otherwise CallSupport within 10 seconds\n" in capsys.readouterr().out
    )


def test_paper_otherwise_means_what_it_means_in_the_dsl() -> None:
    """The deadline is 60 s (MINUTES read as minutes) and the fallback is an `otherwise`."""
    m = Manager.from_text(PAPER)
    (d,) = m.event("CurtainOpenRequest")
    (ob,) = d.obligations
    assert ob.event == "OpenCurtains"
    assert ob.within_s == 60.0


def test_paper_singular_unit_any_case(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = check(tmp_path, capsys, "WHEN Fall THEN CallSupport WITHIN 2 Minute\n", "p.txt")
    assert rc == 1
    assert err == (
        "p.txt: note: inferred 2 events and 0 measures (no def block)\n"
        "p.txt:1:37: error: `Minute` is not a time unit\n"
        "    WHEN Fall THEN CallSupport WITHIN 2 Minute\n"
        "                                        ^~~~~~\n"
        "    hint: SLEEC uses plural units: `minutes`\n"
        "p.txt: 1 error\n"
    )


DSL = """def_start
  event A
  event B
  measure m : scale(low, high)
def_end
rule_start
  R when A and ({m} > low) then B within 1 MINUTES
rule_end
"""


@pytest.mark.parametrize("dialect", ["auto", "legos", "tk"])
def test_dsl_units_are_lower_case_like_its_keywords(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], dialect: str
) -> None:
    """TK and LEGOS keywords are case-sensitive (`WHEN` is a name there), units with them:
    `MINUTES` is an error whose hint says exactly what to write."""
    text = DSL if dialect != "tk" else DSL.replace("({m} > low)", "m > low")
    rc, err = check(tmp_path, capsys, text, "r.sleec", "--dialect", dialect)
    assert rc == 1
    head, *_ = err.splitlines()
    col = 44 if dialect != "tk" else 40
    assert head == f"r.sleec:7:{col}: error: `MINUTES` is not a time unit"
    assert "    hint: units are keywords, written in lower case: `minutes`\n" in err


# ---------------------------------------------------------------- 2. wrong scale literals

SCALE = """def_start
  event CurtainOpenRqt
  event CurtainsOpened
  measure userDistressed : scale(low, medium, high)
  measure pain : scale(none, some)
def_end
rule_start
  Rule1 when CurtainOpenRqt and userDistressed >= extreme then CurtainsOpened
  Rule2 when CurtainOpenRqt and hihg <= userDistressed then CurtainsOpened
rule_end
"""


def test_a_wrong_scale_literal_lists_the_scale(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = check(tmp_path, capsys, SCALE, "r.sleec")
    assert rc == 1
    assert err == (
        "r.sleec:8:51: error: `extreme` is not in the scale of `userDistressed` (low, medium, high)\n"
        "      Rule1 when CurtainOpenRqt and userDistressed >= extreme then CurtainsOpened\n"
        "                                                      ^~~~~~~\n"
        "    hint: compare `userDistressed` with one of its literals: low, medium, high\n"
        "r.sleec:9:33: error: `hihg` is not in the scale of `userDistressed` (low, medium, high)\n"
        "      Rule2 when CurtainOpenRqt and hihg <= userDistressed then CurtainsOpened\n"
        "                                    ^~~~\n"
        "    hint: did you mean `high`?\n"
        "r.sleec: 2 errors\n"
    )


def test_a_literal_of_another_scale_keeps_its_own_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = check(tmp_path, capsys, SCALE.replace("extreme", "some").replace("hihg", "low"), "r.sleec")
    assert rc == 1
    assert err.startswith(
        "r.sleec:8:51: error: `some` is not in the scale of `userDistressed` (low, medium, high); "
        "it is a literal of `pain`\n"
    )


# ---------------------------------------------------------------- 3. an unclosed `(`

UNCLOSED = """def_start
  event A
  event B
  measure x : boolean
  measure y : boolean
def_end
rule_start
  R1 when A then B unless (x and y
  R2 when A then B
rule_end
"""


def test_an_unclosed_paren_is_reported_where_it_opens(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = check(tmp_path, capsys, UNCLOSED, "r.sleec")
    assert rc == 1
    assert err == (
        "r.sleec:8:27: error: `(` is never closed\n"
        "      R1 when A then B unless (x and y\n"
        "                              ^\n"
        "r.sleec:9:3: note: the parser reached `R2` with it still open\n"
        "    hint: add the `)` where the parenthesised expression ends\n"
        "r.sleec: 1 error\n"
    )


def test_the_innermost_unclosed_paren_at_end_of_file_and_in_the_paper_notation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = check(tmp_path, capsys, "WHEN A AND (x OR (y AND z) OR (w THEN B\n", "p.txt")
    assert rc == 1
    assert err.startswith(
        "p.txt:1:31: error: `(` is never closed\n"
        "    WHEN A AND (x OR (y AND z) OR (w THEN B\n"
        "                                  ^\n"
        "p.txt:1:34: note: the parser reached `THEN` with it still open\n"
    )
    rc, err = check(tmp_path, capsys, UNCLOSED.replace("  R2 when A then B\nrule_end\n", ""), "r.sleec")
    assert rc == 1
    assert err.startswith("r.sleec:8:27: error: `(` is never closed\n")
    assert "r.sleec:8:35: note: the parser reached end of file with it still open\n" in err


def test_a_paren_closed_later_is_not_called_unclosed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc, err = check(tmp_path, capsys, UNCLOSED.replace("(x and y", "(x y)"), "r.sleec")
    assert rc == 1
    assert err.startswith("r.sleec:8:30: error: unexpected `y`; expected `)`, `and`, `or`\n")


# ---------------------------------------------------------------- 4. did you mean

NAMES = """def_start
  event CurtainOpenRqt
  event CurtainsOpened
  measure userUnderDressed : boolean
def_end
rule_start
  Rule1 when CurtainOpenRq and userUnderDresed then CurtainsOpend
rule_end
"""


def test_did_you_mean_for_events_and_measures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = check(tmp_path, capsys, NAMES, "r.sleec")
    assert rc == 1
    assert err == (
        "r.sleec:7:14: error: trigger `CurtainOpenRq` is not declared as an event\n"
        "      Rule1 when CurtainOpenRq and userUnderDresed then CurtainsOpend\n"
        "                 ^~~~~~~~~~~~~\n"
        "    hint: did you mean `CurtainOpenRqt`?\n"
        "r.sleec:7:32: error: `userUnderDresed` is not declared (expected a measure)\n"
        "      Rule1 when CurtainOpenRq and userUnderDresed then CurtainsOpend\n"
        "                                   ^~~~~~~~~~~~~~~\n"
        "    hint: did you mean `userUnderDressed`?\n"
        "r.sleec:7:53: error: response `CurtainsOpend` is not declared as an event\n"
        "      Rule1 when CurtainOpenRq and userUnderDresed then CurtainsOpend\n"
        "                                                        ^~~~~~~~~~~~~\n"
        "    hint: did you mean `CurtainsOpened`?\n"
        "r.sleec: 3 errors\n"
    )


# ---------------------------------------------------------------- 5. the DSL's forms in the paper notation


def test_paper_unless_then_says_in_which_case(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`UNLESS c THEN B` is the DSL's form; the paper writes `IN WHICH CASE`, in the case used."""
    text = "WHEN CurtainOpenRequest THEN OpenCurtains\nUNLESS UserUndressed THEN (Refuse AND ExplainWhy)\n"
    rc, err = check(tmp_path, capsys, text, "p.txt")
    assert rc == 1
    assert err == (
        "p.txt:2:22: error: in the paper notation an exception's response follows `IN WHICH CASE`, "
        "not `THEN` (`unless c then B` is the DSL's form)\n"
        "    UNLESS UserUndressed THEN (Refuse AND ExplainWhy)\n"
        "                         ^~~~\n"
        "    hint: write `IN WHICH CASE` for `THEN`: `UNLESS UserUndressed IN WHICH CASE (Refuse AND ExplainWhy)`\n"
        "p.txt: 1 error\n"
    )
    rc, err = check(tmp_path, capsys, text.lower().replace("unless userundressed", "unless a and b"), "p.txt")
    assert rc == 1
    assert err.startswith(
        "p.txt:2:16: error: in the paper notation an exception's response follows `in which case`"
    )
    assert (
        "    hint: write `in which case` for `then`: `unless a and b in which case (refuse and explainwhy)`\n"
        in err
    )


@pytest.mark.parametrize(
    ("text", "where", "written"),
    [
        ("WHEN A THEN B WITHIN 5\n", "1:15", "WITHIN 5"),
        ("WHEN A THEN B WITHIN 5 AND C\n", "1:15", "WITHIN 5"),
        ("WHEN A THEN B\nUNLESS c IN WHICH CASE (C within 2 * 3)\n", "2:27", "within 2 * 3"),
        ("WHEN A THEN B within 2 OTHERWISE C\n", "1:15", "within 2"),
    ],
)
def test_a_time_limit_without_unit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, where: str, written: str
) -> None:
    rc, err = check(tmp_path, capsys, text, "p.txt")
    assert rc == 1
    head, _, caret, hint, *_ = err.splitlines()
    assert head == f"p.txt:{where}: error: `{written}` has no time unit"
    assert caret.strip() == "^" + "~" * (len(written) - 1)  # under the limit, not what follows it
    unit = "SECONDS" if written.isupper() else "seconds"
    assert hint == f"    hint: write the unit: `{written} {unit}` (or minutes, hours, days)"


def test_a_time_limit_without_unit_in_the_dsl(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = check(tmp_path, capsys, DSL.replace("within 1 MINUTES", "within 1"), "r.sleec")
    assert rc == 1
    assert err == (
        "r.sleec:7:35: error: `within 1` has no time unit\n"
        "      R when A and ({m} > low) then B within 1\n"
        "                                      ^~~~~~~~\n"
        "    hint: write the unit: `within 1 seconds` (or minutes, hours, days)\n"
        "r.sleec: 1 error\n"
    )


def test_a_comma_in_the_paper_notation(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, err = check(tmp_path, capsys, "WHEN A THEN B\nUNLESS c, IN WHICH CASE C\n", "p.txt")
    assert rc == 1
    assert err == (
        "p.txt:2:9: error: `,` has no place in the paper notation\n"
        "    UNLESS c, IN WHICH CASE C\n"
        "            ^\n"
        "    hint: join responses with `AND`, and write an exception as `UNLESS c IN WHICH CASE B`, "
        "without a comma\n"
        "p.txt: 1 error\n"
    )
