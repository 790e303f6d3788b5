"""LEGOS-SLEEC as LEGOS-SLEEC reads it: ``legos_compat`` (the LEGOS case studies as written) and
strict ``--dialect legos`` held to LEGOS's real grammar (sleec-language.md §4.4, §11 items 9-11, 18, 19)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cosleec.lang import Options, analyse, format_spec, legos_misreads, parse
from cosleec.lang import ast as A
from cosleec.lang.checker import check
from cosleec.lang.compat import fresh_name
from cosleec.lang.diagnostics import DiagnosticSink

# ---------------------------------------------------------------- the nine case studies

CASE_STUDIES = ("ALMI", "ASPEN", "Autocar", "BSN", "CSI", "DAISY", "gdpr", "dressingAssist", "safescade")
PREFIX = "NickF0211__LEGOS-SLEEC__"

# (code, line, col) of every warning legos_compat gives for a defect LEGOS lets through
DEFECTS: dict[str, list[tuple[str, int, int]]] = {
    "ASPEN__aspen.sleec": [
        ("scale-literal", 78, 77),
        ("scale-literal", 99, 48),
        ("scale-literal", 99, 67),
        ("scale-literal", 109, 45),
        ("scale-literal", 111, 42),
    ],
    "ASPEN__aspen-corrected.sleec": [
        ("scale-literal", 71, 21),
        ("scale-literal", 71, 42),
        ("scale-literal", 92, 77),
        ("scale-literal", 132, 60),
        ("scale-literal", 141, 45),
        ("scale-literal", 143, 42),
    ],
    "BSN__BSN.sleec": [
        ("scale-literal", 82, 56),
        ("scale-literal", 82, 87),
        ("scale-literal", 83, 32),
        ("scale-literal", 84, 54),
        ("scale-literal", 120, 57),
        ("type", 153, 23),
        ("scale-literal", 188, 70),
        ("scale-literal", 265, 44),
    ],
    "BSN__BSN-corrected.sleec": [
        ("scale-literal", 89, 56),
        ("scale-literal", 89, 87),
        ("scale-literal", 90, 32),
        ("scale-literal", 91, 61),
        ("scale-literal", 127, 57),
        ("type", 160, 23),
        ("scale-literal", 206, 91),
        ("scale-literal", 283, 44),
    ],
    "dressingAssist__DRESSASSIST.sleec": [("duplicate-rule", 170, 1)],
    "dressingAssist__DRESSASSIST-corrected.sleec": [("duplicate-rule", 183, 1)],
    "gdpr__DPA.sleec": [("duplicate-name", 200, 2)],
    "gdpr__DPA-corrected.sleec": [("duplicate-name", 227, 2)],
    "safescade__safescade.sleec": [
        ("scale-literal", 59, 82),
        ("scale-literal", 120, 81),
        ("scale-literal", 129, 79),
    ],
    "safescade__safescade-corrected.sleec": [
        ("scale-literal", 84, 85),
        ("duplicate-rule", 123, 6),
        ("scale-literal", 211, 79),
    ],
}
COMPAT_CODES = {"scale-literal", "type", "duplicate-rule", "duplicate-name"}


@pytest.fixture
def case_studies(corpus: list[Path]) -> dict[str, Path]:
    """The 18 files of N-Check's nine case studies, by name less the repository prefix."""
    found = {
        p.name.removeprefix(PREFIX): p
        for p in corpus
        if p.name.startswith(PREFIX) and p.name.removeprefix(PREFIX).split("__")[0] in CASE_STUDIES
    }
    assert len(found) == 18, sorted(found)
    assert set(DEFECTS) <= set(found)
    return found


def read(path: Path, **kw: object) -> tuple[str, object]:
    return path.read_text(encoding="utf-8"), kw


