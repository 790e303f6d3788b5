"""`cosleec check` and the runtime accept the same rules, however deep their expressions:
10,000 terms of `and`, 10,000 `not`s, 10,000 nested parentheses, 10,000 `+`/`-` (in a
condition and in a deadline), and operators alternating 10,000 levels deep -- no
RecursionError, no "too many nested parentheses" from CPython's compiler, and the values
the rules mean (the fast form and the three-valued one).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from cosleec.cli.main import main
from cosleec.lang import analyse
from cosleec.runtime import Manager

N = 10_000


def alternating(n: int) -> str:
    """`a and (b or (a and (b or ... a)))`, n operators deep."""
    ops = ["and" if i % 2 == 0 else "or" for i in range(n)]
    names = ["a" if i % 2 == 0 else "b" for i in range(n)]
    return "".join(f"{x} {op} (" for x, op in zip(names, ops)) + "a" + ")" * n


def alternating_value(n: int, a: bool, b: bool) -> bool:
    """What :func:`alternating` means, computed inside out."""
    value = a
    for i in reversed(range(n)):
        value = (a and value) if i % 2 == 0 else (b or value)
    return value


TK = f"""def_start
  event E1 event E2 event E3 event E4 event E5 event E6 event E7 event F event G
  measure a : boolean
  measure b : boolean
def_end
rule_start
  Rand when E1 and {" and ".join(["a"] * N)} then F
  Rnot when E2 and {"not " * N}b then F
  Rodd when E3 and {"not " * (N - 1)}b then F
  Rparen when E4 and {"(" * N}a{")" * N} then F
  Rright when E5 and {"a and (" * (N - 1)}b{")" * (N - 1)} then F
  Ralt when E6 and {alternating(N)} then F
rule_end
"""

SMALL = f"""def_start event E event F event G measure a : boolean measure b : boolean def_end
rule_start
  R when E then F unless {" and ".join(["a"] * (N - 1))} and b then G
rule_end
"""

MINUS = "(" * (N - 1) + "{x}" + " - {x})" * (N - 1)  # ((x - x) - x) ...: 10,000 terms
PLUS = "(" * (N - 1) + "1" + " + 1)" * (N - 1)
LEGOS = (
    "def_start\n  event E event F\n  measure x : numeric\ndef_end\nrule_start\n"
    f"  R when E and ({MINUS} < 0)\n    then F within {PLUS} seconds\nrule_end\n"
)


@pytest.fixture(scope="module")
def tk() -> Manager:
    return Manager.from_text(TK)


def fired(m: Manager, event: str, **values: object) -> list[str]:
    return [d.rule for d in m.event(event, values) if d.obligations]


def test_check_accepts_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for name, text in (("tk.sleec", TK), ("legos.sleec", LEGOS)):
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        assert main(["check", str(path)]) == 0, capsys.readouterr()
        out, err = capsys.readouterr()
        assert f"{path}: ok (" in out
        assert "Traceback" not in out + err and "deeply" not in out + err


def test_the_runtime_decides_them(tk: Manager) -> None:
    a, b = True, False
    assert fired(tk, "E1", a=a, b=b) == ["Rand"]
    assert fired(tk, "E1", a=False, b=b) == []
    assert fired(tk, "E2", a=a, b=b) == []  # an even number of `not`s: b
    assert fired(tk, "E2", a=a, b=True) == ["Rnot"]
    assert fired(tk, "E3", a=a, b=b) == ["Rodd"]  # odd: not b
    assert fired(tk, "E4", a=a, b=b) == ["Rparen"]
    assert fired(tk, "E5", a=a, b=b) == []
    assert fired(tk, "E5", a=a, b=True) == ["Rright"]
    for va in (True, False):
        for vb in (True, False):
            want = ["Ralt"] if alternating_value(N, va, vb) else []
            assert fired(tk, "E6", a=va, b=vb) == want


def test_unknown_values_in_a_deep_clause_are_three_valued() -> None:
    m = Manager.from_text(SMALL)
    (d,) = m.event("E", {"a": False})  # false and unknown: false
    assert d.clause == 0 and [o.event for o in d.obligations] == ["F"]
    (d,) = m.event("E", {"a": True})  # true and unknown: unknown
    assert d.clause is None and d.missing == ("b",)
    (d,) = m.event("E", {"b": True})
    assert d.clause == 1 and [o.event for o in d.obligations] == ["G"]
    alt = SMALL.replace(SMALL.split("unless ")[1].split(" then G")[0], alternating(N))
    m = Manager.from_text(alt)
    (d,) = m.event("E", {"b": True})  # a and (...): unknown
    assert d.clause is None and d.missing == ("a",)
    m = Manager.from_text(alt)
    (d,) = m.event("E", {"a": True})  # b or (a and ... a): true, whatever b
    assert d.clause == 1


def test_deep_arithmetic_in_a_condition_and_a_deadline() -> None:
    m = Manager.from_text(LEGOS)
    (d,) = m.event("E", {"x": 3})  # 3 - 3 * 9,999 < 0
    (ob,) = d.obligations
    assert ob.within_s == float(N)
    assert m.event("E", {"x": -1}) == []  # -1 + 9,999 > 0
    assert m.event("E", {"x": 0.5}) != []


def test_decide_from_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "small.sleec"
    path.write_text(SMALL, encoding="utf-8")
    rc = main(["decide", str(path), "--event", "E", "--set", "a=true", "--set", "b=true", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert [(d["rule"], d["clause"]) for d in json.loads(out)["decisions"]] == [("R", 1)]


def test_the_messages_of_a_deep_file_are_the_usual_ones() -> None:
    """A deep file with a mistake gets the same diagnostics as a shallow one."""
    result = analyse(SMALL.replace("unless a and", "unless c and", 1))
    assert [(d.code, d.span.line, d.span.col) for d in result.errors] == [("undeclared", 3, 26)]


@pytest.mark.parametrize("depth", [1, 2, 99, 100, 101, 102, 150, 198, 199, 200, 201, 202, 250, 1_001])
def test_every_depth_around_the_limits_of_python_source(depth: int) -> None:
    """Around compile.MAX_NEST (100) and CPython's 200 nested parentheses: the compiled
    source or the evaluator that takes over, both with the values the rule means."""
    text = f"""def_start event E event F event G measure a : boolean measure b : boolean def_end
rule_start R when E and {alternating(depth)} then F unless {alternating(depth)} then G rule_end
"""
    m = Manager.from_text(text)
    for va in (True, False):
        for vb in (True, False):
            decisions = m.event("E", {"a": va, "b": vb})
            if not alternating_value(depth, va, vb):
                assert decisions == []
                continue
            (d,) = decisions
            assert d.clause == 1


def test_the_recursion_limit_is_given_back() -> None:
    before = sys.getrecursionlimit()
    assert analyse(SMALL).ok
    assert sys.getrecursionlimit() == before
