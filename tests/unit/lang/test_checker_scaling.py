"""The checker's work and output grow linearly with a rule's ``unless`` clauses.

Generated rules can have thousands of clauses. The unreachable-clause lint used to compare
every clause with every other (20,000 ``unless false``: minutes, then out of memory), and
every clause's warning quoted the whole one-line rule (gigabytes of output). These tests
count work instead of timing it: the number of Python calls :func:`check` makes, for 1,000
and 4,000 clauses, must grow 4-fold, not 16-fold.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from types import FrameType
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cosleec.lang import (
    Diagnostic,
    DiagnosticSink,
    HedgeSemantics,
    Options,
    Severity,
    analyse,
    analyse_file,
    check,
)
from cosleec.lang import ast as A
from cosleec.lang import diagnostics as D
from cosleec.lang.unreachable import MAX_LINT_CLAUSES, _implication

from .strategies import condition

HEAD = "def_start event A event B measure m : numeric measure b : boolean measure c : boolean def_end\n"

# condition of clause i (0-based), for rules whose clauses are all alike in one way
CLAUSES: dict[str, Callable[[int], str]] = {
    "distinct": lambda i: f"m > {i}",
    "identical": lambda i: "m > 1",
    "boolean": lambda i: "b",
    "implying": lambda i: "b and c" if i % 2 else "b",  # every other clause implies the next
    "false": lambda i: "false",
    "true": lambda i: "true",
    "undeclared": lambda i: f"nope{i} > 1",
}


def rule(n: int, kind: str, sep: str = " ") -> str:
    """One rule with ``n`` clauses of ``kind``, on one line unless ``sep`` says otherwise."""
    clauses = sep.join(f"unless {CLAUSES[kind](i)} then B" for i in range(n))
    return f"{HEAD}rule_start R1 when A then B{sep}{clauses}{sep}rule_end\n"


def calls(text: str) -> int:
    """How many Python and builtin calls checking ``text``'s AST makes (parsing excluded)."""
    spec = analyse(text).spec
    assert spec is not None
    count = 0

    def hook(frame: FrameType, event: str, arg: Any) -> None:
        nonlocal count
        if event in ("call", "c_call"):
            count += 1

    old = sys.getprofile()
    sys.setprofile(hook)
    try:
        check(spec, DiagnosticSink("<count>"))
    finally:
        sys.setprofile(old)
    return count


@pytest.mark.parametrize("kind", sorted(CLAUSES))
def test_checking_work_is_linear_in_unless_clauses(kind: str) -> None:
    small, large = calls(rule(1000, kind)), calls(rule(4000, kind))
    # linear: 4x the clauses, 4x the calls (quadratic would be 16x)
    assert 3.5 <= large / small <= 4.5, (kind, small, large)


def test_did_you_mean_is_searched_only_for_diagnostics_shown() -> None:
    """Misspelled measures in every clause of a file declaring as many: the "did you mean"
    search reads every declared name, so doing it per clause would be quadratic."""

    def text(n: int) -> str:
        defs = " ".join(f"measure level{i} : numeric" for i in range(n))
        clauses = " ".join(f"unless levl{i} > 1 then B" for i in range(n))
        return f"def_start event A event B {defs} def_end rule_start R1 when A then B {clauses} rule_end"

    small, large = calls(text(250)), calls(text(1000))
    assert 3.5 <= large / small <= 4.5, (small, large)
    hints = [d.hint for d in analyse(text(100)).diagnostics if d.code == "undeclared"]
    assert hints[:3] == ["did you mean `level0`?", "did you mean `level1`?", "did you mean `level2`?"]
    assert hints[-1] is None  # the summary of the folded ones


def test_the_comparison_helper_is_called_a_bounded_number_of_times(monkeypatch: pytest.MonkeyPatch) -> None:
    """The clause-against-clause question (``implies``) is asked only of short rules."""
    asked = 0

    def counting(conds: list[A.Expr]) -> Callable[[int, int], bool]:
        implies = _implication(conds)

        def wrapped(i: int, j: int) -> bool:
            nonlocal asked
            asked += 1
            return implies(i, j)

        return wrapped

    monkeypatch.setattr("cosleec.lang.unreachable._implication", counting)
    for n in (1000, 4000):
        asked = 0
        analyse(rule(n, "false"))
        assert asked == 0, n
    analyse(rule(MAX_LINT_CLAUSES, "false"))
    assert 0 < asked <= MAX_LINT_CLAUSES**4  # the bounded exact lint still runs


