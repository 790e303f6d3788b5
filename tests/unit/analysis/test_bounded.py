"""``cosleec analyse`` stays bounded (issue 28, finding 8): the encoding grows linearly in a
rule's ``unless`` clauses, and ``--deadline`` ends the whole run with a partial result that
says what was not decided. And (finding 13) ``check``, ``analyse``, ``graph`` and
``conforms`` read the same deeply nested conditions.

Scaling is measured as a ratio within one test (four times the clauses, against the same
machine at the same moment) or by counting the encoding's size, never against a wall-clock
figure.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from cosleec.analysis import MORE, Deadline, Settings, analyse_file
from cosleec.analysis.checks import LISTED
from cosleec.analysis.encoding import Encoding
from cosleec.cli.main import main
from cosleec.lang import HedgeSemantics, Reading, analyse


def hedged(clauses: int, *, negated: bool = False, rules: int = 1) -> str:
    """``rules`` rules, each with ``clauses`` unless clauses over one numeric measure."""
    head = "def_start event Go event Act event Stop measure m : numeric measure b : boolean def_end\nrule_start\n"
    body = []
    for r in range(rules):
        lines = [f"R{r} when Go then Act within {1000 + r} seconds"]
        for i in range(clauses):
            act = "not Stop" if negated and i % 2 else "Act"
            lines.append(f"  unless m > {i} then {act} within {i + 1} seconds")
        body.append("\n".join(lines))
    return head + "\n".join(body) + "\nrule_end\n"


def edges(enc: Encoding) -> int:
    """The size of what the solver holds: the edges of its assertions' DAG (shared terms once)."""
    seen: set[int] = set()
    todo = list(enc.solver.assertions())
    count = 0
    while todo:
        e = todo.pop()
        if e.get_id() in seen:
            continue
        seen.add(e.get_id())
        kids = e.children()
        count += len(kids)
        todo.extend(kids)
    return count


def encoded(clauses: int, semantics: HedgeSemantics, negated: bool) -> int:
    result = analyse(hedged(clauses, negated=negated), "scale.sleec")
    assert result.ok and result.spec is not None and result.symbols is not None
    enc = Encoding(result.spec, dict(result.symbols.constant_values), Reading(semantics=semantics), 2)
    enc.probe("Go")
    enc.unfold()
    for rule in result.spec.rules:  # what the snapshot checks ask on top: every clause's condition
        enc.chosen(rule.response.defeaters, enc.slots[0].snap, HedgeSemantics.LAST_WINS)
        enc.chosen(rule.response.defeaters, enc.slots[0].snap, HedgeSemantics.NESTED)
    return edges(enc)


@pytest.mark.parametrize("semantics", list(HedgeSemantics))
@pytest.mark.parametrize("negated", [False, True])
def test_the_encoding_grows_linearly_in_unless_clauses(semantics: HedgeSemantics, negated: bool) -> None:
    small, large = encoded(60, semantics, negated), encoded(240, semantics, negated)
    assert large < 5 * small, (small, large)  # linear: 4x; the quadratic choice of a clause was 16x


def test_analyse_time_grows_near_linearly_in_unless_clauses(tmp_path: Path) -> None:
    def seconds(clauses: int) -> float:
        path = tmp_path / f"u{clauses}.sleec"
        path.write_text(hedged(clauses), encoding="utf-8")
        t = time.process_time()  # this process's CPU: what other processes do counts little
        report = analyse_file(path, Settings())
        assert not report.failed and not report.unknown, report.unknown
        return time.process_time() - t

    seconds(10)  # warm up (imports, z3's first context)
    small = min(seconds(40) for _ in range(2))
    large = min(seconds(160) for _ in range(2))
    assert large < 8 * small, (small, large)  # 4x the clauses: linear is 4x, the quadratic encoding 14x


# ---------------------------------------------------------------------------- the whole-run deadline
CONFLICT = "C1 when A then B within 5 seconds\nC2 when A then not B within 10 seconds\n"


def big(tmp_path: Path, name: str = "big.sleec", conflict: bool = True) -> Path:
    """Two rules that conflict (found in a moment), then a rule of 3,000 clauses (R0: seconds)."""
    text = hedged(3_000).replace("event Go", "event Go event A event B")
    if conflict:
        text = text.replace("rule_start\n", "rule_start\n" + CONFLICT)
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_a_deadline_ends_the_whole_run_and_says_what_was_not_decided(tmp_path: Path) -> None:
    path = big(tmp_path)
    t = time.perf_counter()
    report = analyse_file(path, Settings(timeout=60), deadline=Deadline.after(0.5))
    took = time.perf_counter() - t
    assert took < 4, (
        took
    )  # the run, not one question, is bounded: prompt after the deadline (whole: ~5 s idle)
    assert not report.complete
    assert {f.subject for f in report.findings if f.code == "vacuous-conflict"} == {"C1", "C2"}  # kept
    assert report.undecided["vacuous-conflict"] == ["R0"] == report.undecided["dead-rule"]  # under way
    assert report.undecided["redundant"] is None and report.undecided["runtime-conflict"] is None


