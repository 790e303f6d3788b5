"""The floor of the data model: the records a trigger keeps, as straight-line code.

A benchmark's second baseline, beside the hand-coded application: the same decision as the
Manager's, keeping the same records -- the decision (``Decision.at_trigger``), its
obligation (a ``Tracked``, indexed by event and by deadline), the history -- and running it
as the runtime does -- under a lock, checked again where it starts, the outcome's
collector set, the rule's layer active around the capability, the outcome kept -- written
as straight-line code over the Manager's own compiled rules, with none of the runtime's
parts. ``update`` adds what a context update keeps: the values checked, stored and
stamped under the lock, the clause conditions of the rules that read them evaluated again,
and the layer switches they cause. What this costs is what keeping these records costs
at best in CPython: the figure the runtime's parts are measured against
(``dispatch_path``, ``scalability_grid``).
"""

from __future__ import annotations

import heapq
import threading
from collections import deque
from typing import Any

from cosleec.cop import activating
from cosleec.runtime import Manager
from cosleec.runtime.decision import Decision
from cosleec.runtime.implementations import _RUNS, Ran
from cosleec.runtime.layers import RuleStatus
from cosleec.runtime.obligations import PENDING, Tracked


class Floor:
    """The same trigger keeping the same records, as straight-line code (see the module docstring)."""

    def __init__(self, m: Manager, capabilities: dict[str, Any], *, own_context: bool = False) -> None:
        core = m.core
        self.by_trigger = core.ruleset.by_trigger
        self.rules = core.ruleset.rules
        # the Manager's context and Layer Manager, read only; or (own_context) copies that
        # update() keeps, as the Context and the Layer Manager keep theirs
        self.values = dict(core.context.values) if own_context else core.context.values
        self.status = list(core.layers.status) if own_context else core.layers.status
        self.stamps: dict[str, float] = {}
        self.booleans = frozenset(n for n, spec in core.context.measures.items() if spec.kind == "boolean")
        self.index = core.layers.index
        self.issuer = core.issuer
        self.semantics, self.unknown = core.layers.semantics, core.layers.unknown
        self.capabilities = capabilities
        self.lock = threading.RLock()
        self.decisions: deque[Decision] = deque(maxlen=64)
        self.active: dict[int, Tracked] = {}
        self.by_event: dict[str, dict[int, Tracked]] = {}
        self.heap: list[tuple[float, int]] = []
        self.ids = [1, 1]

    def trigger(self, name: str, now: float) -> None:
        """Decide, keep the records, then run each decision's capabilities under its layer."""
        v, status, ids = self.values, self.status, self.ids
        made = []
        with self.lock:
            for rule in self.by_trigger[name]:
                if not rule.condition(v):
                    continue
                st = status[rule.index]
                clause = st.clause
                assert clause is not None
                obligations = self.issuer.items(rule.response_of(clause), rule.name)  # type: ignore[arg-type]
                did = ids[0]
                ids[0] += 1
                d = Decision.at_trigger(
                    id=did, time=now, event=name, rule=rule, clause=clause, fired=True,
                    read=tuple(map(v.get, rule.value_names)), status=st.values, semantics=self.semantics,
                    obligations=obligations, missing=(), context_version=0, unknown=self.unknown,
                    explanations=None,
                )  # fmt: skip
                self.decisions.append(d)
                items = []
                for ob in obligations:
                    hi = None if ob.within_s is None else now + ob.within_s
                    t = Tracked(
                        id=ids[1], decision_id=did, clause=clause, rule=rule.name, obligation=ob,
                        start=now, lo=now, hi=hi, seq=0, instance=did,
                    )  # fmt: skip
                    ids[1] += 1
                    self.active[t.id] = t
                    self.by_event.setdefault(ob.event, {})[t.id] = t
                    if hi is not None:
                        heapq.heappush(self.heap, (hi, t.id))
                    items.append(t)
                made.append((rule.compositions[clause].layers, d, items))
        for layers, d, items in made:
            with self.lock:  # the re-check where the action starts
                if not all(t.status == PENDING for t in items):
                    continue
            runs: list[Ran] = []
            token = _RUNS.set(runs)
            try:
                activating(layers, self._run, d, runs)
            finally:
                _RUNS.reset(token)

    def _run(self, d: Decision, runs: list[Ran]) -> None:
        for ob in d.obligations:
            cap = self.capabilities.get(ob.event)
            if cap is not None:
                cap(ob, d)
                runs.append(Ran("capability", ob.event))

    def update(self, values: dict[str, Any], now: float) -> list[tuple[str, str, str]]:
        """Measures of boolean measures (checked as the Context checks them), stored and stamped;
        each rule that reads one re-evaluated, its clause the last that holds; under the lock
        (the runtime serialises an update with every other step), the layer switches returned
        (``Manager.update`` returns them)."""
        booleans, stored = self.booleans, self.values
        for name, value in values.items():
            if name not in booleans or type(value) is not bool:
                raise ValueError(f"{name}: not a boolean measure's value")
        switches = []
        with self.lock:
            changed = [n for n, x in values.items() if stored.get(n) is not x]
            stored.update(values)
            self.stamps.update(dict.fromkeys(values, now))
            status = self.status
            for i, rule in {r.index: r for n in changed for r in self.index.get(n, ())}.items():
                assert rule.evaluate_all is not None
                held = rule.evaluate_all(stored)
                new = RuleStatus(held, len(held) - held[::-1].index(True) if True in held else 0)
                if new.clause != status[i].clause:
                    names = rule.layer_names
                    switches.append((rule.name, names[status[i].clause or 0], names[new.clause]))
                status[i] = new
        return switches

    def fulfilled(self) -> None:
        """The robot did what was obliged (not timed): the floor's records of it go."""
        self.active.clear()
        self.by_event.clear()
        self.heap.clear()
