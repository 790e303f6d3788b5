"""A run's timeline as a still picture, PNG or SVG, drawn by matplotlib (what the README shows).

The picture is the :class:`~cosleec.views.timeline_layout.Layout` of the run: measures on
top, the run's lane, then a lane per rule (see that module for what each mark means); a
legend names every outcome colour and marker drawn, and notes under the title say what
was left out. Labels that would print over one another are joined (``default, R1.1``) or
left out (the HTML's tooltips say all). matplotlib's Agg backend draws it off screen -- no
window, no display needed -- and the SVG is deterministic (fixed ids, no date, text kept
as text), so one run gives the same bytes every time. Needs the ``timeline`` extra
(``pip install 'cosleec[timeline]'``).
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING, Any

from cosleec.errors import UserError
from cosleec.views.timeline import Timeline
from cosleec.views.timeline_layout import (
    MARKER_STYLES,
    OUTCOME_COLOURS,
    Layout,
    band_colour,
    cluster,
    ink,
    layout,
    steps,
)
from cosleec.views.timeline_marks import MarkerKind, Outcome, Series

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

IMAGE_FORMATS = ("png", "svg")
"""What :func:`timeline_image` draws."""

WIDTH_IN = 14.0
"""The picture's width in inches (1400 pixels in a PNG)."""

LABELLED_MARKS = 60
"""Label clusters a lane shows at most; past it, the marks stand unlabelled (the HTML has tooltips)."""


def timeline_image(tl: Timeline, fmt: str) -> bytes:
    """``tl`` drawn as ``fmt`` (``png`` or ``svg``); UserError when matplotlib is missing."""
    if fmt not in IMAGE_FORMATS:
        raise ValueError(f"timeline_image draws {' or '.join(IMAGE_FORMATS)}, not {fmt!r}")
    try:
        import matplotlib

        matplotlib.use("Agg", force=True)  # never a window, even where a display is set
        from matplotlib import pyplot as plt
    except ModuleNotFoundError as e:
        raise UserError(
            f"drawing a timeline as {fmt.upper()} needs matplotlib ({e.name} is missing)",
            hint="pip install 'cosleec[timeline]'",
        ) from None
    lay = layout(tl)
    # fixed ids, and text as text (searchable, small): the same run gives the same SVG
    with matplotlib.rc_context({"svg.hashsalt": "cosleec-timeline", "svg.fonttype": "none", "font.size": 8}):
        fig = _figure(lay, plt)
        try:
            out = io.BytesIO()
            fig.savefig(out, format=fmt, dpi=100, metadata=_metadata(fmt))
        finally:
            plt.close(fig)
    return out.getvalue()


def _metadata(fmt: str) -> dict[str, Any]:
    """No date and a fixed creator: the same run gives the same file."""
    if fmt == "svg":
        return {"Date": None, "Creator": "cosleec timeline"}
    return {"Software": "cosleec timeline"}


def _figure(lay: Layout, plt: Any) -> Figure:
    n = len(lay.measures)
    heights = [0.55] * n + [0.9, max(1.0, lay.depth * 0.26)]
    head = 0.9 + 0.16 * len(lay.notes)
    fig: Figure = plt.figure(figsize=(WIDTH_IN, sum(heights) + head + 0.6))
    grid = fig.add_gridspec(len(heights), 1, height_ratios=heights, hspace=0.08)
    axes: list[Axes] = []
    for i in range(len(heights)):
        axes.append(fig.add_subplot(grid[i], sharex=axes[0] if axes else None))
    for ax, series in zip(axes, lay.measures):
        _measure(ax, lay, series)
    _run_lane(axes[n], lay)
    _rules(axes[n + 1], lay)
    for ax in axes[:-1]:
        ax.tick_params(labelbottom=False)
    axes[-1].set_xlabel("runtime clock (s)")
    axes[0].set_xlim(*lay.x_range)
    top = 1 - head / fig.get_figheight()
    fig.subplots_adjust(left=0.12, right=0.8, top=top, bottom=0.5 / fig.get_figheight())
    left = _room_for_names(fig, axes)
    fig.suptitle(lay.title, x=left, y=1 - 0.25 / fig.get_figheight(), ha="left", fontsize=11)
    for i, note in enumerate(lay.notes):
        fig.text(
            left, 1 - (0.55 + 0.16 * i) / fig.get_figheight(), f"note: {note}", fontsize=8, style="italic"
        )
    _legend(fig, lay)
    return fig


def _room_for_names(fig: Figure, axes: list[Axes]) -> float:
    """Widen the left margin until every name left of the plots (a measure's, a rule's lane)
    is drawn whole inside the picture -- ``batteryLowDeliveringUrgentMedication``, not
    ``veringUrgentMedication``; returns the left edge of the plots (a fraction of the width)."""
    left = float(fig.subplotpars.left)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    width = fig.get_figwidth() * fig.dpi
    boxes = [ax.get_tightbbox(renderer) for ax in axes]
    leftmost = min((b.x0 for b in boxes if b is not None), default=0.0)
    pad = 0.1 * fig.dpi
    if leftmost < pad:
        left = min(0.6, left + (pad - leftmost) / width)  # at most: the plots keep some room
        fig.subplots_adjust(left=left)
    return left


