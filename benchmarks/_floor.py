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

Every step also does what any step of the runtime must, whatever its parts: it reads the
clock once under the lock (its records' time), lets time pass first (a deadline due by
then is judged before the step's own change: a violation comes before the update that
follows it), counts what users read in ``Manager.stats`` and, for a trigger, meets what
is in force with the occurrence (an obligation it fulfils ends) and numbers it in causal
order; an update bumps the context version a decision keeps; a capability runs inside the
depth guard (``max_depth``: an implementation that triggers its own rule stops) and its
failure is caught and counted.
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
from cosleec.runtime.obligations import FULFILLED, PENDING, VIOLATED, Tracked


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
        self.ids = [1, 1, 1]  # the next decision, obligation and occurrence (seq)
        self.clock = core.steps.clock
        self.version = 0  # the context's, as a decision keeps it
        self.stats = {"updates": 0, "events": 0, "decisions": 0, "violations": 0, "task_failures": 0}
        self.depth = threading.local()
        self.max_depth = 16

    def _time_passes(self, now: float) -> None:
        """(Under the lock.) Windows whose deadline ``now`` passed are violated first."""
        heap, active = self.heap, self.active
        while heap and heap[0][0] < now:
            _, tid = heapq.heappop(heap)
            t = active.pop(tid, None)
            if t is not None:
                t.status, t.outcome_at = VIOLATED, now
                del self.by_event[t.obligation.event][tid]
                self.stats["violations"] += 1

    def _occurs(self, name: str, now: float) -> int:
        """(Under the lock.) ``name`` occurred: the obligations in force that it fulfils end;
        its causal number."""
        waiting = self.by_event.get(name)
        if waiting:
            for t in waiting.values():
                t.status, t.outcome_at, t.by = FULFILLED, now, name
                del self.active[t.id]
            waiting.clear()
        seq = self.ids[2]
        self.ids[2] = seq + 1
        return seq

    def trigger(self, name: str) -> None:
        """Decide, keep the records, then run each decision's capabilities under its layer."""
        v, status, ids, stats = self.values, self.status, self.ids, self.stats
        made = []
        with self.lock:
            now = self.clock.now()
            self._time_passes(now)
            seq = self._occurs(name, now)
            stats["events"] += 1
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
                    obligations=obligations, missing=(), context_version=self.version, unknown=self.unknown,
                    explanations=None,
                )  # fmt: skip
                self.decisions.append(d)
                stats["decisions"] += 1
                items = []
                for ob in obligations:
                    hi = None if ob.within_s is None else now + ob.within_s
                    t = Tracked(
                        id=ids[1], decision_id=did, clause=clause, rule=rule.name, obligation=ob,
                        start=now, lo=now, hi=hi, seq=seq, instance=did,
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
            local = self.depth
            depth = getattr(local, "n", 0)
            if depth >= self.max_depth:  # not run: the runtime records why
                stats["task_failures"] += 1
                continue
            local.n = depth + 1
            runs: list[Ran] = []
            token = _RUNS.set(runs)
            try:
                activating(layers, self._run, d, runs)
            finally:
                _RUNS.reset(token)
                local.n = depth
            for r in runs:
                if not r.ok:
                    stats["task_failures"] += 1

    def _run(self, d: Decision, runs: list[Ran]) -> None:
        for ob in d.obligations:
            cap = self.capabilities.get(ob.event)
            if cap is not None:
                try:
                    cap(ob, d)
                    runs.append(Ran("capability", ob.event))
                except Exception as e:
                    runs.append(Ran("capability", ob.event, repr(e)))

    def update(self, values: dict[str, Any]) -> list[tuple[str, str, str]]:
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
            now = self.clock.now()
            self._time_passes(now)
            self.stats["updates"] += 1
            changed = [n for n, x in values.items() if stored.get(n) is not x]
            if changed:
                self.version += 1
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
