"""``cosleec graph``: the rule set as COP sees it, drawn by the real Graphviz.

What the picture must show is checked on the model (:func:`cosleec.views.build`): a cluster
per rule with its base and one box per layer, events and measures shared between rules,
priorities and possible conflicts as edges; then the DOT and Mermaid texts, and the SVG and
PNG that Graphviz's own ``dot`` makes of them (skipped where Graphviz is missing locally;
under CI, where ``scripts/setup`` installs it, a failure).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cosleec.errors import UserError
from cosleec.runtime import RuleSet
from cosleec.testing.corpus import corpus_dir
from cosleec.views import RuleGraph, build, render, to_dot, to_mermaid
from cosleec.views.graph import Box

ROOT = Path(__file__).resolve().parents[3]
CURTAINS = ROOT / "examples" / "curtains.sleec"
CARE = ROOT / "examples" / "assistive_care" / "rules.sleec"
LARGEST = (
    "a-l-partis__SLEEC-ADAPT__AgentAdaption__agentAdaptionCode__scalability__sleecRules__rulestest625.sleec"
)

TWO = """def_start event E event F event A event B event Log measure m : boolean measure n : numeric def_end
rule_start
R1 when E and n > 3 then A within 5 seconds unless m then not B within 2 seconds
R2 when F then B within 10 seconds
R3 when E then Log
rule_end"""


def graphviz() -> None:
    if shutil.which("dot") is None:
        if os.environ.get("CI"):
            pytest.fail("Graphviz's `dot` is missing under CI: scripts/setup installs it (as root)")
        pytest.skip("Graphviz is not installed here (apt-get install graphviz)")


def edges(rules: RuleSet, only: tuple[str, ...] = ()) -> set[tuple[str, str, str]]:
    return {(e.src, e.dst, e.kind) for e in build(rules, only).edges}


def test_a_rule_is_its_base_and_one_box_per_layer_with_the_rules_own_text() -> None:
    g = build(RuleSet.from_file(CURTAINS))
    [(rule, boxes)] = g.clusters
    assert rule == "R1"
    assert [b.id for b in boxes] == ["R1", "R1.1", "R1.2"]
    assert [b.kind for b in boxes] == ["rule", "layer", "layer"]
    assert boxes[0].lines == ("R1", "when CurtainOpenRequest", "then OpenCurtains within 30 seconds")
    assert boxes[1].lines == ("layer R1.1", "unless userUndressed then Refuse and ExplainWhy")
    assert "unless userDistressed then WarnUser and" in boxes[2].lines[1]


def test_events_and_measures_are_shared_nodes_and_edges_say_how_rules_use_them() -> None:
    rules = RuleSet.from_text(TWO)
    g = build(rules)
    shared = {b.id: b for b in g.shared}
    assert set(shared) == {"e:E", "e:F", "e:A", "e:B", "e:Log", "m:m", "m:n"}  # each once
    assert shared["m:n"].lines == ("n : numeric",)
    got = edges(rules)
    assert {("e:E", "R1", "triggers"), ("e:E", "R3", "triggers"), ("e:F", "R2", "triggers")} <= got
    assert ("m:n", "R1", "reads") in got  # the trigger condition reads n
    assert ("m:m", "R1.1", "reads") in got and ("m:m", "R1", "reads") not in got  # the clause reads m
    assert ("R1", "e:A", "obliges") in got and ("R1", "e:B", "obliges") not in got
    assert ("R1.1", "e:B", "forbids") in got  # `not B`: forbidden, not obliged
    assert ("R1", "R1.1", "layer") in got


def test_a_possible_conflict_is_a_red_edge_until_a_priority_orders_the_rules() -> None:
    rules = RuleSet.from_text(TWO)
    assert ("R2", "R1", "conflict") in edges(rules) or ("R1", "R2", "conflict") in edges(rules)
    ordered = RuleSet.from_text(TWO.replace("rule_end", "rule_end priority_start R2 > R1 priority_end"))
    got = edges(ordered)
    assert ("R2", "R1", "priority") in got
    assert not {e for e in got if e[2] == "conflict"}


def test_one_rule_draws_only_what_it_touches() -> None:
    rules = RuleSet.from_text(TWO)
    g = build(rules, ("R2",))
    assert [r for r, _ in g.clusters] == ["R2"]
    assert {b.id for b in g.shared} == {"e:F", "e:B"}
    assert not {e for e in g.edges if e.kind in ("conflict", "priority")}  # R1 is not drawn


def test_dot_and_mermaid_texts() -> None:
    g = build(RuleSet.from_file(CURTAINS))
    dot = to_dot(g, "curtains")
    assert dot.startswith("digraph sleec {") and dot.rstrip().endswith("}")
    assert "subgraph cluster_0 {" in dot and "cluster_legend" in dot
    assert '"R1" -> "R1.1"' in dot and '"e:CurtainOpenRequest" -> "R1"' in dot
    mmd = to_mermaid(g)
    assert mmd.startswith("flowchart LR\n")
    assert 'subgraph n0 ["R1"]' in mmd and "layer R1.1" in mmd
    quoted = to_mermaid(RuleGraph((), (Box("e:x", ('say "hi"',), "event"),), ()))
    assert "say #quot;hi#quot;" in quoted and 'say "hi"' not in quoted


@pytest.mark.parametrize("path", [CURTAINS, CARE], ids=lambda p: p.name)
def test_graphviz_draws_svg_and_png(path: Path) -> None:
    graphviz()
    dot = to_dot(build(RuleSet.from_file(path)), str(path))
    svg = render(dot, "svg").decode()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg and "R1.1" in svg
    assert render(dot, "png")[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_largest_corpus_file_draws() -> None:
    graphviz()
    path = corpus_dir() / LARGEST
    if not path.exists():
        pytest.skip("the corpus is not beside the checkout")
    svg = render(to_dot(build(RuleSet.from_file(path)), path.name), "svg").decode()
    assert svg.count('class="cluster"') >= 624


def cosleec(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cosleec.cli.main", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        check=False,
    )


def test_the_command_writes_each_format_and_refuses_clearly(tmp_path: Path) -> None:
    done = cosleec("graph", str(CURTAINS), cwd=tmp_path)
    assert done.returncode == 0 and done.stdout.startswith("digraph sleec {")
    for ext in ("dot", "mmd") + (("svg", "png") if shutil.which("dot") else ()):
        done = cosleec("graph", str(CURTAINS), "-o", f"out.{ext}", cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        assert done.stdout == f"out.{ext}: 1 rule(s) drawn ({ext})\n"
        assert (tmp_path / f"out.{ext}").stat().st_size > 100
    bad = cosleec("graph", str(CURTAINS), "--rule", "R2", cwd=tmp_path)
    assert bad.returncode == 1 and "no rule 'R2'" in bad.stderr and "Traceback" not in bad.stderr
    ext = cosleec("graph", str(CURTAINS), "-o", "out.jpg", cwd=tmp_path)
    assert ext.returncode == 1 and "end the file name with one of .svg, .png, .dot, .mmd" in ext.stderr
    assert not (tmp_path / "out.jpg").exists()
    gone = cosleec("graph", "nope.sleec", cwd=tmp_path)
    assert gone.returncode == 1 and "Traceback" not in gone.stderr


def test_with_analyse_the_red_edges_are_what_cosleec_analyse_proves() -> None:
    from cosleec.views import analysed_conflicts

    found = analysed_conflicts(str(CARE))
    assert ("R6", "R10", "runtime-conflict, proved") in found
    rules = RuleSet.from_file(CARE)
    red = {(e.src, e.dst, e.label) for e in build(rules, (), found).edges if e.kind == "conflict"}
    assert red == set(found)
    quick = {(e.src, e.dst) for e in build(rules).edges if e.kind == "conflict"}
    assert quick == {("R10", "R6")} or quick == {("R6", "R10")}  # the pairwise check: the same pair
    assert not {e for e in build(rules, ("R1",), found).edges if e.kind == "conflict"}  # R6 not drawn


# ---------------------------------------------------------------------------- bounded (issue 28)
def clashing(n: int) -> str:
    """``n`` rules on one trigger, every other one forbidding what the rest oblige: every
    obliging rule can conflict with every forbidding one (``n**2 / 4`` possible conflicts)."""
    rules = "\n".join(f"R{i} when E then {'not ' if i % 2 else ''}A within 5 seconds" for i in range(n))
    return f"def_start event E event A def_end\nrule_start\n{rules}\nrule_end\n"


def test_a_picture_of_too_many_rules_is_refused_before_it_is_built(tmp_path: Path) -> None:
    """`cosleec graph` of 100,000 rules ran for minutes into gigabytes: 5,001 rules that
    can conflict pairwise (6 million possible conflicts) are refused at once, naming the
    limit and the way out, and a few of them (--rule) draw with only their own conflicts."""
    path = tmp_path / "many.sleec"
    path.write_text(clashing(5_001), encoding="utf-8")
    refused = cosleec("graph", str(path), cwd=tmp_path)
    assert refused.returncode == 1 and "Traceback" not in refused.stderr
    assert "5,001 rules are more than one picture draws (at most 5,000)" in refused.stderr
    assert "many.sleec" in refused.stderr and "--rule R" in refused.stderr
    some = cosleec("graph", str(path), "--rule", "R1", "--rule", "R2", "-o", "some.dot", cwd=tmp_path)
    assert some.returncode == 0, some.stderr
    dot = (tmp_path / "some.dot").read_text(encoding="utf-8")
    red = [
        line.split("[")[0].strip() for line in dot.splitlines() if "dir=both" in line and "legend" not in line
    ]
    assert red in (['"R1" -> "R2"'], ['"R2" -> "R1"'])  # their own conflict, none of the 5,000 others


def test_graphviz_is_not_asked_for_more_than_it_lays_out_in_seconds() -> None:
    rules = RuleSet.from_text(clashing(300))  # 150 x 150 possible conflicts: 22,500 red edges
    with pytest.raises(UserError) as refused:
        build(rules, fmt="svg")
    said = refused.value.render()
    assert "more than 10,000 possible conflicts between the 300 rules" in said
    assert "at most 10,000 boxes and arrows" in said and "DOT or Mermaid text holds up to 100,000" in said
    g = build(rules, fmt="dot")  # as text: 22,500 red edges is within what DOT holds
    assert sum(1 for e in g.edges if e.kind == "conflict") == 150 * 150
    apart = "\n".join(f"R{i} when E{i} then A{i} within 5 seconds" for i in range(2_100))
    events = " ".join(f"event E{i} event A{i}" for i in range(2_100))
    separate = RuleSet.from_text(f"def_start {events} def_end\nrule_start\n{apart}\nrule_end\n")
    with pytest.raises(
        UserError, match=r"10,500 boxes and arrows for the 2,100 rules: more than a picture in SVG"
    ):
        build(separate, fmt="svg")  # no conflict: 5 boxes and arrows a rule
    assert len(build(separate, fmt="mmd").edges) == 2 * 2_100


def test_with_analyse_an_analysis_out_of_time_is_refused_not_drawn_in_part(tmp_path: Path) -> None:
    from cosleec.views import analysed_conflicts

    clauses = "\n".join(f"  unless m > {i} then A within {i + 1} seconds" for i in range(3_000))
    path = tmp_path / "long.sleec"
    path.write_text(
        f"def_start event E event A measure m : numeric def_end\nrule_start\nR1 when E then A within 9 seconds\n"
        f"{clauses}\nrule_end\n",
        encoding="utf-8",
    )
    with pytest.raises(UserError) as refused:
        analysed_conflicts(str(path), seconds=0.3)  # a picture without the conflicts would say there are none
    said = refused.value.render()
    assert "did not finish within 0.3 s" in said and "long.sleec" in said and "without --analyse" in said