def test_undecided_pairs_are_listed_up_to_a_limit(tmp_path: Path) -> None:
    """150 rules owe what 150 others forbid: 22,500 pairs of clauses that can clash, walked
    lazily; those the deadline leaves are listed up to 10,000, then ``...``."""
    rules = "\n".join(f"R{i} when E then {'not ' if i % 2 else ''}A within 5 seconds" for i in range(300))
    path = tmp_path / "pairs.sleec"
    path.write_text(f"def_start event E event A def_end\nrule_start\n{rules}\nrule_end\n", encoding="utf-8")
    t = time.perf_counter()
    report = analyse_file(path, Settings(), ["runtime-conflict"], deadline=Deadline.after(1.0))
    assert time.perf_counter() - t < 4
    left = report.undecided["runtime-conflict"]
    assert left is not None and len(left) == LISTED + 1 and left[-1] == MORE
    assert all("/" in pair for pair in left[:-1]) and len(set(left)) == len(left)
    assert not {f.subject for f in report.findings} & set(left)  # each pair decided or listed, never both


def test_without_a_deadline_the_same_file_is_analysed_whole(tmp_path: Path) -> None:
    report = analyse_file(big(tmp_path), Settings(), ["vacuous-conflict"])
    assert report.complete and report.undecided == {}
    assert {f.subject for f in report.findings} == {"C1", "C2"}


def test_the_command_exits_3_on_a_partial_run_and_lists_what_is_open(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    quiet, after = big(tmp_path, "quiet.sleec", conflict=False), big(tmp_path, "after.sleec")
    t = time.perf_counter()
    rc = main(
        ["analyse", "--deadline", "0.5", "--sarif", str(tmp_path / "out.sarif"), str(quiet), str(after)]
    )
    assert time.perf_counter() - t < 4
    out = capsys.readouterr().out
    assert rc == 3  # nothing found, but not everything decided: neither 0 nor 1
    assert "quiet.sleec: undecided: vacuous-conflict: the deadline passed before R0 could be decided" in out
    assert "not run, the deadline had passed" in out and "the file was not read" in out
    assert "quiet.sleec: no findings, partial: the deadline passed" in out
    log = json.loads((tmp_path / "out.sarif").read_text(encoding="utf-8"))
    assert log["runs"][0]["invocations"][0]["executionSuccessful"] is False
    rc = main(["analyse", "--deadline", "0.5", "--json", str(after)])
    doc = json.loads(capsys.readouterr().out)["files"][0]
    assert rc == 1  # found: a finding is proved whether the run finished or not
    assert doc["complete"] is False and doc["undecided"]["redundant"] is None
    assert doc["undecided"]["vacuous-conflict"] == ["R0"]
    assert main(["analyse", "--deadline", "0", str(after)]) == 2  # a usage error
    assert "not a positive number of seconds" in capsys.readouterr().err


# ---------------------------------------------------------------------------- nesting (finding 13)
def deep(condition: str) -> str:
    return (
        "def_start event Go event Act measure m : numeric measure b : boolean def_end\n"
        f"rule_start\nR1 when Go and {condition} then Act within 10 seconds\nrule_end\n"
    )


DEEP = {
    "and-chain": " and ".join(f"m > {i}" for i in range(20_000)),  # flat: read without recursion
    "or-chain": "(" + " or ".join(f"m = {i}" for i in range(20_000)) + ")",
    "not-chain": "not " * 3_000 + "b",  # deep: run in a deep thread, as `check` runs its passes
    "alternating": "".join(f"(b {'and' if i % 2 else 'or'} " for i in range(2_000)) + "b" + ")" * 2_000,
}


@pytest.mark.parametrize("shape", list(DEEP))
@pytest.mark.parametrize("command", ["check", "analyse", "graph", "conforms"])
def test_every_command_reads_what_check_accepts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, shape: str
) -> None:
    """`check` accepted a 50,000-term `and` that `analyse`, `graph` and `conforms` refused
    as nested too deeply: each now reads whatever `check` accepts."""
    rules = tmp_path / "deep.sleec"
    rules.write_text(deep(DEEP[shape]), encoding="utf-8")
    trace = tmp_path / "trace.jsonl"
    trace.write_text(
        '{"t": 0, "set": {"m": 1, "b": true}}\n{"t": 0, "event": "Go"}\n{"t": 1, "event": "Act"}\n{"t": 20}\n',
        encoding="utf-8",
    )
    args = {
        "check": [str(rules)],
        "analyse": [str(rules), "--check", "vacuous-conflict,redundant,unselectable-clause"],
        "graph": [str(rules), "-o", str(tmp_path / "deep.dot")],
        "conforms": [str(rules), str(trace)],
    }[command]
    rc = main([command, *args])
    out, err = capsys.readouterr()
    assert "nested too deeply" not in err and "Traceback" not in err, err[-500:]
    assert rc in (0, 1), err[-500:]  # 1: conforms or analyse found something; never a refusal
    assert rc == 0 or command in ("analyse", "conforms"), (out[-500:], err[-500:])