def test_all_case_studies_are_ok_under_legos_compat_and_carry_a_clean_spec(
    case_studies: dict[str, Path],
) -> None:
    for name, path in case_studies.items():
        text = path.read_text(encoding="utf-8")
        for dialect in ("auto", "legos"):
            result = analyse(text, name, dialect=dialect, legos_compat=True)
            assert result.ok and result.spec is not None, (name, dialect, result.render())
        spec = result.spec
        assert spec is not None
        # the reading is in the spec: checked without the option, it has no error left
        sink = DiagnosticSink(name)
        check(spec, sink)
        assert not [d for d in sink.items if d.is_error], (name, [d.message for d in sink.items])
        # and it prints and reads back as itself, in LEGOS syntax, without the option
        again = analyse(format_spec(spec, A.Dialect.LEGOS), name, dialect="legos")
        assert again.ok and again.spec == spec, (name, again.render())


def test_each_defect_is_a_warning_at_its_place_and_an_error_without_the_option(
    case_studies: dict[str, Path],
) -> None:
    for name, path in case_studies.items():
        text = path.read_text(encoding="utf-8")
        result = analyse(text, name, legos_compat=True)
        got = [
            (d.code, d.span.line, d.span.col)
            for d in result.diagnostics
            if d.code in COMPAT_CODES and d.severity.value == "warning"
        ]
        assert got == DEFECTS.get(name, []), name
        plain = analyse(text, name)
        errors = [(d.code, d.span.line, d.span.col) for d in plain.errors]
        assert errors == DEFECTS.get(name, []), name
        assert plain.ok is (name not in DEFECTS)


def rule(spec: A.Specification, name: str) -> A.Rule:
    return spec.rule(name)


def conjuncts(e: A.Expr | None) -> list[A.Expr]:
    """The leaves of a tree of and/or, left to right."""
    if isinstance(e, A.BinOp) and e.op in A.BOOL_OPS:
        return [*conjuncts(e.left), *conjuncts(e.right)]
    return [] if e is None else [e]


def test_cross_scale_literals_become_the_literal_at_the_same_position(case_studies: dict[str, Path]) -> None:
    spec = parse(case_studies["ASPEN__aspen.sleec"].read_text(encoding="utf-8"), legos_compat=True)
    # R13: ({battery} = low) or ({store} = low): `low` is the first of carbonFootprint's scale
    battery, store, _damages = conjuncts(rule(spec, "R13").trigger.condition)
    assert battery == A.Compare("=", A.Name("battery"), A.Name("low2"))
    assert store == A.Compare("=", A.Name("store"), A.Name("low3"))
    # R8_1: ({benefits} < medium): `medium` is the second, so `medium1`, not `low1`
    _carbon, benefits = conjuncts(rule(spec, "R8_1").trigger.condition)
    assert benefits == A.Compare("<", A.Name("benefits"), A.Name("medium1"))
    # the literal node keeps its place in the source
    assert isinstance(benefits, A.Compare) and benefits.right.span[:2] == (78, 77)


def test_bsn_reads_as_legos_reads_it(case_studies: dict[str, Path]) -> None:
    result = analyse(case_studies["BSN__BSN.sleec"].read_text(encoding="utf-8"), legos_compat=True)
    spec = result.spec
    assert result.ok and spec is not None
    low, moderate, high = conjuncts(rule(spec, "Rule1").trigger.condition)
    assert [c.right for c in (low, moderate, high)] == [  # type: ignore[union-attr]
        A.Name("p_low"),
        A.Name("p_moderate"),
        A.Name("p_high"),
    ]
    assert rule(spec, "Rule7_1").trigger.condition == A.Compare(
        ">=", A.Name("riskLevel"), A.Name("r_moderate")
    )
    # `{riskLevel} > autonomyConcern`, 20 against positions 0..2: always false in LEGOS
    (clause,) = rule(spec, "Rule13").response.defeaters
    assert clause.condition == A.BoolLit(False)
    assert clause.condition.span[:2] == (153, 23)
    # purpose P6 writes the scale measure bare (LEGOS syntax, no dialect mix) and another
    # scale's literal
    p6 = next(p for p in spec.purposes if p.name == "P6")
    assert p6.trigger.condition == A.Compare(">=", A.Name("riskLevel"), A.Name("r_moderate"))
    assert not [d for d in result.diagnostics if d.code == "mixed-dialect"]
    warning = next(d for d in result.diagnostics if d.span[:2] == (153, 23))
    assert "always false" in warning.message and "autonomyConcern" in warning.message
    assert warning.hint is not None and "r_low, r_moderate, r_high" in warning.hint


