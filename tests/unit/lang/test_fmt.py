"""`cosleec fmt` as people adopt a formatter: it keeps every comment and blank-line paragraph,
wraps long rules one clause per line, is idempotent, never changes what a file means, and
refuses (at the place) what the chosen notation cannot say."""

from __future__ import annotations

import os
import random
import re
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosleec.cli.main import main
from cosleec.lang import WIDTH, SleecError, analyse, format_source, format_spec, legos_features
from cosleec.lang import ast as A
from cosleec.lang.parser import SLEEC

from .strategies import paper_text, specifications

EXAMPLES = int(os.environ.get("COSLEEC_EXAMPLES", "200"))


def fmt(text: str, dialect: str | None = None, width: int = WIDTH) -> str:
    result = analyse(text, "t.sleec")
    assert result.ok and result.spec is not None, result.render()
    return format_source(result.source, result.spec, dialect, width)


def refusal(text: str, dialect: str) -> list[str]:
    result = analyse(text, "t.sleec")
    assert result.spec is not None
    with pytest.raises(SleecError) as e:
        format_source(result.source, result.spec, dialect)
    return [d.header() for d in e.value.diagnostics]


DEFS = """\
def_start
    event A
    event B
    event C
    measure m : boolean
    measure n : numeric
def_end
"""


# ---------------------------------------------------------------------------- comments


def test_every_kind_of_comment_stays_where_it_belongs() -> None:
    source = """\
// header
/* second header */

def_start
    // events
    event A   // the trigger
    event B
    event C

    // measures
    measure m : boolean
    measure n : numeric // in metres
def_end
/* the rules */
rule_start


    R1 when A then B // first
    // the exception
    unless m then C // second
    unless n > 3 // third

    // paragraph
    R2 when B then C
    // last words
rule_end
// the end
"""
    assert (
        fmt(source)
        == """\
// header
/* second header */

def_start
    // events
    event A // the trigger
    event B
    event C

    // measures
    measure m : boolean
    measure n : numeric // in metres
def_end

/* the rules */
rule_start
    R1 when A then B // first
        // the exception
        unless m then C // second
        unless n > 3 // third

    // paragraph
    R2 when B then C
    // last words
rule_end
// the end
"""
    )


def test_a_comment_inside_the_head_of_a_rule_leads_the_rule() -> None:
    source = DEFS + "rule_start\n    R1 when A\n    // why\n    then B\nrule_end\n"
    assert "    // why\n    R1 when A then B\n" in fmt(source)


def test_trailing_comments_of_one_clause_stay_on_one_line() -> None:
    # one clause commented: the short rule stays on one line, its comments at the end
    source = DEFS + "rule_start\n    R1 when A then B\n    unless /* x */ m // y\nrule_end\n"
    assert "    R1 when A then B unless m /* x */ // y\n" in fmt(source)
    # two clauses commented: one clause per line, each comment with its clause
    source = DEFS + "rule_start\n    R1 when A then B // x\n    unless m // y\nrule_end\n"
    assert "    R1 when A then B // x\n        unless m // y\n" in fmt(source)


def test_a_comment_between_tokens_of_a_line_moves_to_its_end() -> None:
    source = DEFS + "rule_start\n    R1 when /* why */ A then B\nrule_end\n"
    assert "    R1 when A then B /* why */\n" in fmt(source)


def test_blank_lines_collapse_to_one_and_never_open_or_close_a_block() -> None:
    source = DEFS.replace("event B", "\n\n\nevent B") + "rule_start\n\n    R1 when A then B\n\n\nrule_end\n"
    out = fmt(source)
    assert "event A\n\n    event B" in out and "\n\n\n" not in out
    assert "rule_start\n    R1" in out and "then B\nrule_end" in out


def test_a_multi_line_block_comment_is_kept_verbatim() -> None:
    source = DEFS + "rule_start\n  /* one\n     two */\n  R1 when A then B\nrule_end\n"
    assert "    /* one\n     two */\n    R1 when A then B" in fmt(source)


def test_legos_gets_block_comments_as_line_comments() -> None:
    source = DEFS + "rule_start\n    /* one\n       two */\n    R1 when A then B /* x\n y */\nrule_end\n"
    out = fmt(source, "legos")
    assert "    // one\n    // two\n    R1 when A then B // x y\n" in out
    assert "/*" not in out and fmt(out, "legos") == out


