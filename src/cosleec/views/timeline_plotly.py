"""A run's timeline as one self-contained interactive HTML page, drawn by Plotly.

The same :class:`~cosleec.views.timeline_layout.Layout` as the still picture, for long
runs: drag to zoom into a stretch of time (the measures and lanes follow; a double click
shows everything again, past the run's end too, where late deadlines lie), scroll to
zoom, and hover over any mark for all it says -- a decision's clause and explanation, an
obligation's window, outcome and when it was settled, a layer's interval. Plotly's
JavaScript is inlined, so the page opens with no network, and the plot's id is fixed, so
one run gives one page. What is inlined is plotly.js's *basic* bundle (scatter and bar
plots: all a timeline draws; ``static/plotly-basic.min.js``, MIT, published on npm as
``plotly.js-basic-dist-min``), about 1.2 MB instead of the whole library's 4.8 MB; when
the installed Plotly bundles another major version of plotly.js than that one, the whole
library is inlined as before. Needs the ``timeline`` extra (``pip install 'cosleec[timeline]'``).
"""

from __future__ import annotations

import re
from importlib import resources
from typing import Any

from cosleec.errors import UserError
from cosleec.views.timeline import Timeline
from cosleec.views.timeline_layout import (
    MARKER_STYLES,
    OUTCOME_COLOURS,
    ROW,
    Layout,
    band_colour,
    layout,
    steps,
)
from cosleec.views.timeline_marks import Band, Bar, Marker, MarkerKind, Outcome

DIV_ID = "cosleec-timeline"
"""The id of the plot's element in the page (fixed: the same run gives the same page)."""

BUNDLE = "plotly-basic.min.js"
"""plotly.js's basic bundle (scatter, bar, pie), in ``static/``: what the page inlines."""


def timeline_html(tl: Timeline) -> str:
    """``tl`` as a complete HTML page that needs no network; UserError when Plotly is missing."""
    try:
        from plotly import graph_objects as go
        from plotly.subplots import make_subplots
    except ModuleNotFoundError as e:
        raise UserError(
            f"drawing a timeline as HTML needs Plotly ({e.name} is missing)",
            hint="pip install 'cosleec[timeline]'",
        ) from None
    lay = layout(tl)
    n = len(lay.measures)
    heights = [60.0] * n + [80.0, max(120.0, lay.depth * 28.0)]
    fig = make_subplots(
        rows=len(heights), cols=1, shared_xaxes=True, vertical_spacing=12 / sum(heights), row_heights=heights
    )
    _measures(fig, go, lay)
    _run_lane(fig, go, lay, n + 1)
    _rules(fig, go, lay, n + 2)
    title = lay.title + "".join(f"<br><sub>note: {note}</sub>" for note in lay.notes)
    fig.update_layout(
        title={"text": title, "x": 0.01, "font": {"size": 14}},
        height=int(sum(heights) + 110 + 18 * len(lay.notes)),
        barmode="overlay",
        hovermode="closest",
        plot_bgcolor="white",
        margin={"l": 120, "r": 260, "t": 80 + 18 * len(lay.notes), "b": 50},
        legend={"x": 1.01, "y": 1, "xanchor": "left", "yanchor": "top", "font": {"size": 10}},
    )
    fig.update_xaxes(range=list(lay.x_range), showgrid=True, gridcolor="#eeeeee")
    fig.update_xaxes(title={"text": "runtime clock (s)"}, row=len(heights), col=1)
    return _page(fig, {"scrollZoom": True, "displaylogo": False, "responsive": True})


def _page(fig: Any, config: dict[str, Any]) -> str:
    """The page of ``fig`` with the basic bundle inlined (the whole library when the installed
    Plotly bundles another major version of plotly.js than the basic bundle's)."""
    from plotly.offline import get_plotlyjs_version

    bundle = resources.files("cosleec.views").joinpath("static", BUNDLE).read_text(encoding="utf-8")
    ours = re.search(r"plotly\.js \(basic - minified\) v(\d+)\.", bundle[:300])
    if ours is None or ours[1] != get_plotlyjs_version().split(".")[0]:
        whole: str = fig.to_html(include_plotlyjs=True, full_html=True, div_id=DIV_ID, config=config)
        return whole
    html: str = fig.to_html(include_plotlyjs=False, full_html=True, div_id=DIV_ID, config=config)
    safe = bundle.replace("</script", "<\\/script")  # (it holds none: a newer one might)
    script = f'<script charset="utf-8" type="text/javascript">{safe}</script>'
    return html.replace("<body>", f"<body>\n{script}", 1)


def _text(v: object) -> str:
    return ("true" if v else "false") if isinstance(v, bool) else str(v)


