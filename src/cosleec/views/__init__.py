"""Pictures of rule sets and runs for the people who review them: rule diagrams
(:mod:`cosleec.views.graph`). On top of ``lang``, ``runtime`` and ``analysis``; nothing
below imports it."""

from cosleec.views.graph import FORMATS, RuleGraph, analysed_conflicts, build, render, to_dot, to_mermaid

__all__ = ["FORMATS", "RuleGraph", "analysed_conflicts", "build", "render", "to_dot", "to_mermaid"]