def test_comments_and_blank_lines_survive_crlf_and_a_bom(tmp_path: Path) -> None:
    f = tmp_path / "r.sleec"
    text = "\ufeff" + DEFS + "\nrule_start\n    // c\n    R1 when A then B\nrule_end\n"
    f.write_bytes(text.replace("\n", "\r\n").encode())
    assert main(["fmt", "--check", str(f)]) == 0  # already formatted: CRLF and BOM kept
    assert main(["fmt", "-i", str(f)]) == 0
    assert f.read_bytes() == text.replace("\n", "\r\n").encode()


# ---------------------------------------------------------------------------- wrapping


def test_a_rule_one_character_over_the_width_wraps_and_one_at_it_does_not() -> None:
    rule = "R1 when A then B unless m then C"
    source = DEFS + f"rule_start\n    {rule}\nrule_end\n"
    at = len("    " + rule)
    assert f"    {rule}\n" in fmt(source, width=at)
    assert "    R1 when A then B\n        unless m then C\n" in fmt(source, width=at - 1)


def test_a_long_rule_is_printed_one_clause_per_line_nested_ones_inline() -> None:
    source = (
        DEFS
        + "rule_start\n    R1 when A and n > 10 then B within 5 minutes otherwise C unless m then "
        + "{C unless n < 3 then B} unless not m and n > 100 then C within 2 seconds\nrule_end\n"
    )
    assert fmt(source) == DEFS + (
        "\nrule_start\n"
        "    R1 when A and n > 10 then B within 5 minutes otherwise C\n"
        "        unless m then {C unless n < 3 then B}\n"
        "        unless not m and n > 100 then C within 2 seconds\n"
        "rule_end\n"
    )


def test_a_long_rule_without_clauses_stays_on_one_line() -> None:
    long = " and ".join(f"n > {i}" for i in range(40))
    out = fmt(DEFS + f"rule_start\n    R1 when A and {long} then B\nrule_end\n")
    assert f"    R1 when A and {long} then B\n" in out


# ---------------------------------------------------------------------------- paper notation

CURTAINS = """\
def_start
    event CurtainOpenRequest
    event OpenCurtains
    event Refuse
    event ExplainWhy
    event WarnUser
    measure userUndressed : boolean
    measure userDistressed : boolean
def_end

rule_start
    // the paper's running example
    R1 when CurtainOpenRequest then OpenCurtains
        unless userUndressed then Refuse and ExplainWhy
        unless userDistressed then WarnUser and OpenCurtains
rule_end
"""


def test_the_papers_rule_prints_as_the_paper_writes_it() -> None:
    out = fmt(CURTAINS, "paper")
    assert out == (
        "// the paper's running example\n"
        "WHEN CurtainOpenRequest THEN OpenCurtains\n"
        "    UNLESS userUndressed IN WHICH CASE (Refuse AND ExplainWhy)\n"
        "    UNLESS userDistressed IN WHICH CASE (WarnUser AND OpenCurtains)\n"
    )
    back = analyse(out)
    assert back.spec is not None and back.spec.dialect is A.Dialect.PAPER
    assert back.spec.rules == analyse(CURTAINS).spec.rules  # type: ignore[union-attr]
    assert fmt(out) == out  # a paper file stays in the paper notation


def test_paper_notation_parenthesises_what_would_be_swallowed() -> None:
    source = DEFS + "rule_start\n    R1 when A then B within 2 seconds otherwise {C} and A\nrule_end\n"
    out = fmt(source, "paper")
    assert "THEN (B WITHIN 2 seconds OTHERWISE C AND A)" not in out
    assert analyse(out).spec.rules == analyse(source).spec.rules  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("rule", "says"),
    [
        ("R1 when A then B else C", "no `else`"),
        ("R1 when A then B eventually", "no `eventually`"),
        ("R1 when A then B within [1 seconds, 2 seconds]", "no interval deadlines"),
        ("R1 when A then B otherwise {C unless m}", "no `unless` inside a response"),
    ],
)
def test_what_the_paper_notation_cannot_say_is_refused_at_its_place(rule: str, says: str) -> None:
    (header,) = refusal(DEFS + f"rule_start\n    {rule}\nrule_end\n", "paper")
    assert header.startswith("t.sleec:9:") and says in header