def test_a_twenty_thousand_clause_rule_reports_a_bounded_number_of_diagnostics() -> None:
    n = 20_000
    kinds = ("false", "undeclared")  # a warning and an error per clause, alternating
    text = f"{HEAD}rule_start R1 when A then B " + " ".join(
        f"unless {CLAUSES[kinds[i % 2]](i)} then B" for i in range(n)
    )
    text += " rule_end\n"
    result = analyse(text, "big.sleec")
    by_code: dict[str, list[Diagnostic]] = {}
    for d in result.diagnostics:
        by_code.setdefault(d.code, []).append(d)
    assert sorted(by_code) == ["undeclared", "unreachable-hedge"]
    for code, severity in (("undeclared", Severity.ERROR), ("unreachable-hedge", Severity.WARNING)):
        shown = by_code[code]
        assert len(shown) == 20 + 1
        summary = shown[-1]
        assert summary.message.startswith("... and 9,980 more")
        assert f"`{code}`" in summary.message and "rule `R1`" in summary.message
        assert summary.severity is severity
    assert not result.ok  # the folded errors still fail the file
    rendered = result.render()
    assert len(rendered) < len(text) // 10  # the one-line rule is not quoted per clause


def test_folding_is_per_rule_and_can_be_turned_off() -> None:
    two = rule(30, "false").replace(
        "rule_end\n", "R2 when A then B " + "unless false then B " * 30 + "rule_end\n"
    )
    folded = analyse(two)
    assert len(folded.diagnostics) == 2 * (20 + 1)
    assert sum("... and 10 more" in d.message for d in folded.diagnostics) == 2
    everything = analyse(two, options=Options(repeat_limit=0))
    assert len(everything.diagnostics) == 60


def test_a_rule_too_long_for_the_exact_lint_still_reports_false_clauses() -> None:
    n = MAX_LINT_CLAUSES + 1
    text = rule(n, "distinct").replace(f"unless m > {n - 1}", "unless false")
    got = [(d.code, d.message) for d in analyse(text).diagnostics]
    assert got == [("unreachable-hedge", f"clause {n}: condition is `false`, it never applies")]


def test_render_shows_a_bounded_window_of_a_long_line() -> None:
    line = "x = 1; " * 20_000 + "BAD" + " y" * 20_000
    col = line.index("BAD") + 1
    d = Diagnostic(severity=Severity.ERROR, code="c", message="m", span=A.Span(1, col, 1, col + 3), path="p")
    _header, quoted, caret = d.render(line + "\n").splitlines()
    assert len(quoted) <= 4 + D.LINE_WIDTH + 6 and len(caret) <= len(quoted)
    # the caret still points at the offending text
    assert quoted[caret.index("^") : caret.index("^") + 3] == "BAD" and caret.endswith("^~~")
    short = "R1 when A then B"
    e = Diagnostic(severity=Severity.ERROR, code="c", message="m", span=A.Span(1, 4, 1, 8), path="p")
    assert e.render(short).splitlines()[1:] == ["    " + short, "       ^~~~"]  # short lines: whole


def test_rendering_a_files_diagnostics_splits_its_source_once() -> None:
    text = rule(2000, "false", sep="\n")
    result = analyse(text, options=Options(repeat_limit=0))
    before = D._lines.cache_info().misses
    result.render()
    assert D._lines.cache_info().misses - before <= 1


def test_messages_quote_source_text_cut_short() -> None:
    long = "x" * 100_000
    result = analyse(f"{HEAD}rule_start R1 when A then B unless {long} > 1 then {long}Y rule_end")
    assert [d.code for d in result.diagnostics] == ["undeclared", "undeclared-event"]
    assert all(len(d.message) < 200 for d in result.diagnostics)
    assert D.clip("abc") == "abc" and len(D.clip("a" * 1000)) == D.QUOTE_LIMIT


def _implies_by_structure(conds: list[A.Expr], i: int, j: int) -> bool:
    """The lint's definition, stated directly: condition j is condition i or a conjunct of it."""

    def conjuncts(e: A.Expr) -> list[A.Expr]:
        if isinstance(e, A.BinOp) and e.op == "and":
            return [*conjuncts(e.left), *conjuncts(e.right)]
        return [e]

    return conds[j - 1] == conds[i - 1] or conds[j - 1] in conjuncts(conds[i - 1])


@given(st.lists(condition, min_size=1, max_size=6).flatmap(lambda cs: st.just(cs + cs[: len(cs) // 2])))
def test_hashed_implication_agrees_with_the_structural_definition(conds: list[A.Expr]) -> None:
    implies = _implication(conds)
    n = len(conds)
    for i in range(1, n + 1):
        for j in range(1, n + 1):
            assert implies(i, j) == _implies_by_structure(conds, i, j)


def test_corpus_diagnostics_do_not_depend_on_folding(corpus: list[Path]) -> None:
    """No real file repeats one finding 20 times in a rule: folding changes nothing there."""
    for path in corpus:
        for semantics in HedgeSemantics:
            opts = Options(lint=True, semantics=semantics)
            folded = analyse_file(path, infer_defs=True, options=opts)
            whole = analyse_file(path, infer_defs=True, options=replace(opts, repeat_limit=0))
            assert folded.diagnostics == whole.diagnostics, path.name
            assert folded.render() == whole.render(), path.name
