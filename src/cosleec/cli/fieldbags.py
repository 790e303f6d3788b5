"""A field bag as ``cosleec conforms`` judges it: the replayed trace, and the message behind each verdict.

``cosleec conforms RULES BAG --mapping MAPPING.yaml`` replays the bag through the Context
Listener's mapping (:func:`cosleec.nodes.fieldbag.replay`: the listener's own code) and
judges the trace by the reference semantics, like any trace. This module turns the replay
into the :class:`~cosleec.semantics.Recording` the judge reads, and names, for a verdict,
the bag messages behind it: the one whose event triggered the rule and, for a prohibition
broken by an occurrence, the one that carried the forbidden event -- by topic and bag time.

A bag that leaves part of the mapping uncovered (:attr:`BagTrace.gaps`) is judged all the
same, with its measures unknown and its events absent, but never passes: ``conforms`` exits
1 and says why (:attr:`BagRun.complete`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from cosleec.cli.common import input_file
from cosleec.lang import Specification
from cosleec.nodes import BagTrace, Mapping, Origin, replay
from cosleec.runtime import RuleSet
from cosleec.semantics import Firing, Judgement, Recording, Step, Verdict


@dataclass
class BagRun:
    """A bag replayed for ``conforms``: the recording judged, the replay it came from, and per
    step (the judge's step index) the message it came from (None: the bag's end)."""

    recording: Recording
    trace: BagTrace
    origins: list[Origin | None] = field(default_factory=list)
    _started: dict[int, Firing] = field(default_factory=dict, init=False, repr=False)
    _occurred: dict[tuple[str, float], int] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        for i, step in enumerate(self.recording.steps):  # (event, time) -> its first step
            if step.event is not None:
                self._occurred.setdefault((step.event, step.t), i)

    @property
    def complete(self) -> bool:
        """Did the bag give every entry of the mapping its topic, type and field?"""
        return self.trace.complete

    def behind(self, j: Judgement, v: Verdict) -> str:
        """The messages behind ``v``: ``trigger UserFallen: /fall_detector at 10 s (bag time ...)``,
        then the forbidden occurrence for a broken prohibition; "" when none is known."""
        parts = [f"{what}: {origin.describe()}" for what, origin in self.sources(j, v)]
        return "; ".join(parts)

    def sources(self, j: Judgement, v: Verdict) -> list[tuple[str, Origin]]:
        """(what, origin) of the messages behind ``v``, as :meth:`behind` names them."""
        out: list[tuple[str, Origin]] = []
        if not self._started:
            self._started = {f.instance: f for f in j.firings if f.instance is not None}
        firing = self._started.get(v.instance)
        if firing is not None:
            origin = self._origin(firing.step)
            if origin is not None:
                out.append((f"trigger {firing.event}", origin))
        if v.negated and v.status == "violated" and v.at is not None:
            origin = self._origin(self._occurred.get((v.event, v.at), -1))
            if origin is not None:
                out.append((v.event, origin))
        return out

    def firing_origin(self, f: Firing) -> Origin | None:
        """The message whose event made the firing ``f``."""
        return self._origin(f.step)

    def _origin(self, step: int) -> Origin | None:
        return self.origins[step] if 0 <= step < len(self.origins) else None

    def to_json(self, j: Judgement) -> dict[str, Any]:
        """The ``bag`` object of ``--json``: the bag, whether it covers the mapping, the gaps and
        rejections, and per verdict (by id) the messages behind it."""
        t = self.trace
        return {
            "source": t.source,
            "start_ns": t.start,
            "end": t.end,
            "messages": t.read,
            "complete": t.complete,
            "gaps": list(t.gaps),
            "rejections": list(t.rejections),
            "behind": {
                str(v.id): [{"what": what, **o.to_json()} for what, o in self.sources(j, v)]
                for v in j.verdicts
            },
        }


def read_bag(path: str, mapping_path: str, spec: Specification) -> BagRun:
    """The bag at ``path`` replayed through the mapping at ``mapping_path``, checked against
    ``spec``'s measures and events as the listener node checks it at start-up.

    UserError (a MappingError, a BagError) for a mapping or a bag that cannot be read.
    """
    rules = RuleSet.from_spec(spec)
    mapping = Mapping.load(
        input_file(mapping_path, "the mapping", text=True),
        dict(rules.measures),
        frozenset(e.name for e in spec.events),
    )
    trace = replay(path, mapping)
    steps = [Step(t=s.t, event=s.event, values=s.values, line=n) for n, s in enumerate(trace.steps, 1)]
    return BagRun(Recording(steps, source=str(path)), trace, [s.origin for s in trace.steps])