def test_constants_blocks_and_misread_declarations_are_refused_for_the_paper() -> None:
    text = DEFS.replace("def_end", "    constant K = 3\ndef_end") + (
        "rule_start\n    R1 when A and n > K then B\nrule_end\n"
        "concern_start\n    c1 when A and m then B\nconcern_end\n"
    )
    headers = refusal(text, "paper")
    assert any("t.sleec:7:14:" in h and "no constants: `K`" in h for h in headers)
    assert any("no concern block" in h for h in headers)
    # `n` is only ever used as a truth value: the paper's reader would infer a boolean
    text = DEFS.replace("measure m : boolean", "measure m : numeric") + (
        "rule_start\n    R1 when A and m then B\nrule_end\n"
    )
    (header,) = [h for h in refusal(text, "paper")]
    assert "`measure m : numeric` would be read as `measure m : boolean`" in header


def test_declarations_no_rule_uses_are_kept_in_a_comment() -> None:
    out = fmt(DEFS + "rule_start\n    R1 when A and m then B\nrule_end\n", "paper")
    assert out.startswith("// declared, used by no rule:\n//   event C, measure n : numeric\n")
    assert fmt(out) == out


# ---------------------------------------------------------------------------- other refusals


def test_legos_only_constructs_are_refused_for_tk() -> None:
    text = DEFS.replace("measure m", "measure m") + ("rule_start\n    R1 when A then B else C\nrule_end\n")
    (header,) = refusal(text, "tk")
    assert header.startswith("t.sleec:9:") and "LEGOS-SLEEC only" in header


def test_a_name_legos_would_cut_in_two_is_refused_for_legos() -> None:
    text = DEFS.replace("event C", "event notC") + "rule_start\n    R1 when A then notC\nrule_end\n"
    assert any("notC" in h for h in refusal(text, "legos"))


# ---------------------------------------------------------------------------- properties

_ANCHOR = re.compile(r"\S+")


def _decorate(text: str, rng: random.Random, legos: bool) -> tuple[str, list[str]]:
    """``text`` with comments and blank lines inserted between tokens, and their texts."""
    tokens = SLEEC.lexicon.tokens(text)
    cut = sorted(rng.sample(range(1, len(tokens) + 1), k=min(len(tokens), rng.randint(1, 12))))
    out, last, comments = [], 0, []
    for n, i in enumerate(cut):
        end = tokens[i - 1].start_pos + len(tokens[i - 1].value)
        out.append(text[last:end])
        last = end
        kinds = ["line", "own", "blank"] if legos else ["line", "own", "block", "multi", "blank"]
        kind = rng.choice(kinds)
        c = f"c{n}."
        if kind == "line":
            out.append(f" // {c}\n")
            comments.append(f"// {c}")
        elif kind == "own":
            out.append(f"\n// {c}\n")
            comments.append(f"// {c}")
        elif kind == "block":
            out.append(f" /* {c} */ ")
            comments.append(f"/* {c} */")
        elif kind == "multi":
            out.append(f" /* {c}\n more */ ")
            comments.append(f"/* {c}\n more */")
        else:
            out.append("\n\n")
    out.append(text[last:])
    return "".join(out), comments


@pytest.mark.parametrize("dialect", [A.Dialect.TK, A.Dialect.LEGOS])
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(spec=specifications(), seed=st.integers(0, 2**32), width=st.sampled_from([40, 80, WIDTH]))
def test_fmt_keeps_meaning_and_comments_and_is_idempotent(
    dialect: A.Dialect, spec: A.Specification, seed: int, width: int
) -> None:
    source, comments = _decorate(format_spec(spec, dialect), random.Random(seed), dialect is A.Dialect.LEGOS)
    result = analyse(source, dialect=str(dialect))
    assert result.spec == spec, source
    try:
        once = format_source(source, result.spec, dialect, width)
    except SleecError:
        # only SLEEC-TK refuses, and only what it cannot write; LEGOS-SLEEC can write it all
        assert dialect is A.Dialect.TK and [f for f in legos_features(result.spec) if "braces" not in f[0]]
        dialect = A.Dialect.LEGOS
        once = format_source(source, result.spec, dialect, width)
    again = analyse(once, dialect=str(dialect))
    assert again.spec == spec, once
    # each comment is still a comment of its own (LEGOS-SLEEC gets `/* c */` as `// c`)
    kept = [text for _, text in SLEEC.lexicon.comments(once)]
    if dialect is A.Dialect.TK:
        assert sorted(kept) == sorted(comments), (source, once)
    else:
        assert len(kept) >= len(comments) and all(f" {c[3:].split()[0]}" in once for c in comments)
        for c in comments:
            assert sum(k.startswith(f"// {c[3:].split()[0]}") for k in kept) == 1, (c, source, once)
    assert format_source(once, again.spec, dialect, width) == once, (source, once)