def _measure(ax: Axes, lay: Layout, series: Series) -> None:
    xs, ys, ticks = steps(series, lay.timeline.end)
    ax.plot(xs, [float("nan") if y is None else y for y in ys], color="#00695c", lw=1.4)
    known = [(x, y) for x, y in zip(xs[::2], ys[::2]) if y is not None]  # each change, so an instant shows
    ax.plot([x for x, _ in known], [y for _, y in known], ls="none", marker="o", ms=2.5, color="#00695c")
    ax.set_ylabel(series.name, rotation=0, ha="right", va="center", fontsize=8)
    if ticks:
        ax.set_yticks([y for y, _ in ticks], [t for _, t in ticks], fontsize=6)
        lo, hi = ticks[0][0], ticks[-1][0]
        ax.set_ylim(lo - 0.35, hi + 0.35)
    else:
        ax.tick_params(axis="y", labelsize=6)
        ax.margins(y=0.25)
    ax.grid(axis="x", color="#eeeeee", lw=0.6)


def _run_lane(ax: Axes, lay: Layout) -> None:
    ax.set_ylim(-1, 1)
    ax.set_yticks([0], ["run"])
    span = lay.x_range[1] - lay.x_range[0]
    by_kind: dict[Any, list[float]] = {}
    for m in lay.run_marks:
        by_kind.setdefault(m.kind, []).append(m.time)
    for kind, times in by_kind.items():
        style = MARKER_STYLES[kind]
        ax.scatter(
            times, [0] * len(times), marker=style.mpl, color=style.colour, s=90 if style.mpl == "|" else 30
        )
    labels = cluster(lay.run_marks, span)
    placed: list[list[tuple[float, float]]] = [[], [], []]
    if len(labels) <= LABELLED_MARKS:
        for i, (t, text) in enumerate(labels):  # three heights, so neighbours do not print over each other
            left = _near_right(lay, t)
            if not _room(placed[i % 3], t, text, left, span):
                continue
            ax.annotate(
                text,
                (t, 0),
                xytext=(-3 if left else 3, 9 - 9 * (i % 3)),
                textcoords="offset points",
                fontsize=6,
                va="center",
                ha="right" if left else "left",
                clip_on=True,
            )
    ax.grid(axis="x", color="#eeeeee", lw=0.6)


def _room(placed: list[tuple[float, float]], t: float, text: str, left: bool, span: float) -> bool:
    """Is there room on a line for ``text`` labelling time ``t`` (to its left or right), beside
    the labels ``placed`` there? If so it is placed. Widths are estimated, in seconds."""
    width = span * (0.0047 * len(text) + 0.006)
    x0, x1 = (t - width, t) if left else (t, t + width)
    if any(x0 < b and a < x1 for a, b in placed):
        return False
    placed.append((x0, x1))
    return True


def _near_right(lay: Layout, t: float) -> bool:
    """Is ``t`` in the right fifth of the picture (its label goes to the left, not off the edge)?"""
    lo, hi = lay.x_range
    return t > lo + (hi - lo) * 0.8


def _rules(ax: Axes, lay: Layout) -> None:
    """The rule lanes: bands, bars, otherwise arrows and marks, one lane per rule."""
    span = lay.x_range[1] - lay.x_range[0]
    _bands(ax, lay, span)
    _bars(ax, lay, span)
    _links(ax, lay)
    _marks(ax, lay, span)
    for m in lay.run_marks:
        if m.kind == MarkerKind.NOTE:
            ax.axvline(m.time, color="#455a64", ls="--", lw=0.8, zorder=2)
    ax.set_ylim(lay.depth, 0)
    ax.set_yticks([(lane.top + lane.bottom) / 2 for lane in lay.lanes], [lane.rule for lane in lay.lanes])
    ax.grid(axis="x", color="#eeeeee", lw=0.6, zorder=0)
    if not lay.lanes:
        ax.text(0.5, 0.5, "no rule took part in this run", transform=ax.transAxes, ha="center", va="center")


def _bands(ax: Axes, lay: Layout, span: float) -> None:
    """Every other lane shaded; each active layer a band behind its lane, named when there is room."""
    for i, lane in enumerate(lay.lanes):
        if i % 2:
            ax.axhspan(lane.top, lane.bottom, color="#fafafa", zorder=0)
        ax.axhline(lane.bottom, color="#e0e0e0", lw=0.5, zorder=0)
    for band in lay.bands:
        lane = lay.lane(band.rule)
        ax.broken_barh(
            [(band.start, band.end - band.start)],
            (lane.top, lane.bottom - lane.top),
            facecolors=band_colour(band),
            alpha=0.7,
            hatch="//" if band.clause is None else None,
            edgecolor="#bdbdbd" if band.clause is None else "none",
            zorder=1,
        )
        if band.end - band.start > span * 0.04:
            ax.text(
                band.start,
                lane.bottom - 0.06,
                f" {band.layer}",
                fontsize=6,
                va="bottom",
                color="#37474f",
                zorder=2,
            )