def _measures(fig: Any, go: Any, lay: Layout) -> None:
    """One step plot per measure (rows 1..n), its name in its top left corner."""
    for i, series in enumerate(lay.measures, start=1):
        xs, ys, ticks = steps(series, lay.timeline.end)
        shown = [v for _, v in series.points for _ in (0, 1)]
        fig.add_trace(
            go.Scatter(
                x=xs,
                y=ys,
                mode="lines+markers",
                marker={"size": 4},
                line={"color": "#00695c", "width": 1.6},
                name=series.name,
                showlegend=False,
                connectgaps=False,
                customdata=["unknown" if v is None else _text(v) for v in shown],
                hovertemplate=f"{series.name} = %{{customdata}} from t = %{{x}} s<extra></extra>",
            ),
            row=i,
            col=1,
        )
        axis: dict[str, Any] = {"zeroline": False, "nticks": 3, "tickfont": {"size": 9}}
        if ticks:
            axis |= {"tickvals": [y for y, _ in ticks], "ticktext": [t for _, t in ticks]}
            axis["range"] = [ticks[0][0] - 0.35, ticks[-1][0] + 0.35]
        fig.update_yaxes(axis, row=i, col=1)
        fig.add_annotation(
            text=f"<b>{series.name}</b>",
            xref="x domain" if i == 1 else f"x{i} domain",
            yref="y domain" if i == 1 else f"y{i} domain",
            x=0.005,
            y=1.0,
            xanchor="left",
            yanchor="top",
            showarrow=False,
            font={"size": 10, "color": "#004d40"},
            bgcolor="rgba(255,255,255,0.7)",
        )