@settings(max_examples=EXAMPLES, deadline=None)
@given(seed=st.integers(0, 2**32))
def test_fmt_of_the_paper_notation_is_idempotent(seed: int) -> None:
    rng = random.Random(seed)
    source = "// a rule set\n" + paper_text(rng)
    result = analyse(source)
    if result.spec is None or not result.ok:
        return
    once = format_source(source, result.spec)
    again = analyse(once)
    assert again.spec is not None and again.spec.rules == result.spec.rules, once
    assert once.count("// a rule set") == 1
    assert format_source(once, again.spec) == once


# ---------------------------------------------------------------------------- the command


def _file(tmp_path: Path, text: str, name: str = "r.sleec") -> Path:
    f = tmp_path / name
    f.write_text(text, encoding="utf-8")
    return f


UGLY = DEFS + "rule_start\n  R1   when A then B // keep me\nrule_end\n"
PRETTY = DEFS + "\nrule_start\n    R1 when A then B // keep me\nrule_end\n"


def test_check_shows_a_diff_and_fails_then_in_place_fixes_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _file(tmp_path, UGLY)
    f.chmod(0o640)
    assert main(["fmt", "--check", str(f)]) == 1
    out, err = capsys.readouterr()
    assert f"--- {f}\n+++ {f} (formatted)\n" in out
    assert "-  R1   when A then B // keep me\n+    R1 when A then B // keep me\n" in out
    assert f"{f}: would be reformatted" in err
    assert f.read_text() == UGLY  # --check changes nothing
    assert main(["fmt", "--in-place", str(f)]) == 0
    assert f.read_text() == PRETTY and stat.S_IMODE(f.stat().st_mode) == 0o640
    assert f"{f}: reformatted" in capsys.readouterr().err
    assert main(["fmt", "--check", str(f)]) == 0
    assert capsys.readouterr().out == ""
    assert [p.name for p in tmp_path.iterdir()] == ["r.sleec"]  # no temporary file left


def test_in_place_leaves_a_formatted_file_untouched(tmp_path: Path) -> None:
    f = _file(tmp_path, PRETTY)
    os.utime(f, (1, 1))
    assert main(["fmt", "-i", str(f)]) == 0
    assert f.stat().st_mtime == 1


def test_many_files_need_check_or_in_place(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = _file(tmp_path, PRETTY, "a.sleec"), _file(tmp_path, UGLY, "b.sleec")
    assert main(["fmt", str(a), str(b)]) == 2
    assert "several files need --check or --in-place" in capsys.readouterr().err
    assert main(["fmt", "--check", str(a), str(b)]) == 1  # one is not formatted
    assert main(["fmt", "--in-place", str(a), str(b)]) == 0
    assert b.read_text() == PRETTY


def test_a_broken_file_is_reported_and_never_rewritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    broken = DEFS + "rule_start\n    R1 when A then Nope\nrule_end\n"
    f = _file(tmp_path, broken)
    assert main(["fmt", "-i", str(f)]) == 1
    assert f"{f}:9:20: error" in capsys.readouterr().err
    assert f.read_text() == broken


def test_a_refused_conversion_writes_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = DEFS + "rule_start\n    R1 when A then B else C\nrule_end\n"
    f = _file(tmp_path, text)
    assert main(["fmt", "-i", "--dialect", "paper", str(f)]) == 1
    assert "no `else`" in capsys.readouterr().err and f.read_text() == text


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--check", "--in-place"], "not allowed with argument"),
        (["--width", "5"], "too narrow"),
        (["--width", "wide"], "not a number"),
        (["--dialect", "papr"], "did you mean 'paper'"),
    ],
)
def test_option_mistakes_are_usage_errors(
    argv: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["fmt", *argv, str(_file(tmp_path, PRETTY))]) == 2
    assert says in capsys.readouterr().err


def test_a_commented_out_rule_block_does_not_make_a_paper_file_a_dsl_file() -> None:
    text = (
        "// old version:\n// rule_start\n//   R1 when A then B\n// rule_end\nWHEN A THEN B\n/* def_start */\n"
    )
    result = analyse(text)
    assert result.ok and result.spec is not None and result.spec.dialect is A.Dialect.PAPER
    assert (
        fmt(text)
        == "// old version:\n// rule_start\n//   R1 when A then B\n// rule_end\nWHEN A THEN B\n/* def_start */\n"
    )