def _bars(ax: Axes, lay: Layout, span: float) -> None:
    """Each obligation's bar, coloured by outcome (hatched while pending), with when it was
    settled, a late event, an arrowhead when it has no end, and its name when there is room."""
    for b in lay.bars:
        y = lay.bar_y[b.key]
        colour = OUTCOME_COLOURS[b.outcome]
        width = max(b.end - b.start, lay.min_width)
        pending = b.outcome == Outcome.PENDING
        ax.barh(
            y,
            width,
            left=b.start,
            height=0.62,
            color="white" if pending else colour,
            edgecolor=colour,
            hatch="///" if pending else None,
            linewidth=0.8,
            zorder=3,
        )
        if b.at is not None:
            ax.plot([b.at], [y], marker="|", color="black", ms=7, zorder=4)
        if b.late is not None:
            ax.plot([b.late], [y], marker="D", color=colour, mec="black", ms=4, zorder=4)
        if b.open:
            ax.plot([b.end], [y], marker=">", color=colour, ms=4, zorder=4)
        if width > span * 0.007 * len(b.label):
            ax.text(
                b.start,
                y,
                f" {b.label}",
                fontsize=5.5,
                va="center",
                color=ink(colour),
                zorder=5,
                clip_on=True,
            )


def _links(ax: Axes, lay: Layout) -> None:
    """An arrow from each missed obligation (when it was missed) to each obligation its otherwise started."""
    for link in lay.links:
        parent, child = lay.timeline.bar(link.parent), lay.timeline.bar(link.child)
        start = parent.at if parent.at is not None else parent.end
        ax.annotate(
            "",
            xy=(child.start, lay.bar_y[child.key]),
            xytext=(start, lay.bar_y[parent.key]),
            arrowprops={
                "arrowstyle": "->",
                "color": "#e65100",
                "lw": 1.1,
                "connectionstyle": "arc3,rad=-0.25",
            },
            zorder=6,
        )


def _marks(ax: Axes, lay: Layout, span: float) -> None:
    """Decisions and the rest on each lane's top row; labels that would overlap are joined."""
    kinds: dict[MarkerKind, tuple[list[float], list[float]]] = {}
    for m in lay.markers:
        assert m.rule is not None
        xs, ys = kinds.setdefault(m.kind, ([], []))
        xs.append(m.time)
        ys.append(lay.lane(m.rule).marker_y)
    for kind, (xs, ys) in kinds.items():
        style = MARKER_STYLES[kind]
        ax.scatter(
            xs, ys, marker=style.mpl, color=style.colour, s=22, zorder=7, edgecolors="white", linewidths=0.4
        )
    for lane in lay.lanes:
        labels = cluster([m for m in lay.markers if m.rule == lane.rule], span)
        if len(labels) > LABELLED_MARKS:
            continue
        placed: list[tuple[float, float]] = []
        for t, text in labels:
            left = _near_right(lay, t)
            if not _room(placed, t, text, left, span):
                continue  # it would print over its neighbour's (the HTML's tooltips say all)
            ax.annotate(
                text,
                (t, lane.marker_y),
                xytext=(-4 if left else 4, 0),
                textcoords="offset points",
                fontsize=5.5,
                va="center",
                ha="right" if left else "left",
                zorder=8,
                clip_on=True,
            )


def _legend(fig: Figure, lay: Layout) -> None:
    """One legend for the figure: the outcomes, layer colours and marker kinds drawn."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = [
        Patch(
            facecolor="white" if o == Outcome.PENDING else OUTCOME_COLOURS[o],
            edgecolor=OUTCOME_COLOURS[o],
            hatch="///" if o == Outcome.PENDING else None,
            label=f"obligation {o.value}",
        )
        for o in lay.outcomes()
    ]
    clauses = sorted({b.clause for b in lay.bands}, key=lambda c: -1 if c is None else c)
    for c in clauses:
        colour = band_colour(next(b for b in lay.bands if b.clause == c))
        label = "layer undetermined (?)" if c is None else f"layer of clause {c} (R1.{c}, R2.{c}, …)"
        handles.append(Patch(facecolor=colour, alpha=0.7, label=label, hatch="//" if c is None else None))
    for kind in lay.marker_kinds():
        style = MARKER_STYLES[kind]
        handles.append(Line2D([], [], marker=style.mpl, color=style.colour, ls="none", label=style.name))
    if lay.bars:
        handles.append(Line2D([], [], marker="|", color="black", ls="none", label="settled at"))
    if any(b.late is not None for b in lay.bars):
        handles.append(
            Line2D(
                [],
                [],
                marker="D",
                color=OUTCOME_COLOURS[Outcome.LATE],
                mec="black",
                ls="none",
                label="late event",
            )
        )
    if lay.links:
        handles.append(Line2D([], [], color="#e65100", label="otherwise: missed → fallback"))
    fig.legend(
        handles=handles,
        loc="upper left",
        bbox_to_anchor=(0.81, 1 - 0.9 / fig.get_figheight()),
        fontsize=7,
        frameon=False,
    )
