"""A rule set as COP sees it, as a picture: Graphviz (DOT, SVG, PNG) or Mermaid text.

Each rule is a cluster: its trigger and default response (the layered method's base),
then one box per clause layer (``R1.1``, ...) with its condition and response. Events and
measures are nodes shared between rules, so that dependencies show: an event points to
the rules it triggers, a rule or layer to the events its response obliges (a dashed edge
for one it forbids), a measure to the triggers and layers that read it. Declared
priorities are blue edges from the higher rule to the lower; pairs of responses that
oblige and forbid the same event across rules no priority orders (what the Manager warns
of at start, or with ``--analyse`` what ``cosleec analyse`` proves) are red edges. A legend
says which is which.

Reviewers read it next to the rules, so every label is the rule's own text (the
canonical printer's), shortened past :data:`LABEL_WIDTH` characters a line.
"""

from __future__ import annotations

import functools
import json
import shutil
import subprocess
import textwrap
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import NoReturn

from cosleec.analysis import Deadline, Settings, analyse_file
from cosleec.errors import UserError
from cosleec.lang import Printer, deeply, pairs, visit
from cosleec.lang import ast as A
from cosleec.runtime import Priorities, RuleSet, possible_conflicts

LABEL_WIDTH = 48
"""Characters a label line holds before it wraps (longer conditions wrap, never vanish)."""

MAX_LINES = 6
"""Lines a label keeps; the rest is cut, marked with an ellipsis."""

FORMATS = ("svg", "png", "dot", "mmd")

MAX_RULES = 5_000
"""Rules one picture draws (``--rule`` picks some of a larger file). Past that nobody reads
it, and the possible conflicts to draw can grow with the rules squared (issue 28)."""

MAX_SIZE = {"svg": 10_000, "png": 10_000, "dot": 100_000, "mmd": 100_000}
"""Boxes and arrows one picture holds, by format. Graphviz's layout grows faster than the
picture (measured by ``benchmarks/scale_limits.py``: 4,600 boxes and arrows in 3 s, 9,800
in 18 s, 14,400 in 74 s); DOT and Mermaid text is written in time linear in it."""


@dataclass(frozen=True)
class Box:
    """One node of the picture: ``id`` (stable, quoted where needed), its label lines, its kind."""

    id: str
    lines: tuple[str, ...]
    kind: str  # rule | layer | event | measure


@dataclass(frozen=True)
class Edge:
    """An arrow ``src -> dst`` of a kind: triggers, reads, obliges, forbids, priority, conflict, layer."""

    src: str
    dst: str
    kind: str
    label: str = ""


@dataclass(frozen=True)
class RuleGraph:
    """What the picture shows, independent of the notation it is drawn in."""

    clusters: tuple[tuple[str, tuple[Box, ...]], ...]  # rule name -> its base and layer boxes
    shared: tuple[Box, ...]  # events and measures
    edges: tuple[Edge, ...]


def _wrap(text: str) -> tuple[str, ...]:
    lines = textwrap.wrap(text, LABEL_WIDTH, break_long_words=True, break_on_hyphens=False) or [""]
    if len(lines) > MAX_LINES:
        lines = [*lines[: MAX_LINES - 1], lines[MAX_LINES - 1][: LABEL_WIDTH - 1] + "…"]
    return tuple(lines)


def check_drawable(rules: RuleSet, only: Sequence[str] = ()) -> None:
    """UserError when the picture of ``rules`` (or of those named in ``only``) would draw
    more than :data:`MAX_RULES` rules: said before anything is built or analysed."""
    count = len(set(only)) if only else len(rules.rules)
    if count > MAX_RULES:
        raise UserError(
            f"{count:,} rules are more than one picture draws (at most {MAX_RULES:,})",
            where=rules.spec.path,
            hint="draw some of them: --rule R (repeatable) draws R with the events and measures it touches",
        )


