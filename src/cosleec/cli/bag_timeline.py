"""``cosleec timeline BAG --mapping MAPPING --rules RULES``: a field bag drawn as a run.

A bag of the robot's own topics holds measures and events, not decisions: to draw what the
rules made of it, the bag is replayed through the Context Listener's mapping (fieldbags.py,
the same replay ``cosleec conforms`` judges) and its steps are given, in bag time, to an
embedded Manager on a virtual clock that decides without running tasks. Its records are
what a Manager node would have written had it run beside the robot; the timeline draws
them as it draws an audit log.
"""

from __future__ import annotations

import json
from typing import Any

from cosleec.cli.fieldbags import read_bag
from cosleec.errors import UserError
from cosleec.lang import SleecError, load
from cosleec.runtime import Manager, RuleSet, VirtualClock


def bag_records(bag: str, mapping: str, rules: str) -> list[dict[str, Any]]:
    """The runtime records of ``rules`` over the bag's steps (UserError when the rules, the
    mapping or the bag cannot be read)."""
    try:
        spec = load(rules)
    except SleecError as e:
        raise UserError(f"the rules cannot be read: {e}", where=rules) from None
    run = read_bag(bag, mapping, spec)
    clock = VirtualClock()
    manager = Manager(RuleSet.from_spec(spec), clock=clock, dispatch=False)
    out: list[dict[str, Any]] = []
    manager.subscribe(
        lambda e: out.append(json.loads(json.dumps({"kind": e.kind, "time": e.time, **e.data}, default=str)))
    )
    manager.start(check=False)  # nothing runs the robot's tasks here: the bag shows what they did
    try:
        for step in run.recording.steps:
            clock.advance(max(0.0, step.t - clock.now()))
            manager.tick()
            if step.values:
                manager.update(dict(step.values))
            if step.event is not None:
                manager.event(step.event)
        manager.tick()
    finally:
        manager.close()
    return out


__all__ = ["bag_records"]