def test_in_place_through_a_symbolic_link_rewrites_its_target(tmp_path: Path) -> None:
    target = _file(tmp_path, UGLY, "real.sleec")
    link = tmp_path / "link.sleec"
    link.symlink_to(target)
    assert main(["fmt", "-i", str(link)]) == 0
    assert link.is_symlink() and target.read_text() == PRETTY


def test_every_example_that_checks_is_formatted(capsys: pytest.CaptureFixture[str]) -> None:
    """Our own rule files model what `cosleec fmt` prints (as `ruff format --check` would);
    the paper-notation examples (``.txt``) stay as the paper prints them, unindented."""
    root = Path(__file__).resolve().parents[3]
    files = [
        str(p)
        for p in sorted([*root.glob("examples/**/*.sleec"), *root.glob("src/**/*.sleec")])
        if analyse(p.read_text(encoding="utf-8"), str(p)).ok
    ]
    assert len(files) >= 10
    assert main(["fmt", "--check", *files]) == 0, capsys.readouterr().out


# ---------------------------------------------------------------------------- found by a hostile tester

AB = "def_start\n    event A\n    event B\ndef_end\n\n"


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        # a `//` ends its line: what trailed after it goes on a line of its own, after it
        (
            AB + "rule_start\n    R1 when A // x\n    then B /* y\n    z */\nrule_end\n",
            "    R1 when A then B // x\n    /* y\n    z */\nrule_end\n",
        ),
        (
            "def_start\n    event A\n    event B\n    measure s : scale(lo, // low\n hi) /* high */\ndef_end\n"
            "\nrule_start\n    R1 when A and s = hi then B\nrule_end\n",
            "    measure s : scale(lo, hi) // low\n    /* high */\ndef_end\n",
        ),
        # nor does code or another comment follow a multi-line one on its last line
        (
            AB + "rule_start\n    R1 /* one\n    two */ when A then B /* three */\nrule_end\n",
            "    R1 when A then B /* one\n    two */\n    /* three */\nrule_end\n",
        ),
        # in a chain, each comment stays with its pair
        (
            AB + "rule_start\n    R1 when A then B\n    R2 when B then A\n    R3 when A then A\nrule_end\n\n"
            "priority_start\n    R1 > R2 // safety first\n       > R3 // then comfort\npriority_end\n",
            "    R1 > R2 // safety first\n    R2 > R3 // then comfort\n",
        ),
        # an empty block keeps its comments, and so itself
        (
            AB
            + "rule_start\n    R1 when A then B\nrule_end\n\npriority_start\n    // TODO: R1 > R2\npriority_end\n",
            "\npriority_start\n    // TODO: R1 > R2\npriority_end\n",
        ),
        # the keyword before a name belongs to it
        (
            "def_start\n    event /* first */ A\n    event B\ndef_end\n\nrule_start\n    R1 when A then B\nrule_end\n",
            "    event A /* first */\n",
        ),
        # an unnamed paper rule starts at its WHEN
        (
            "WHEN A THEN B\n    UNLESS m\n// about the second\nWHEN\n    C THEN D\n",
            "UNLESS m\n// about the second\nWHEN C",
        ),
        (
            "WHEN A THEN B // first\nWHEN /* second */ C THEN D\n",
            "WHEN A THEN B // first\nWHEN C THEN D /* second */\n",
        ),
    ],
)
def test_comments_stay_comments_of_their_own_and_in_their_place(source: str, expected: str) -> None:
    out = fmt(source)
    assert expected in out, out
    assert analyse(out).ok and fmt(out) == out
    kept = [c for _, c in SLEEC.lexicon.comments(out)]
    assert len(kept) == len(SLEEC.lexicon.comments(source))


@pytest.mark.parametrize(
    ("source", "dialect", "says"),
    [
        ("WHEN A AND m THEN NOT B\n", "tk", "1:23: error: an untimed `not E` is LEGOS-SLEEC only"),
        ("WHEN A AND n * 2 > -1 THEN B\n", "tk", "1:12: error: arithmetic is LEGOS-SLEEC only"),
        (
            "def_start\n    event ^when\n    event B\ndef_end\n\nrule_start\n    R1 when ^when then B\nrule_end\n",
            "legos",
            "2:11: error: `when` is a keyword: LEGOS-SLEEC has no way to use it as a name",
        ),
        (
            "def_start\n    event A\n    event B\n    measure s : scale(low, high)\n    measure t : scale(low, high)\n"
            "def_end\n\nrule_start\n    R1 when A and s = low then B\nrule_end\n",
            "legos",
            "9:23: error: LEGOS-SLEEC rejects this reference to `low`",
        ),
        (
            AB.replace("event B", "event ^rule_start")
            + "rule_start\n    R1 when A then ^rule_start\nrule_end\n",
            "paper",
            "3:11: error: `rule_start` would make the file read as a DSL file",
        ),
    ],
)
def test_a_conversion_the_target_tool_would_not_read_is_refused_at_its_place(
    source: str, dialect: str, says: str
) -> None:
    assert any(says in h for h in refusal(source, dialect))