def build(
    rules: RuleSet,
    only: Sequence[str] = (),
    conflicts: Iterable[tuple[str, str, str]] | None = None,
    *,
    fmt: str = "dot",
) -> RuleGraph:
    """The picture of ``rules`` (every rule, or those named in ``only``, with what they touch).

    ``conflicts`` are the red edges, ``(rule, rule, label)``: by default the quick pairwise
    check the Manager warns with at start (a response obliges an event another forbids, no
    priority between them); :func:`analysed_conflicts` gives those ``cosleec analyse``
    finds, proved or up to its bound. UserError when the picture is larger than ``fmt``
    can hold (:data:`MAX_RULES`, :data:`MAX_SIZE`), naming the limit and the way out."""
    check_drawable(rules, only)
    spec = rules.spec
    printer = Printer(spec, A.Dialect.TK)
    measures = {m.name: m for m in spec.measures}
    wanted = set(only)
    chosen = [r for r in rules.rules if not only or r.name in wanted]
    clusters: list[tuple[str, tuple[Box, ...]]] = []
    edges: list[Edge] = []
    used_events: dict[str, None] = {}
    used_measures: dict[str, None] = {}

    def reads(e: A.Expr | None, box: str) -> None:
        found = {n.name for n in visit.names(e) if n.name in measures}
        for m in sorted(found):
            used_measures[m] = None
            edges.append(Edge(f"m:{m}", box, "reads"))

    def obliges(resp: A.Response | None, box: str, *, inner: bool) -> None:
        found: list[tuple[str, bool]] = []
        if resp is not None:  # the base's own items only: its clauses are the layers' boxes
            found = [
                (o.event, o.negated) for o in visit.occurrences(resp if inner else A.Response(resp.items, ()))
            ]
        for ev, negated in dict.fromkeys(found):
            used_events[ev] = None
            edges.append(Edge(box, f"e:{ev}", "forbids" if negated else "obliges"))

    for r in chosen:
        ast = r.ast
        trigger, head, layers = deeply(functools.partial(_texts, printer, ast))
        base = Box(r.name, (r.name, *_wrap(f"when {trigger}"), *_wrap(f"then {head}")), "rule")
        boxes = [base]
        used_events[ast.trigger.event] = None
        edges.append(Edge(f"e:{ast.trigger.event}", r.name, "triggers"))
        reads(ast.trigger.condition, r.name)
        obliges(ast.response, r.name, inner=False)
        for clause, d, text in zip(r.clauses, ast.response.defeaters, layers):
            boxes.append(Box(clause.layer, (f"layer {clause.layer}", *_wrap(text)), "layer"))
            edges.append(Edge(r.name, clause.layer, "layer"))
            reads(d.condition, clause.layer)
            obliges(d.response, clause.layer, inner=True)
        clusters.append((r.name, tuple(boxes)))
    limit = MAX_SIZE.get(fmt, MAX_SIZE["dot"])
    edges += _between(rules, [r.name for r in chosen], conflicts, fmt, limit)
    shared = [Box(f"e:{e}", (e,), "event") for e in used_events]
    for m in used_measures:  # `measure m : type` without the keyword
        shared.append(Box(f"m:{m}", (printer.definition(measures[m]).removeprefix("measure "),), "measure"))
    size = sum(len(boxes) for _, boxes in clusters) + len(shared) + len(edges)
    if size > limit:
        _too_big(f"{size:,} boxes and arrows for the {len(chosen):,} rules", spec, fmt, limit)
    return RuleGraph(tuple(clusters), tuple(shared), tuple(edges))


def _between(
    rules: RuleSet, drawn: list[str], conflicts: Iterable[tuple[str, str, str]] | None, fmt: str, limit: int
) -> list[Edge]:
    """The edges between the rules ``drawn``: declared priorities, then ``conflicts`` (by
    default the quick pairwise check among them, refused past ``limit``)."""
    names = set(drawn)
    prio = Priorities.build((r.name for r in rules.rules), pairs(rules.spec))
    edges = [Edge(h, low, "priority", "over") for h, low in prio.declared if h in names and low in names]
    if conflicts is None:  # among the rules drawn only, and no more than the picture can hold
        found = possible_conflicts(rules, prio, among=names, limit=limit + 1)
        if len(found) > limit:
            what = f"more than {limit:,} possible conflicts between the {len(drawn):,} rules"
            _too_big(what, rules.spec, fmt, limit)
        conflicts = [(*c.rules, c.event) for c in found]
    seen: set[tuple[str, str, str]] = set()
    for a, b, label in conflicts:
        if a in names and b in names and a != b and (a, b, label) not in seen:
            seen.add((a, b, label))
            edges.append(Edge(a, b, "conflict", label))
    return edges