def test_duplicate_rules_and_purposes_are_kept_under_new_names(case_studies: dict[str, Path]) -> None:
    spec = parse(
        case_studies["dressingAssist__DRESSASSIST.sleec"].read_text(encoding="utf-8"), legos_compat=True
    )
    names = [r.name for r in spec.rules]
    assert len(names) == len(set(names))
    i = names.index("Rule20_1")
    assert names[i : i + 3] == ["Rule20_1", "Rule20_1__2", "Rule20_2"]
    assert spec.rules[i + 1].response.items[0].occurrence.event == "DiscardInformation"
    spec = parse(case_studies["gdpr__DPA.sleec"].read_text(encoding="utf-8"), legos_compat=True)
    p6, p6b = (p for p in spec.purposes if p.name.startswith("P6"))
    assert (p6.name, p6b.name) == ("P6", "P6__2") and p6b.trigger.event == "PassSecurity"
    result = analyse(case_studies["safescade__safescade-corrected.sleec"].read_text(encoding="utf-8"),
                     legos_compat=True)  # fmt: skip
    warning = next(d for d in result.diagnostics if d.code == "duplicate-rule")
    assert "`R7_1`" in warning.message and "`R7_1__2`" in warning.message
    assert warning.related and warning.related[0][1][:2] == (122, 6)


# ---------------------------------------------------------------- legos_compat on small files

DEFS = """def_start
  event E event F
  measure x : numeric measure a : boolean
  measure m : scale(m0, m1, m2)
  measure s : scale(s0, s1, s2, s3, s4)
  constant K = 1 constant BIG = 7 constant NEG = -1
def_end
"""


def cond(text: str, **kw: object) -> tuple[A.Expr | None, list[tuple[str, str, int, int]]]:
    """The trigger condition of ``R when E and <text> then F`` as legos_compat reads it, and
    its diagnostics (severity, code, line, col)."""
    result = analyse(DEFS + f"rule_start\nR when E and {text} then F\nrule_end\n", legos_compat=True, **kw)  # type: ignore[arg-type]
    diags = [(d.severity.value, d.code, d.span.line, d.span.col) for d in result.diagnostics]
    if not result.ok or result.spec is None:
        return None, diags
    return result.spec.rules[0].trigger.condition, diags


M, S = A.Name("m"), A.Name("s")


@pytest.mark.parametrize(
    ("text", "reading"),
    [
        ("({m} = s0)", A.Compare("=", M, A.Name("m0"))),
        ("({m} = s1)", A.Compare("=", M, A.Name("m1"))),  # the position, not the first literal
        ("({m} >= s2)", A.Compare(">=", M, A.Name("m2"))),
        ("(s1 < {m})", A.Compare("<", A.Name("m1"), M)),  # the literal on the left
        # beyond m's three positions: one value for every value of m
        ("({m} = s3)", A.BoolLit(False)),
        ("({m} <> s3)", A.BoolLit(True)),
        ("({m} < s4)", A.BoolLit(True)),
        ("({m} >= s3)", A.BoolLit(False)),
        ("(s4 > {m})", A.BoolLit(True)),
        # a scale against a number: the literal at that position, or the constant value
        ("({m} > 1)", A.Compare(">", M, A.Name("m1"))),
        ("({m} = K)", A.Compare("=", M, A.Name("m1"))),
        ("(2 <= {m})", A.Compare("<=", A.Name("m2"), M)),
        ("({m} > BIG)", A.BoolLit(False)),
        ("({m} < BIG)", A.BoolLit(True)),
        ("({m} > NEG)", A.BoolLit(True)),
        ("({m} = -1)", A.BoolLit(False)),
        # a literal against a number: its position
        ("({x} > m2)", A.Compare(">", A.Name("x"), A.IntLit(2))),
        ("(s1 = {x})", A.Compare("=", A.IntLit(1), A.Name("x"))),
    ],
)
def test_positions_are_read_as_legos_compares_them(text: str, reading: A.Expr) -> None:
    got, diags = cond(text)
    assert got == reading, diags
    (warning,) = diags
    assert warning[0] == "warning" and warning[1] in ("scale-literal", "type") and warning[2] == 9
    # and without the option it is an error, as before
    plain = analyse(DEFS + f"rule_start\nR when E and {text} then F\nrule_end\n")
    assert [d.code for d in plain.errors] == [warning[1]]


