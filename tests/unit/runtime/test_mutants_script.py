"""scripts/mutants' one-token mutants (issue 29, part 7): where they are, how they apply, and
how the sample is drawn -- on small sources in a temporary tree, and on the runtime itself.

No mutant runs here (that takes minutes): the script is loaded as a module, and its
generator, its equivalence table and its sampler are checked alone. The script leaves this
file out of its own test selection.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[3]


def _load() -> ModuleType:
    loader = importlib.machinery.SourceFileLoader("cosleec_mutants_script", str(ROOT / "scripts" / "mutants"))
    spec = importlib.util.spec_from_loader(loader.name, loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[loader.name] = module  # dataclasses look their module up
    loader.exec_module(module)
    return module


mutants = _load()

SOURCE = '''\
"""A piece."""


def due(t: int = 0, flag: bool = True) -> bool:
    """A docstring holds no site."""
    label = "dû" if t == 2 else ""  # a column counts characters, not UTF-8 bytes
    if not t and flag or t is None:
        return t < 3 and t not in (1, 2)
    return 1.0 >= 0.0 == 0.5
'''


def tree(tmp_path: Path, text: str = SOURCE) -> Path:
    """A root whose src/cosleec/runtime holds ``piece.py`` with ``text``."""
    where = tmp_path / mutants.RUNTIME
    where.mkdir(parents=True)
    (where / "piece.py").write_text(text, encoding="utf-8")
    return tmp_path


def names(tmp_path: Path, text: str = SOURCE) -> list[str]:
    return [s.name for s in mutants.sites(tree(tmp_path, text), ["piece.py"])]


def test_every_kind_of_site_is_found_by_line_column_and_change(tmp_path: Path) -> None:
    assert names(tmp_path) == [
        "piece.py:4:18:0-1",
        "piece.py:4:34:True-False",
        "piece.py:6:23:eq-ne",  # after "dû": characters, not bytes (24)
        "piece.py:6:26:2-1",
        "piece.py:6:26:2-3",
        "piece.py:7:8:drop-not",
        "piece.py:7:14:and-or",
        "piece.py:7:23:or-and",
        "piece.py:7:28:is-is-not",
        "piece.py:8:18:lt-le",
        "piece.py:8:20:3-2",
        "piece.py:8:20:3-4",
        "piece.py:8:22:and-or",
        "piece.py:8:28:not-in-in",
        "piece.py:8:36:1-0",
        "piece.py:8:36:1-2",
        "piece.py:8:39:2-1",
        "piece.py:8:39:2-3",
        "piece.py:9:12:1.0-0.0",
        "piece.py:9:16:ge-gt",
        "piece.py:9:19:0.0-1.0",
        "piece.py:9:23:eq-ne",
    ]  # the defaults (t = 0, flag = True) are mutated too: they are behaviour; annotations are not


def test_annotations_and_large_or_other_constants_are_not_sites(tmp_path: Path) -> None:
    text = "x: tuple[int, int] = (11, -1)\ny: float = 2.5\nz = 'True'\n"
    assert names(tmp_path, text) == ["piece.py:1:28:1-0", "piece.py:1:28:1-2"]  # the 1 of -1


def test_a_site_applies_at_its_position_only_and_gives_valid_python(tmp_path: Path) -> None:
    root = tree(tmp_path)
    lines = mutants._lines(SOURCE)
    for site in mutants.sites(root, ["piece.py"]):
        mu = site.mutant()
        n, mutated = mutants.apply(SOURCE, mu)
        assert n == 1 and mutated != SOURCE and mutants.compiles(mutated, Path("piece.py"))
        changed = [(a, b) for a, b in zip(SOURCE.splitlines(), mutated.splitlines()) if a != b]
        assert len(changed) == 1 and changed[0][0] == lines[site.line - 1].rstrip("\n")
    (drop,) = [s for s in mutants.sites(root, ["piece.py"]) if s.change == "drop-not"]
    _, mutated = mutants.apply(SOURCE, drop.mutant())
    assert "    if t and flag or t is None:\n" in mutated  # the word and its space, nothing else


def test_a_site_whose_code_moved_does_not_apply(tmp_path: Path) -> None:
    (site, *_) = mutants.sites(tree(tmp_path), ["piece.py"])
    n, text = mutants.apply("\n" + SOURCE, site.mutant())
    assert (n, text) == (0, "\n" + SOURCE)


def test_an_equivalence_entry_marks_its_token_and_change(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    root = tree(tmp_path)
    everywhere = mutants.sites(root, ["piece.py"])
    monkeypatch.setattr(
        mutants,
        "EQUIVALENT",
        (
            mutants.Same("piece.py", "return t < «3» and", "three is as good as four", "3-4"),
            mutants.Same("piece.py", "t «is» None", "never None"),
        ),
    )
    same = mutants.equivalent_sites(everywhere, root)
    assert same == {"piece.py:8:20:3-4": "three is as good as four", "piece.py:7:28:is-is-not": "never None"}
    monkeypatch.setattr(mutants, "sites", lambda r: everywhere)
    assert mutants.check_equivalent(root) == []


@pytest.mark.parametrize(
    ("entry", "problem"),
    [
        (("piece.py", "t «<» 3", "x"), ""),
        (("piece.py", "t «<» 4", "x"), "occurs 0 times"),
        (("piece.py", "«return»", "x"), "occurs 2 times"),
        (("piece.py", "t < «3» and", "x", "3-5"), "marks no one-token site (3-5)"),
        (("piece.py", "def «due»(", "x"), "marks no one-token site (any change)"),
        (("piece.py", "t < 3", "x"), "mark the token as «token», once"),
        (("gone.py", "«x»", "x"), "no file"),
    ],
)
def test_a_stale_equivalence_entry_is_an_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, entry: tuple[str, ...], problem: str
) -> None:
    root = tree(tmp_path)
    everywhere = mutants.sites(root, ["piece.py"])
    monkeypatch.setattr(mutants, "EQUIVALENT", (mutants.Same(*entry),))
    monkeypatch.setattr(mutants, "sites", lambda r: everywhere)
    problems = mutants.check_equivalent(root)
    assert problems == [] if not problem else len(problems) == 1 and problem in problems[0]


def test_the_sample_is_seeded_skips_equivalents_and_keeps_the_rest_when_one_is_argued(tmp_path: Path) -> None:
    everywhere = mutants.sites(tree(tmp_path), ["piece.py"])
    first = mutants.sample(everywhere, {}, 5, seed=7)
    assert mutants.sample(everywhere, {}, 5, seed=7) == first
    assert mutants.sample(everywhere, {}, 5, seed=8) != first
    assert [everywhere.index(s) for s in first] == sorted(everywhere.index(s) for s in first)  # source order
    argued = mutants.sample(everywhere, {first[0].name: "why"}, 5, seed=7)
    assert first[0] not in argued and set(first[1:]) <= set(argued) and len(argued) == 5
    assert len(mutants.sample(everywhere, {}, 100, seed=7)) == len(everywhere)


def test_an_edit_elsewhere_moves_no_site_in_or_out_of_the_sample(tmp_path: Path) -> None:
    before = mutants.sample(mutants.sites(tree(tmp_path / "a"), ["piece.py"]), {}, 6, seed=3)
    edited = SOURCE.replace('"""A piece."""\n', '"""A piece."""\n\nLIMIT = 2 if True else 3\n')
    after = mutants.sample(mutants.sites(tree(tmp_path / "b", edited), ["piece.py"]), {}, 6, seed=3)
    kept = {(s.line - 2, s.col, s.change) for s in after if s.where == "due"}  # two lines lower
    new = [s for s in after if s.where != "due"]  # the new line's own sites may take a place
    assert kept <= {(s.line, s.col, s.change) for s in before} and len(kept) == 6 - len(new)


def test_every_site_of_the_runtime_applies_once_and_compiles() -> None:
    everywhere = mutants.sites(ROOT)
    assert len(everywhere) > 500  # every piece is read
    assert {s.file for s in everywhere} == set(mutants.PIECES)
    assert len({s.name for s in everywhere}) == len(everywhere)
    texts = {f: (ROOT / mutants.RUNTIME / f).read_text(encoding="utf-8") for f in mutants.PIECES}
    for site in everywhere:
        n, mutated = mutants.apply(texts[site.file], site.mutant())
        assert n == 1 and mutants.compiles(mutated, Path(site.file)), site.name


def test_the_equivalence_table_and_the_named_mutants_match_the_runtime() -> None:
    assert mutants.check(mutants.MUTANTS, ROOT) == []
    assert mutants.check_equivalent(ROOT) == []


def test_the_selection_leaves_this_file_out() -> None:
    assert "tests/unit/runtime/test_mutants_script.py" not in mutants.selection(ROOT)
    assert "tests/unit/runtime/test_mutant_kills.py" in mutants.selection(ROOT)[:3]


def test_a_one_token_mutant_is_named_on_the_command_line() -> None:
    (site, *_) = mutants.sites(ROOT, ["gate.py"])
    p = mutants.plan(mutants.arguments(["--only", site.name]))
    assert [mu.name for mu in p.chosen] == [site.name] and p.sample == [site.name]
    assert mutants.plan(mutants.arguments(["--only", "gate.py:1:1:lt-le"])) == (
        "no mutant gate.py:1:1:lt-le (see --list, --sites)"
    )
    drawn = mutants.plan(mutants.arguments(["--random", "3", "--no-named"]))
    assert len(drawn.chosen) == 3 and all(mu.at is not None for mu in drawn.chosen)
    both = mutants.plan(mutants.arguments(["--random", "3"]))
    assert len(both.chosen) == 3 + sum(not mu.equivalent for mu in mutants.MUTANTS)


def _results(killed: int, survived: int) -> tuple[Any, list[Any]]:
    """A plan of ``killed + survived`` one-token mutants and their results."""
    names = [f"gate.py:{i}:1:lt-le" for i in range(1, killed + survived + 1)]
    results = [
        mutants.Result(n, False, False, "killed" if i < killed else "survived", 1.0, "", "")
        for i, n in enumerate(names)
    ]
    return mutants.Plan([], [], {n: i for i, n in enumerate(names)}, names), results


@pytest.mark.parametrize(("killed", "survived", "status"), [(20, 0, 0), (19, 1, 0), (18, 2, 1), (0, 0, 0)])
def test_the_sample_passes_at_the_minimum_score_and_fails_below_it(
    killed: int, survived: int, status: int, capsys: pytest.CaptureFixture[str]
) -> None:
    plan, results = _results(killed, survived)
    a = mutants.arguments(["--random", str(killed + survived), "--random-seed", "5"])
    a.jobs = 2
    assert mutants.report(a, plan, results, 10.0) == status
    out, err = capsys.readouterr()
    if killed + survived:
        share = f"{100 * killed / (killed + survived):.1f} %"
        assert f"one-token sample (seed 5): {killed}/{killed + survived} killed ({share})" in out
    assert ("below 95 %" in err) is bool(status)
    assert "score:" not in out  # no named mutant ran: no score for them


def test_the_sample_is_reported_apart_in_json(capsys: pytest.CaptureFixture[str]) -> None:
    plan, results = _results(3, 1)
    a = mutants.arguments(["--random", "4", "--json", "--min-score", "70"])
    a.jobs = 1
    assert mutants.report(a, plan, results, 1.0) == 0
    out = json.loads(capsys.readouterr().out)
    assert (out["score"], out["mutants"]) == ("0/0", [])
    assert (out["sample"]["score"], out["sample"]["percent"], out["sample"]["seed"]) == ("3/4", 75.0, 0)