def test_conversions_that_only_change_spelling_go_through() -> None:
    legos = (
        "def_start\n    event A\n    event B\n    measure m : boolean\n    constant K = 3\n    constant L = -> K\n"
        "def_end\n\nrule_start\n    R1 when A and {m} then B within L seconds\n    R2 when B then A\nrule_end\n\n"
        "priority_start\n    R1 > R2\npriority_end\n"
    )
    out = fmt(legos, "tk")
    assert "R1 when A and m then B within L seconds" in out and "constant L = K" in out
    assert analyse(out, dialect="auto").spec.dialect is A.Dialect.TK  # type: ignore[union-attr]


def test_long_conditions_convert_without_a_false_too_deep() -> None:
    cond = " and ".join(f"(m or n > {i})" for i in range(1500))
    source = DEFS + f"rule_start\n    R1 when A and {cond} then B\nrule_end\n"
    assert "WHEN A AND m OR n > 0 AND (m OR n > 1)" in fmt(source, "paper")
    assert "({m} or ({n} > 0))" in fmt(source, "legos")


def test_paper_units_are_keywords_in_capitals() -> None:
    assert fmt("WHEN A THEN B WITHIN 30 seconds\n") == "WHEN A THEN B WITHIN 30 SECONDS\n"


def test_inferred_declarations_come_after_the_files_header(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _file(tmp_path, "// header\nrule_start\n    R1 when A then B\nrule_end\n")
    assert main(["fmt", "--infer-defs", str(f)]) == 0
    assert capsys.readouterr().out.startswith("// header\n\ndef_start\n    event A\n")


def test_a_mixed_file_is_what_dialect_conversion_is_for(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _file(tmp_path, DEFS + "rule_start\n    R1 when A then B unless {m} /* why */\nrule_end\n")
    assert main(["fmt", str(f)]) == 1  # mixed: an error, as `check` says
    assert "`cosleec fmt --dialect legos` converts it" in capsys.readouterr().err
    assert main(["fmt", "--dialect", "legos", str(f)]) == 0
    assert "R1 when A then B unless {m} // why\n" in capsys.readouterr().out


def test_in_place_refuses_a_read_only_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Even where the directory would let the file be replaced (a world-writable one): a
    read-only file is not rewritten. As root every file is writable, so the command runs as
    `nobody` (setpriv) when the tests run as root -- or, where nobody cannot reach this
    checkout, in-process with the permission check answering "not writable"."""
    folder = Path(tempfile.mkdtemp(prefix="cosleec-ro-"))
    try:
        folder.chmod(0o777)
        f = folder / "r.sleec"
        f.write_text(UGLY, encoding="utf-8")
        f.chmod(0o444)
        command = [str(Path(sys.executable).with_name("cosleec")), "fmt", "-i", str(f)]
        if os.geteuid() == 0:
            nobody = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"]
            reachable = shutil.which("setpriv") is not None and (
                subprocess.run([*nobody, command[0], "--version"], capture_output=True, timeout=60).returncode
                == 0
            )
            if not reachable:  # a checkout nobody may read (a private temporary clone)
                monkeypatch.setattr(os, "access", lambda path, mode: False)
                assert main(["fmt", "-i", str(f)]) == 1
                assert "read-only" in capsys.readouterr().err and f.read_text(encoding="utf-8") == UGLY
                return
            command = [*nobody, *command]
        done = subprocess.run(command, capture_output=True, text=True, timeout=60, cwd=folder)
        assert done.returncode == 1, done.stderr
        assert "read-only" in done.stderr and "Traceback" not in done.stderr
        assert f.read_text(encoding="utf-8") == UGLY
    finally:
        shutil.rmtree(folder)


def test_check_marks_a_missing_final_newline_as_diff_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = _file(tmp_path, PRETTY.rstrip("\n"))
    assert main(["fmt", "--check", str(f)]) == 1
    assert "-rule_end\n\\ No newline at end of file\n+rule_end\n" in capsys.readouterr().out