def _run_lane(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """Triggers, rejections and notes about the whole run, on one line."""
    by_kind: dict[MarkerKind, list[Marker]] = {}
    for m in lay.run_marks:
        by_kind.setdefault(m.kind, []).append(m)
    for kind, marks in by_kind.items():
        style = MARKER_STYLES[kind]
        size = 14 if kind == MarkerKind.TRIGGER else 9
        fig.add_trace(
            go.Scatter(
                x=[m.time for m in marks],
                y=[0] * len(marks),
                mode="markers",
                marker={
                    "symbol": style.plotly,
                    "color": style.colour,
                    "size": size,
                    "line": {"width": 2, "color": style.colour},
                },
                name=style.name,
                legendgroup=kind.value,
                hovertext=[f"t = {m.time:g} s: {m.detail}" for m in marks],
                hoverinfo="text",
            ),
            row=row,
            col=1,
        )
    fig.update_yaxes(
        tickvals=[0], ticktext=["run"], range=[-1, 1], showgrid=False, zeroline=False, row=row, col=1
    )


def _rules(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """The rule lanes: bands, bars, otherwise arrows and marks, one lane per rule."""
    _bands(fig, go, lay, row)
    _bars(fig, go, lay, row)
    _links(fig, go, lay, row)
    _marks(fig, go, lay, row)
    for m in lay.run_marks:
        if m.kind == MarkerKind.NOTE:
            fig.add_vline(x=m.time, line={"color": "#455a64", "dash": "dash", "width": 1}, row=row, col=1)
    for lane in lay.lanes:
        fig.add_hline(y=lane.bottom, line={"color": "#e0e0e0", "width": 1}, row=row, col=1)
    fig.update_yaxes(
        tickvals=[(lane.top + lane.bottom) / 2 for lane in lay.lanes],
        ticktext=[lane.rule for lane in lay.lanes],
        range=[lay.depth, 0],
        showgrid=False,
        zeroline=False,
        row=row,
        col=1,
    )


def _bands(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """Each active layer as a band behind its lane: one trace (a legend entry) per clause number."""
    by_clause: dict[int | None, list[Band]] = {}
    for band in lay.bands:
        by_clause.setdefault(band.clause, []).append(band)
    for clause, bands in sorted(by_clause.items(), key=lambda kv: -1 if kv[0] is None else kv[0]):
        lanes = [lay.lane(b.rule) for b in bands]
        fig.add_trace(
            go.Bar(
                orientation="h",
                base=[b.start for b in bands],
                x=[b.end - b.start for b in bands],
                y=[(lane.top + lane.bottom) / 2 for lane in lanes],
                width=[lane.bottom - lane.top for lane in lanes],
                marker={"color": band_colour(bands[0]), "line": {"width": 0}},
                opacity=0.6,
                name="layer undetermined (?)" if clause is None else f"layer of clause {clause}",
                legendgroup=f"layer{clause}",
                hovertext=[
                    f"{b.rule}: layer {b.layer} active from {b.start:g} to {b.end:g} s" for b in bands
                ],
                hoverinfo="text",
            ),
            row=row,
            col=1,
        )


def _bars(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """Each obligation's bar (one trace per outcome), when it was settled, and late events."""
    by_outcome: dict[Outcome, list[Bar]] = {}
    for b in lay.bars:
        by_outcome.setdefault(b.outcome, []).append(b)
    for outcome in lay.outcomes():
        bars = by_outcome[outcome]
        colour = OUTCOME_COLOURS[outcome]
        marker: dict[str, Any] = {"color": colour, "line": {"color": colour, "width": 1}}
        if outcome == Outcome.PENDING:
            marker |= {"color": "white", "pattern": {"shape": "/", "fgcolor": colour}}
        fig.add_trace(
            go.Bar(
                orientation="h",
                base=[b.start for b in bars],
                x=[max(b.end - b.start, lay.min_width) for b in bars],
                y=[lay.bar_y[b.key] for b in bars],
                width=0.62 * ROW,
                marker=marker,
                name=f"obligation {outcome.value}",
                legendgroup=f"o-{outcome.value}",
                text=[b.label for b in bars],
                textposition="inside",
                insidetextanchor="start",
                textfont={"size": 9},
                hovertext=[_bar_text(b) for b in bars],
                hoverinfo="text",
            ),
            row=row,
            col=1,
        )
    _settled(fig, go, lay, row)


def _settled(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """A tick when each obligation was settled, a diamond at each late event."""
    settled = [b for b in lay.bars if b.at is not None]
    late = [b for b in lay.bars if b.late is not None]
    points = (
        (
            "settled at",
            settled,
            [b.at for b in settled],
            {"symbol": "line-ns-open", "size": 12, "color": "black", "line": {"width": 2}},
            [f"#{b.id} {b.status} at {b.at:g} s" for b in settled],
        ),
        (
            "late event",
            late,
            [b.late for b in late],
            {
                "symbol": "diamond",
                "size": 9,
                "color": OUTCOME_COLOURS[Outcome.LATE],
                "line": {"width": 1, "color": "black"},
            },
            [f"#{b.id}: {b.event} came late, at {b.late:g} s" for b in late],
        ),
    )
    for name, which, xs, marker, texts in points:
        if which:
            fig.add_trace(
                go.Scatter(
                    x=xs,
                    y=[lay.bar_y[b.key] for b in which],
                    mode="markers",
                    marker=marker,
                    name=name,
                    hovertext=texts,
                    hoverinfo="text",
                ),
                row=row,
                col=1,
            )


def _links(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """A dotted arrow from each missed obligation (when it was missed) to each its otherwise started."""
    if not lay.links:
        return
    xs: list[float | None] = []
    ys: list[float | None] = []
    texts: list[str] = []
    for link in lay.links:
        parent, child = lay.timeline.bar(link.parent), lay.timeline.bar(link.child)
        start = parent.at if parent.at is not None else parent.end
        xs += [start, child.start, None]
        ys += [lay.bar_y[parent.key], lay.bar_y[child.key], None]
        words = f"otherwise: #{parent.id} {parent.event} missed at {start:g} s → #{child.id} {child.label}"
        texts += [words, words, ""]
    fig.add_trace(
        go.Scatter(
            x=xs,
            y=ys,
            mode="lines+markers",
            line={"color": "#e65100", "width": 2, "dash": "dot"},
            marker={"symbol": "triangle-right", "size": 8, "color": "#e65100"},
            name="otherwise: missed → fallback",
            hovertext=texts,
            hoverinfo="text",
        ),
        row=row,
        col=1,
    )


def _marks(fig: Any, go: Any, lay: Layout, row: int) -> None:
    """Decisions and the rest on each lane's top row: one trace per kind, all said on hover."""
    by_kind: dict[MarkerKind, list[Marker]] = {}
    for m in lay.markers:
        by_kind.setdefault(m.kind, []).append(m)
    for kind, marks in by_kind.items():
        style = MARKER_STYLES[kind]
        fig.add_trace(
            go.Scatter(
                x=[m.time for m in marks],
                y=[lay.lane(str(m.rule)).marker_y for m in marks],
                mode="markers",
                marker={
                    "symbol": style.plotly,
                    "color": style.colour,
                    "size": 9,
                    "line": {"width": 1, "color": style.colour},
                },
                name=style.name,
                legendgroup=kind.value,
                hovertext=[f"t = {m.time:g} s, {m.rule}: {m.detail}".replace("\n", "<br>") for m in marks],
                hoverinfo="text",
            ),
            row=row,
            col=1,
        )


def _bar_text(b: Bar) -> str:
    window = (
        f"{b.start:g} to {b.deadline:g} s" if b.deadline is not None else f"from {b.start:g} s, no deadline"
    )
    lines = [
        f"{b.rule}: {b.label} ({'prohibition' if b.negated else 'obligation'})",
        f"window {window}",
        f"outcome {b.outcome.value}" + (f" (status {b.status})" if b.status != b.outcome.value else ""),
    ]
    if b.at is not None:
        lines.append(f"settled at {b.at:g} s")
    if b.late is not None:
        lines.append(f"late event at {b.late:g} s")
    where = "default" if b.clause == 0 else "undetermined" if b.clause is None else f"clause {b.clause}"
    lines.append(f"decision #{b.decision} ({where})" + (f", otherwise depth {b.depth}" if b.depth else ""))
    return "<br>".join(lines)
