"""Pictures of rule sets and runs for the people who review them: rule diagrams
(:mod:`cosleec.views.graph`) and a run over time (:mod:`cosleec.views.timeline`, drawn by
:mod:`cosleec.views.timeline_mpl` and :mod:`cosleec.views.timeline_plotly`), and views of a
running Manager attached to it from here (:mod:`cosleec.views.registry`: :func:`attach`,
:class:`AttachedView`; the live web view, :mod:`cosleec.views.web`). On top of ``lang``,
``runtime``, ``analysis`` and ``nodes`` (an MCAP recording's reader); nothing below imports it."""

from cosleec.views.graph import (
    FORMATS,
    RuleGraph,
    analysed_conflicts,
    build,
    check_drawable,
    render,
    to_dot,
    to_mermaid,
)
from cosleec.views.registry import AttachedView, View, ViewFactory, attach, load_view
from cosleec.views.timeline import Timeline
from cosleec.views.timeline_layout import TIMELINE_FORMATS, Layout, layout
from cosleec.views.timeline_marks import Band, Bar, Link, Marker, MarkerKind, Outcome, Series
from cosleec.views.timeline_mpl import timeline_image
from cosleec.views.timeline_plotly import timeline_html

__all__ = [
    "FORMATS",
    "TIMELINE_FORMATS",
    "AttachedView",
    "Band",
    "Bar",
    "Layout",
    "Link",
    "Marker",
    "MarkerKind",
    "Outcome",
    "RuleGraph",
    "Series",
    "Timeline",
    "View",
    "ViewFactory",
    "analysed_conflicts",
    "attach",
    "build",
    "check_drawable",
    "layout",
    "load_view",
    "render",
    "timeline_html",
    "timeline_image",
    "to_dot",
    "to_mermaid",
]