def test_the_reading_replaces_only_the_node_in_a_larger_condition() -> None:
    text = "({a} and (({m} = s1) or ({m} > BIG)))"
    got, diags = cond(text)
    assert got == A.BinOp(
        "and", A.Name("a"), A.BinOp("or", A.Compare("=", M, A.Name("m1")), A.BoolLit(False))
    )
    # the literal is marked where it is; a comparison read as a truth value, at its operator
    at = len("R when E and ") + 1
    assert [(c, col) for _, c, _, col in diags] == [
        ("scale-literal", at + text.index("s1")),
        ("type", at + text.index(">")),
    ]


def test_the_reading_reaches_every_place_a_condition_can_be() -> None:
    text = DEFS + (
        "rule_start\nR when E then F within 3 seconds otherwise {F unless ({m} = s1)} "
        "unless ({m} = s2) then {F unless ({m} > 1)}\nrule_end\n"
        "concern_start\nc1 when E and ({m} = s1) then F meanwhile (exists F and ({m} = s1))\nconcern_end\n"
        "relation_start\nmeasure imply ({m} = s1) {a}\nforbid E ({m} = s1)\n"
        "when E and ({m} = s1) then ({m} = s1) until F and ({m} = s1)\nrelation_end\n"
    )
    result = analyse(text, legos_compat=True)
    assert result.ok and result.spec is not None, result.render()
    printed = format_spec(result.spec, A.Dialect.LEGOS).split("def_end")[1]
    assert " s1" not in printed and " s2" not in printed
    assert printed.count("= m1") == 8 and "= m2" in printed and "> m1" in printed
    assert (
        sum(d.severity.value == "warning" for d in result.diagnostics if d.code != "untimed-fallback") == 10
    )


@pytest.mark.parametrize(
    ("defs", "text", "code"),
    [
        # `lo` is first in one scale and second in another: LEGOS's own table asserts
        ("measure p : scale(lo, hi) measure q : scale(hi, lo)", "({m} = lo)", "scale-literal"),
        ("", "({m} > {x})", "type"),  # a scale against a number that is not constant
        ("", "({m} > {s})", "type"),  # two scales
        ("", "(m1 = s1)", "type"),  # two literals
    ],
)
def test_what_legos_compat_cannot_read_stays_an_error(defs: str, text: str, code: str) -> None:
    result = analyse(
        DEFS.replace("def_end", defs + "\ndef_end") + f"rule_start\nR when E and {text} then F\nrule_end\n",
        legos_compat=True,
    )
    assert [d.code for d in result.errors] == [code]


def test_fresh_names_never_clash() -> None:
    assert fresh_name("R", 2, {"R"}) == "R__2"
    assert fresh_name("R", 2, {"R", "R__2", "R__3"}) == "R__4"
    text = (
        DEFS + "rule_start\nR when E then F\nR when E then F\nR__2 when E then F\nR when E then F\nrule_end\n"
    )
    result = analyse(text, legos_compat=True)
    assert result.ok and result.spec is not None
    assert [r.name for r in result.spec.rules] == ["R", "R__3", "R__2", "R__4"]
    assert [(d.code, d.span.line) for d in result.diagnostics] == [
        ("duplicate-rule", 10),
        ("duplicate-rule", 12),
    ]
    concerns = "concern_start\nc when E then F\nc when F then E\nconcern_end\n"
    result = analyse(DEFS + "rule_start\nR when E then F\nrule_end\n" + concerns, legos_compat=True)
    assert result.ok and result.spec is not None
    assert [c.name for c in result.spec.concerns] == ["c", "c__2"]
    assert [d.code for d in analyse(DEFS + "rule_start\nR when E then F\nrule_end\n" + concerns).errors] == [
        "duplicate-name"
    ]


