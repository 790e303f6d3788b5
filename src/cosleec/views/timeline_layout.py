"""Where each mark of a :class:`~cosleec.views.timeline.Timeline` goes, and in which colour.

Both renderers -- matplotlib (:mod:`cosleec.views.timeline_plot`) and Plotly
(:mod:`cosleec.views.timeline_html`) -- draw the same :class:`Layout`, so a PNG and the
HTML of one run agree mark for mark. From top to bottom:

- one small step plot per measure (true/false, a number, or a scale's literals in the
  order the run met them; a gap while the value is unknown);
- the run's lane: triggers as ticks, rejections, and notes about the whole run (a
  semantics switch, a reload, a new run -- also drawn as a dashed line across the rules);
- one lane per rule the run involved: its active layer as a coloured band behind (none
  at the default, grey ``?`` when undetermined); a row of markers (decisions with their
  clause, ``otherwise`` fallbacks, refusals, conflicts, cancellations, held decisions,
  failed tasks); under it, each obligation as a bar from its trigger to its deadline,
  coloured by outcome, with a dot when it was settled and a diamond at a late event; an
  arrow from a missed obligation to each obligation its ``otherwise`` put in force.

What would be unreadable is capped, and the picture says so in a note: at most
:data:`MAX_RULES` rule lanes (a run of a large rule set involves only the rules that
fired; past the cap, the busiest rules are drawn), :data:`MAX_MEASURES` measures (those
that changed most), :data:`MAX_ROWS` rows of bars a lane (overlapping bars share the last
row). Bars are packed into rows so that bars of one rule do not cover each other.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from cosleec.views.timeline import Timeline
from cosleec.views.timeline_marks import (
    Band,
    Bar,
    Link,
    Marker,
    MarkerKind,
    Outcome,
    Series,
    Value,
    natural,
)

TIMELINE_FORMATS = ("png", "svg", "html")
"""What a timeline is drawn as: PNG and SVG by matplotlib, HTML by Plotly (by the output's extension)."""

MAX_RULES = 30
"""Rule lanes a picture holds; past it, the rules with the most marks are drawn."""

MAX_MEASURES = 10
"""Measure plots a picture holds; past it, the measures that changed most are drawn."""

MAX_ROWS = 4
"""Rows of obligation bars a rule lane holds; past it, bars overlap in the last row."""

OUTCOME_COLOURS: Mapping[Outcome, str] = {
    Outcome.FULFILLED: "#2e7d32",
    Outcome.RESPECTED: "#81c784",
    Outcome.VIOLATED: "#c62828",
    Outcome.LATE: "#ef6c00",
    Outcome.BLOCKED: "#6a1b9a",
    Outcome.CONFLICT: "#d81b60",
    Outcome.CANCELLED: "#795548",
    Outcome.PENDING: "#90a4ae",
    Outcome.WITHDRAWN: "#cfd8dc",
    Outcome.OTHER: "#424242",
}
"""The colour of a bar of each outcome (the same in every format)."""

LAYER_COLOURS = ("#bbdefb", "#ffe0b2", "#d1c4e9", "#c8e6c9", "#f8bbd0", "#b2ebf2", "#fff59d")
"""Band colours for clause 1, 2, ... (cycling); an undetermined band is :data:`UNDETERMINED_COLOUR`."""

UNDETERMINED_COLOUR = "#e0e0e0"


@dataclass(frozen=True, slots=True)
class Style:
    """How a marker kind is drawn: a matplotlib marker, a Plotly symbol, a colour, a legend name."""

    mpl: str
    plotly: str
    colour: str
    name: str


MARKER_STYLES: Mapping[MarkerKind, Style] = {
    MarkerKind.TRIGGER: Style("|", "line-ns-open", "#37474f", "trigger (event)"),
    MarkerKind.DECISION: Style("o", "circle", "#1565c0", "decision (default or layer)"),
    MarkerKind.UNDETERMINED: Style("d", "diamond", "#757575", "decision, undetermined"),
    MarkerKind.OTHERWISE: Style(">", "triangle-right", "#ef6c00", "otherwise (fallback)"),
    MarkerKind.REFUSED: Style("s", "square", "#6a1b9a", "request refused"),
    MarkerKind.REJECTED: Style("x", "x", "#c62828", "rejected input"),
    MarkerKind.CONFLICT: Style("*", "star", "#d81b60", "conflict"),
    MarkerKind.CANCELLED: Style("v", "triangle-down", "#795548", "cancelled by priority"),
    MarkerKind.HELD: Style("h", "hexagon", "#f9a825", "decision held"),
    MarkerKind.WITHHELD: Style("H", "hexagon-open", "#9e9e9e", "decision withheld"),
    MarkerKind.TASK_FAILED: Style("X", "x-thin-open", "#b71c1c", "task failed"),
    MarkerKind.TASK_INTERRUPTED: Style("P", "cross", "#b71c1c", "task interrupted"),
    MarkerKind.NOTE: Style("^", "triangle-up", "#455a64", "about the run"),
}
"""Each marker kind's look, in both renderers."""

ROW = 1.0
"""The height of one row of a rule lane (the marker row, then each row of bars), in lane units."""


@dataclass(frozen=True, slots=True)
class Lane:
    """Rule ``rule``'s lane: from ``top`` down ``rows + 1`` rows (markers, then bars); y grows downwards."""

    rule: str
    top: float
    rows: int

    @property
    def bottom(self) -> float:
        """Where the lane ends (the next one starts)."""
        return self.top + (self.rows + 1) * ROW

    @property
    def marker_y(self) -> float:
        """The centre of the marker row."""
        return self.top + ROW / 2

    def row_y(self, row: int) -> float:
        """The centre of bar row ``row`` (0 is the first under the markers)."""
        return self.top + (row + 1.5) * ROW


@dataclass(frozen=True, kw_only=True)
class Layout:
    """What is drawn and where: the lanes, the chosen measures, each bar's y, the x range, notes."""

    timeline: Timeline
    title: str
    lanes: tuple[Lane, ...]
    measures: tuple[Series, ...]
    bands: tuple[Band, ...]
    bars: tuple[Bar, ...]
    bar_y: Mapping[tuple[int, int], float]
    links: tuple[Link, ...]
    markers: tuple[Marker, ...]  # on rule lanes
    run_marks: tuple[Marker, ...]  # on the run's lane
    x_range: tuple[float, float]
    min_width: float  # the shortest a bar is drawn, in seconds (so an instant shows)
    notes: tuple[str, ...]

    def lane(self, rule: str) -> Lane:
        """The lane of ``rule`` (KeyError when it is not drawn)."""
        for lane in self.lanes:
            if lane.rule == rule:
                return lane
        raise KeyError(rule)

    @property
    def depth(self) -> float:
        """The height of all rule lanes, in lane units."""
        return self.lanes[-1].bottom if self.lanes else ROW

    def outcomes(self) -> list[Outcome]:
        """The outcomes the drawn bars have, in legend order."""
        present = {b.outcome for b in self.bars}
        return [o for o in OUTCOME_COLOURS if o in present]

    def marker_kinds(self) -> list[MarkerKind]:
        """The marker kinds drawn, in legend order."""
        present = {m.kind for m in (*self.markers, *self.run_marks)}
        return [k for k in MARKER_STYLES if k in present]


def layout(
    tl: Timeline, *, max_rules: int = MAX_RULES, max_measures: int = MAX_MEASURES, max_rows: int = MAX_ROWS
) -> Layout:
    """Lay ``tl`` out: choose the lanes and measures (capped, with a note), pack the bars in rows."""
    notes: list[str] = []
    rules = _busiest(tl, max_rules, notes)
    shown = set(rules)
    measures = list(tl.series)
    if len(measures) > max_measures:
        kept = {s.name for s in sorted(measures, key=lambda s: (-s.changes, natural(s.name)))[:max_measures]}
        notes.append(
            f"{len(measures) - max_measures} more measures changed; the {max_measures} that changed most are drawn"
        )
        measures = [s for s in measures if s.name in kept]
    lo, hi = tl.start, tl.end
    span = max(hi - lo, 1.0)
    min_width = span * 0.004
    bars = [b for b in tl.bars if b.rule in shown]
    lanes: list[Lane] = []
    bar_y: dict[tuple[int, int], float] = {}
    top = 0.0
    overlapped = 0
    for rule in rules:
        mine = sorted((b for b in bars if b.rule == rule), key=lambda b: (b.start, b.end, b.key))
        rows, overlaps = _pack(mine, min_width, span * 0.002, max_rows)
        overlapped += overlaps
        lane = Lane(rule, top, max(rows.values(), default=-1) + 1)
        for b in mine:
            bar_y[b.key] = lane.row_y(rows[b.key])
        lanes.append(lane)
        top = lane.bottom
    if overlapped:
        notes.append(f"{overlapped} obligation bars overlap others (a lane holds {max_rows} rows)")
    if tl.ignored:
        kinds = ", ".join(f"{k} ({n})" for k, n in sorted(tl.ignored.items()))
        notes.append(f"records of kinds this version does not know were left out: {kinds}")
    if tl.runs > 1:
        notes.append(f"the records hold {tl.runs} runs (each starts at a dashed line 'new run')")
    return Layout(
        timeline=tl,
        title=_title(tl),
        lanes=tuple(lanes),
        measures=tuple(measures),
        bands=tuple(b for b in tl.bands if b.rule in shown),
        bars=tuple(bars),
        bar_y=bar_y,
        links=tuple(lk for lk in tl.links if lk.parent in bar_y and lk.child in bar_y),
        markers=tuple(m for m in tl.markers if m.rule in shown),
        run_marks=tuple(m for m in tl.markers if m.rule is None),
        x_range=(lo - span * 0.03, hi + span * 0.1),
        min_width=min_width,
        notes=tuple(notes),
    )


def _busiest(tl: Timeline, max_rules: int, notes: list[str]) -> list[str]:
    """The rules that get a lane: those with a mark, at most ``max_rules`` (the busiest, noted)."""
    activity: Counter[str] = Counter()
    for b in tl.bars:
        activity[b.rule] += 1
    for m in tl.markers:
        if m.rule is not None:
            activity[m.rule] += 1
    for band in tl.bands:
        activity[band.rule] += 1
    rules = [r for r in tl.rules if activity[r]]
    if len(rules) > max_rules:
        kept = set(sorted(rules, key=lambda r: (-activity[r], natural(r)))[:max_rules])
        notes.append(
            f"{len(rules) - max_rules} more rules took part; the {max_rules} with the most marks are drawn"
        )
        rules = [r for r in rules if r in kept]
    return rules


def _pack(
    bars: Sequence[Bar], min_width: float, gap: float, max_rows: int
) -> tuple[dict[tuple[int, int], int], int]:
    """Each bar's row: the first whose last bar ended (plus ``gap``) before it starts; past
    ``max_rows`` rows, the row free soonest. Returns the rows and how many bars overlap."""
    free: list[float] = []  # per row: where its last bar ends, gap included
    out: dict[tuple[int, int], int] = {}
    overlaps = 0
    for b in bars:
        end = max(b.end, b.start + min_width) + gap
        row = next((i for i, f in enumerate(free) if f <= b.start), None)
        if row is None and len(free) < max_rows:
            row = len(free)
            free.append(end)
        elif row is None:
            row = min(range(len(free)), key=lambda i: free[i])
            overlaps += 1
            free[row] = max(free[row], end)
        else:
            free[row] = end
        out[b.key] = row
    return out, overlaps


def _title(tl: Timeline) -> str:
    name = Path(tl.source).name if tl.source else "run"
    o = tl.options
    how = f", {o['semantics']}" if "semantics" in o else ""
    if o.get("priorities"):
        how += f", priorities {o.get('priority_semantics', '')}".rstrip()
    return f"{name}: {len(tl.rules)} rules, {len(tl.bars)} obligations, t = {tl.start:g} to {tl.end:g} s{how}"


def ink(colour: str) -> str:
    """Black or white: whichever reads better on ``colour`` (``#rrggbb``)."""
    r, g, b = (int(colour[i : i + 2], 16) for i in (1, 3, 5))
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 150 else "white"


def band_colour(band: Band) -> str:
    """The colour of a layer band: by its clause (grey when undetermined)."""
    clause = band.clause
    if clause is None:
        return UNDETERMINED_COLOUR
    return LAYER_COLOURS[(clause - 1) % len(LAYER_COLOURS)]


def steps(series: Series, end: float) -> tuple[list[float], list[float | None], list[tuple[float, str]]]:
    """A measure as a step line to draw: x, y (None where unknown: a gap) and the y ticks.

    True/false is 1/0, a number itself, a scale literal (or any text) its place among the
    values the run met, in order. Each value holds until the next point, the last until ``end``.
    """
    values = [v for _, v in series.points if v is not None]
    if values and all(isinstance(v, bool) for v in values):
        ticks = [(0.0, "false"), (1.0, "true")]

        def y(v: Value) -> float:
            return float(bool(v))

    elif values and all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        ticks = []

        def y(v: Value) -> float:
            return float(v)

    else:
        levels = list(dict.fromkeys(str(v) for v in values))
        ticks = [(float(i), text) for i, text in enumerate(levels)]

        def y(v: Value) -> float:
            return float(levels.index(str(v)))

    xs: list[float] = []
    ys: list[float | None] = []
    for i, (t, v) in enumerate(series.points):
        nxt = series.points[i + 1][0] if i + 1 < len(series.points) else max(end, t)
        value = None if v is None else y(v)
        xs += [t, nxt]
        ys += [value, value]
    return xs, ys, ticks


def cluster(marks: Sequence[Marker], span: float, buckets: int = 200) -> list[tuple[float, str]]:
    """Labels of ``marks`` that would print over one another (one lane, within 1/``buckets`` of
    the span) joined into one: ``(time, "R1 default, R1.1 +2")``."""
    groups: dict[int, list[Marker]] = {}
    for m in marks:
        groups.setdefault(round(m.time / span * buckets) if span else 0, []).append(m)
    out = []
    for group in groups.values():
        labels = list(dict.fromkeys(m.label for m in group))
        text = ", ".join(labels[:3]) + (f" +{len(labels) - 3}" if len(labels) > 3 else "")
        out.append((group[0].time, text))
    return out