def _too_big(what: str, spec: A.Specification, fmt: str, limit: int) -> NoReturn:
    """Refuse a picture larger than ``fmt`` holds, with the limit and the way out."""
    raise UserError(
        f"the picture would need {what}: more than a picture in {fmt.upper()} holds "
        f"(at most {limit:,} boxes and arrows)",
        where=spec.path,
        hint="draw fewer rules with --rule R (repeatable), or declare priorities between the rules"
        + ("" if fmt in ("dot", "mmd") else f"; DOT or Mermaid text holds up to {MAX_SIZE['dot']:,}"),
    )


def _texts(printer: Printer, ast: A.Rule) -> tuple[str, str, list[str]]:
    """A rule's trigger, default response and clauses as the printer writes them (the
    printer recurses once per level of an expression: :func:`deeply` runs this)."""
    head, _ = printer.response_parts(A.Response(ast.response.items, ()))
    return printer.trigger(ast.trigger), head, [printer.defeater(d) for d in ast.response.defeaters]


CONFLICT_CHECKS = ("runtime-conflict", "situational-conflict", "vacuous-conflict")
"""The ``cosleec analyse`` checks whose findings :func:`analysed_conflicts` draws."""


ANALYSIS_S = 60.0
"""Seconds :func:`analysed_conflicts` gives ``cosleec analyse`` (its ``--deadline``)."""


def analysed_conflicts(
    path: str, settings: Settings | None = None, seconds: float = ANALYSIS_S
) -> list[tuple[str, str, str]]:
    """The conflicts ``cosleec analyse`` finds in the rule file ``path`` (z3; seconds per
    file), as red edges: each pair of rules a finding involves, labelled with its check and
    proof (``runtime-conflict, proved``). UserError when the analysis does not finish
    within ``seconds``: a picture missing conflicts would say there are none."""
    report = analyse_file(path, settings or Settings(), CONFLICT_CHECKS, deadline=Deadline.after(seconds))
    if not report.complete:
        raise UserError(
            f"cosleec analyse did not finish within {seconds:g} s, so the conflicts it proves cannot all be "
            "drawn",
            where=path,
            hint="draw without --analyse (the quick pairwise check), or draw fewer rules in a file of their "
            "own; `cosleec analyse --deadline S FILE` shows how far it gets",
        )
    out = []
    for f in report.findings:
        involved = [r for r in f.rules if not r.startswith("relation ")]
        label = f"{f.code}, {f.proof}"
        for i, a in enumerate(involved):
            for b in involved[i + 1 :]:
                out.append((a, b, label))
    return out


# ---------------------------------------------------------------------------- Graphviz

_NODE_STYLE = {
    "rule": 'shape=box, style="filled", fillcolor="#fff7e0"',
    "layer": 'shape=box, style="rounded,filled", fillcolor="#e8f4ea"',
    "event": 'shape=ellipse, style="filled", fillcolor="#e8f0fe"',
    "measure": 'shape=hexagon, style="filled", fillcolor="#f3e8fd"',
}
_EDGE_STYLE = {
    "triggers": 'color="#1a73e8"',
    "reads": 'color="#8e24aa", style=dotted, arrowhead=none',
    "obliges": 'color="#188038"',
    "forbids": 'color="#188038", style=dashed, arrowhead=tee',
    "layer": 'color="#5f6368", style=dashed, label="unless"',
    "priority": 'color="#1a73e8", penwidth=2, constraint=false',
    "conflict": 'color="#d93025", penwidth=2, constraint=false, dir=both',
}


def _q(text: str) -> str:
    """A DOT string literal (JSON's escaping is DOT's for quotes and backslashes)."""
    return json.dumps(text, ensure_ascii=False)


def _label(lines: Iterable[str]) -> str:
    return _q("\n".join(lines))


def to_dot(g: RuleGraph, title: str = "") -> str:
    """The picture as Graphviz DOT: a cluster per rule, shared event and measure nodes, a legend."""
    out = [
        "digraph sleec {",
        '  graph [rankdir=LR, fontname="Helvetica", fontsize=11, newrank=true'
        + (f", label={_q(title)}, labelloc=t" if title else "")
        + "];",
        '  node [fontname="Helvetica", fontsize=10];',
        '  edge [fontname="Helvetica", fontsize=9];',
    ]
    for i, (rule, boxes) in enumerate(g.clusters):
        out.append(f"  subgraph cluster_{i} {{")
        out.append(f'    label={_q(rule)}; style="rounded"; color="#bdc1c6";')
        for b in boxes:
            out.append(f"    {_q(b.id)} [label={_label(b.lines)}, {_NODE_STYLE[b.kind]}];")
        out.append("  }")
    for b in g.shared:
        out.append(f"  {_q(b.id)} [label={_label(b.lines)}, {_NODE_STYLE[b.kind]}];")
    for e in g.edges:
        label = f", label={_q(e.label)}" if e.label else ""
        out.append(f"  {_q(e.src)} -> {_q(e.dst)} [{_EDGE_STYLE[e.kind]}{label}];")
    out += _legend()
    out.append("}")
    return "\n".join(out) + "\n"