def test_the_option_is_the_same_through_options() -> None:
    text = DEFS + "rule_start\nR when E and ({m} = s1) then F\nR when E then F\nrule_end\n"
    a = analyse(text, legos_compat=True)
    b = analyse(text, options=Options(legos_compat=True))
    assert a.spec == b.spec and [d.message for d in a.diagnostics] == [d.message for d in b.diagnostics]
    assert not analyse(text).ok


# ---------------------------------------------------------------- strict legos mode = LEGOS's grammar

LDEFS = """def_start
  event E event F
  measure a : boolean measure b : boolean
  measure x : numeric measure lvl : scale(low, mid, high)
  constant K = 3
def_end
"""


def legos(body: str, defs: str = LDEFS, **kw: object) -> list[tuple[str, int, int, str]]:
    """(code, line, col, message) of the errors of ``body`` in strict legos mode."""
    result = analyse(defs + body, dialect="legos", **kw)  # type: ignore[arg-type]
    return [(d.code, d.span.line, d.span.col, d.message) for d in result.errors]


def rules(text: str) -> str:
    return f"rule_start\n{text}\nrule_end\n"


@pytest.mark.parametrize(
    "body",
    [
        rules("R when E and (x > 3) then F"),  # bare numeric measure in a comparison
        rules("R when E and (lvl >= mid) then F"),  # bare scale measure (BSN's P6)
        rules("R when E and ((x + 1) > K) then F within x seconds"),  # arithmetic, a deadline
        rules("R when E and ({x} > +3) then F"),  # a signed positive number
        rules("R when E and ({x} > -3) then F"),
        rules("R when E then F") + "relation_start\n when E then {a} until F\nrelation_end\n",
    ],
)
def test_strict_legos_accepts_what_legos_accepts(body: str) -> None:
    assert legos(body) == []


def test_plus_three_is_three_and_tk_rejects_the_sign() -> None:
    (r,) = parse(LDEFS + rules("R when E and ({x} > +3) then F")).rules
    assert r.trigger.condition == A.Compare(">", A.Name("x"), A.IntLit(3))
    assert parse(LDEFS.replace("K = 3", "K = +3") + rules("R when E then F")).constants[0].value == 3
    errs = analyse(LDEFS + rules("R when E and x > +3 then F"), dialect="tk").errors
    assert [(e.code, e.message) for e in errs] == [
        ("dialect", "a signed number is not TK syntax (SLEEC-TK rejects it)")
    ]


@pytest.mark.parametrize(
    ("body", "line", "col", "words"),
    [
        (rules("R when E and a then F"), 8, 14, "bare measure `a` as a condition"),
        (rules("R when E and ({a} = true) then F"), 8, 21, "`true` as an operand of `=`"),
        (rules("R when E and (false <> {a}) then F"), 8, 15, "`false` as an operand of `<>`"),
        (rules("R when E and (({x} > 3)) then F"), 8, 20, "`>` in 2 pairs of parentheses"),
        (rules("R when E then F unless ((not {a}))"), 8, 26, "`not` in 2 pairs of parentheses"),
        (rules("R when E and (true) then F"), 8, 15, "`true` in parentheses"),
        (rules("R when E and ({x} > (3)) then F"), 8, 22, "`3` in parentheses"),
        (rules("R when E and ({x} > - 3) then F"), 8, 21, "a sign apart from its number (`- 3`)"),
        ("def_start\ndef_end\n" + rules("R when E then F"), 1, 1, "an empty def block"),
        (rules("R when E then F") + "concern_start\nconcern_end\n", 10, 1, "an empty concern block"),
        (rules("R when E then F") + "purpose_start\npurpose_end\n", 10, 1, "an empty purpose block"),
        (rules("R when E then F") + "relation_start\nrelation_end\n", 10, 1, "an empty relation block"),
        (
            rules("R when E then F") + "relation_start\n when E then {a} for 3 seconds\nrelation_end\n",
            11,
            7,
            "never reads a `for` relation",
        ),
        (
            rules("R when E then F") + "relation_start\n isContradictoryWith E F\nrelation_end\n",
            11,
            2,
            "`isContradictoryWith` is an extension",
        ),
        (rules("R when E then notF"), 8, 15, "reads it as `not F`"),
        (rules("R1 when E then F\neventuallyR2 when E then F"), 9, 1, "reads it as `eventually R2`"),
    ],
)
def test_strict_legos_rejects_what_legos_rejects(body: str, line: int, col: int, words: str) -> None:
    defs = LDEFS.replace("event F", "event F event notF") if "notF" in body else LDEFS
    if body.startswith("def_start"):
        defs = ""
    errs = [e for e in legos(body, defs) if e[0] == "dialect"]
    assert [(e[1], e[2]) for e in errs] == [(line, col)], errs
    assert words in errs[0][3]
    if "def_start\ndef_end" not in body:  # the same file is fine outside strict legos mode
        assert not [d for d in analyse(defs + body).errors if d.code == "dialect"]