def _legend() -> list[str]:
    rows = [
        ("event", "event"),
        ("measure", "measure"),
        ("rule: trigger and default response (the base)", "rule"),
        ("layer: an unless clause", "layer"),
    ]
    out = ["  subgraph cluster_legend {", '    label="legend"; style="dashed"; color="#bdc1c6";']
    for i, (text, kind) in enumerate(rows):
        out.append(f'    "legend:{i}" [label={_q(text)}, {_NODE_STYLE[kind]}];')
    arrows = [
        ("triggers", "triggers"),
        ("obliges", "obliges"),
        ("forbids", "forbids"),
        ("reads", "reads"),
        ("priority", "priority (higher to lower)"),
        ("conflict", "can conflict (no priority)"),
    ]
    for i, (kind, text) in enumerate(arrows):
        out.append(f'    "legend:a{i}" [label="", shape=point, width=0.05];')
        out.append(f'    "legend:b{i}" [label={_q(text)}, shape=plaintext];')
        out.append(f'    "legend:a{i}" -> "legend:b{i}" [{_EDGE_STYLE[kind]}];')
    out.append("  }")
    return out


def render(dot: str, fmt: str) -> bytes:
    """``dot`` drawn by Graphviz as ``svg`` or ``png``; UserError when Graphviz is missing or fails."""
    exe = shutil.which("dot")
    if exe is None:
        raise UserError(
            "drawing SVG or PNG needs Graphviz's `dot`, which is not installed",
            hint="install it (`apt-get install graphviz`; `bash scripts/setup` does, as root), "
            "or write `-o FILE.dot` or `-o FILE.mmd`",
        )
    try:
        done = subprocess.run(
            [exe, f"-T{fmt}"], input=dot.encode(), capture_output=True, timeout=300, check=False
        )
    except subprocess.TimeoutExpired:
        raise UserError(
            "Graphviz took over 5 minutes to lay the picture out", hint="draw fewer rules with --rule"
        ) from None
    if done.returncode != 0:
        raise UserError(f"Graphviz failed: {done.stderr.decode(errors='replace').strip()[:500]}")
    return done.stdout


# ---------------------------------------------------------------------------- Mermaid

_MERMAID_ARROW = {
    "triggers": "-->|triggers|",
    "reads": "-.-",
    "obliges": "-->",
    "forbids": "-.->|forbids|",
    "layer": "-.->|unless|",
    "priority": "==>|over|",
    "conflict": "x--x",
}


def to_mermaid(g: RuleGraph) -> str:
    """The picture as Mermaid ``flowchart`` text (for Markdown: GitHub, MkDocs)."""
    ids: dict[str, str] = {}

    def mid(x: str) -> str:
        return ids.setdefault(x, f"n{len(ids)}")

    def text(lines: Iterable[str]) -> str:
        body = "<br/>".join(line.replace('"', "#quot;") for line in lines)
        return f'"{body}"'

    shape = {"rule": ("[", "]"), "layer": ("(", ")"), "event": ("([", "])"), "measure": ("{{", "}}")}
    out = ["flowchart LR"]
    for rule, boxes in g.clusters:
        out.append(f"  subgraph {mid('cluster:' + rule)} [{text([rule])}]")
        for b in boxes:
            a, z = shape[b.kind]
            out.append(f"    {mid(b.id)}{a}{text(b.lines)}{z}")
        out.append("  end")
    for b in g.shared:
        a, z = shape[b.kind]
        out.append(f"  {mid(b.id)}{a}{text(b.lines)}{z}")
    styles: list[str] = []
    for i, e in enumerate(g.edges):
        arrow = _MERMAID_ARROW[e.kind]
        if e.kind == "conflict":
            arrow = f"x--x|{e.label}|" if e.label else arrow
            styles.append(f"  linkStyle {i} stroke:#d93025,stroke-width:2px")
        out.append(f"  {mid(e.src)} {arrow} {mid(e.dst)}")
    return "\n".join(out + styles) + "\n"