def test_strict_legos_rejects_a_sign_apart_in_a_constant_and_a_fork_fluent() -> None:
    errs = legos(rules("R when E then F"), LDEFS.replace("K = 3", "K = - 3"))
    assert [(e[1], e[2]) for e in errs] == [(5, 12)] and "apart" in errs[0][3]
    errs = legos(rules("R when E then F"), LDEFS.replace("def_end", "fluent G <{E}, {F}>\ndef_end"))
    assert [(e[0], e[1], e[2]) for e in errs] == [("dialect", 6, 8)] and "CPeluti" in errs[0][3]


@pytest.mark.parametrize(
    ("defs", "body", "where"),
    [
        # an event declared twice, then used: textX "name F is not unique"
        (LDEFS.replace("event F", "event F event F"), rules("R when E then F"), (8, 15)),
        # a boolean measure declared twice, then used as a condition
        (LDEFS.replace("measure b : boolean", "measure b : boolean measure b : boolean"), rules("R when E and {b} then F"), (8, 15)),
        # a rule called like the measure a comparison names: looked up among everything
        (LDEFS, rules("x when E and ({x} > 3) then F"), (8, 16)),
        # a literal that two scales share
        (LDEFS.replace("constant K = 3", "measure q : scale(mid, top)"), rules("R when E and ({lvl} = mid) then F"), (8, 23)),
    ],
)  # fmt: skip
def test_strict_legos_rejects_a_reference_textx_finds_twice(
    defs: str, body: str, where: tuple[int, int]
) -> None:
    errs = [e for e in legos(body, defs) if e[0] == "dialect"]
    assert [(e[1], e[2]) for e in errs] == [where]
    assert "is not unique" in errs[0][3]


def test_an_unreferenced_duplicate_is_only_the_usual_warning() -> None:
    result = analyse(
        LDEFS.replace("event F", "event F event G event G") + rules("R when E then F"), dialect="legos"
    )
    assert result.ok and [d.code for d in result.diagnostics] == ["redeclared"]
    # a rule called like a boolean measure used as a condition: LEGOS looks `{a}` up among
    # the boolean measures only
    assert legos(rules("a when E and {a} then F")) == []


def test_a_relation_without_until_has_a_precise_message() -> None:
    text = LDEFS + rules("R when E then F") + "relation_start\n when E then {a}\nrelation_end\n"
    result = analyse(text)
    assert [(d.code, d.span.line, d.span.col) for d in result.errors] == [("relation-end", 12, 1)]
    assert "needs `until F`" in result.errors[0].message
    assert result.errors[0].hint is not None and "unsupported yet" in result.errors[0].hint


def test_legos_misreads_are_found_where_legos_tries_the_keyword() -> None:
    text = (
        LDEFS.replace("event F", "event F event notF event Serve event nothing")
        + rules("eventuallyA when E then notF\nR2 when E then not nothing\nthenB when E then F")
        + "concern_start\nc1 exists E\nwhileC exists E\nconcern_end\n"
    )
    spec = parse(text)
    found = [(span.line, span.col, message.split(":")[0]) for message, span in legos_misreads(spec)]
    assert found == [
        (8, 25, "the response event `notF` begins with the keyword `not`"),
        (10, 1, "the rule name `thenB` begins with the keyword `then`"),
        (14, 1, "the concern or purpose name `whileC` begins with the keyword `while`"),
    ]
