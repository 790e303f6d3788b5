"""The floor of the data model: the records a trigger keeps, as fast straight-line code.

A benchmark's second baseline, beside the hand-coded application: the same decision as the
Manager's, keeping the same records -- the decision (``Decision.at_trigger``), its
obligation (a ``Tracked``, indexed by id, by event and by deadline), the history -- and
running it as the runtime does -- under a lock, checked again where it starts, the
outcome's collector set, the rule's layer active around the capability, the outcome kept --
written over the Manager's own compiled rules, with none of the runtime's parts. ``update``
adds what a context update keeps: the values checked, stored and stamped under the lock,
the clause conditions of the rules that read them evaluated again, and the layer switches
they cause.

Every step also does what any step of the runtime must, whatever its parts: it reads the
clock once under the lock (its records' time), lets time pass first (a deadline due by
then is judged before the step's own change: a violation comes before the update that
follows it), counts what users read in ``Manager.stats`` and, for a trigger, meets what
is in force with the occurrence (an obligation it fulfils ends) and numbers it in causal
order; an update bumps the context version a decision keeps; a capability runs inside the
depth guard (``max_depth``: an implementation that triggers its own rule stops) and its
failure is caught and counted.

It is the quiet case only (what the benchmarks run): boolean measures, no prohibition,
interval, ``else``, ``otherwise`` or unknown value. Within it, it is written to be as fast
as CPython allows, so that the runtime is measured against the best, not against a
straw man: what can be done once per rule set is done when it is built (per event, each
rule's condition, a C-level reader of the values it keeps and, per clause, its fixed
obligations and layers; per rule, the measures only it reads), and the rest with C-level
bulk operations (``issuperset`` picks the one rule an update touches, ``items() <=`` sees
an update that changes nothing, ``itemgetter`` reads the values, ``tuple.__new__`` makes
the ``RuleStatus``). An adversarial review (issue 32) wrote this version: 0.63x the cost
of the straightforward one it replaced, keeping every record and duty (checked record for
record against it on random sequences). What this costs is what keeping these records
costs at best in CPython: the figure the runtime's parts are measured against
(``dispatch_path``, ``scalability_grid``).
"""

from __future__ import annotations

import heapq
import threading
from collections import deque
from operator import itemgetter
from typing import Any

from cosleec.cop import activating
from cosleec.runtime import Manager
from cosleec.runtime.decision import Decision
from cosleec.runtime.implementations import _RUNS, Ran
from cosleec.runtime.layers import RuleStatus
from cosleec.runtime.obligations import FULFILLED, PENDING, VIOLATED, Tracked

_tnew = tuple.__new__  # what RuleStatus.__new__ does, without its Python frame
_heappush = heapq.heappush


def _noop(*_: Any) -> None:
    return None


def _reader(names: tuple[str, ...]):  # type: ignore[no-untyped-def]
    """tuple(map(v.get, names)) in one C call while every value is known."""
    if not names:
        return lambda v: ()
    if len(names) == 1:
        (n,) = names
        return lambda v: (v[n],)
    return itemgetter(*names)


class Floor:
    """The same trigger keeping the same records, as fast straight-line code (see the module docstring)."""

    def __init__(self, m: Manager, capabilities: dict[str, Any], *, own_context: bool = False) -> None:
        core = m.core
        self.by_trigger = core.ruleset.by_trigger
        self.rules = core.ruleset.rules
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
        self.version = 0
        self.stats = {"updates": 0, "events": 0, "decisions": 0, "violations": 0, "task_failures": 0}
        self.depth = threading.local()
        self.max_depth = 16
        self._at_trigger = Decision.at_trigger
        # --- precomputed per rule set
        # measure -> indices of the rules that read it (in the index's order)
        self._readers: dict[str, tuple[int, ...]] = {
            n: tuple(r.index for r in rs) for n, rs in self.index.items()
        }
        self._rule_at = {r.index: r for r in self.rules}
        # rule index -> (evaluate_all, layer_names)
        self._eval = {
            r.index: (r.evaluate_all, r.layer_names) for r in self.rules if r.evaluate_all is not None
        }
        # event -> per rule it triggers: (rule, index, condition, reader, per clause: (fixed obligations
        # or None, response spec, layers of its composition))
        self._triggered: dict[str, tuple[Any, ...]] = {}
        for name, rules in self.by_trigger.items():
            entries = []
            for rule in rules:
                per_clause = []
                for k in range(len(rule.layer_names)):
                    spec = rule.response_of(k)
                    fixed = None
                    if spec is not None and spec.fixed:
                        fixed = self.issuer.items(spec, rule.name)  # the issuer's own memo, made now
                    per_clause.append((fixed, spec, rule.compositions[k].layers))
                entries.append(
                    (
                        rule,
                        rule.index,
                        rule.condition,
                        _reader(rule.value_names),
                        rule.value_names,
                        tuple(per_clause),
                    )
                )
            self._triggered[name] = tuple(entries)
        # rule index -> the measures it reads, when they are all boolean and read by it alone: an
        # update of some of them touches this rule, and only it, iff anything changed
        reads_of: dict[int, set[str]] = {}
        for n, rs in self._readers.items():
            for i in rs:
                reads_of.setdefault(i, set()).add(n)
        self._alone: dict[int, frozenset[str]] = {
            i: frozenset(reads)
            for i, reads in reads_of.items()
            if reads <= self.booleans and all(self._readers[n] == (i,) for n in reads)
        }
        self._ran_ok: dict[str, Ran] = {}  # a successful run's outcome is an immutable value: shared

    # ------------------------------------------------------------------ steps' common parts
    def _time_passes(self, now: float) -> None:
        heap, active, by_event = self.heap, self.active, self.by_event
        stats = self.stats
        while heap and heap[0][0] < now:
            _, tid = heapq.heappop(heap)
            t = active.pop(tid, None)
            if t is not None:
                t.status, t.outcome_at = VIOLATED, now
                del by_event[t.obligation.event][tid]
                stats["violations"] += 1

    # ------------------------------------------------------------------ update
    def update(self, values: dict[str, Any]) -> list[tuple[str, str, str]]:
        one = -1
        for first in values:  # the rule the first measure feeds: does it alone read them all?
            rs = self._readers.get(first)
            if rs is not None and len(rs) == 1:
                reads = self._alone.get(rs[0])
                if reads is not None and reads.issuperset(values):
                    one = rs[0]
            break
        if (one < 0 and not self.booleans.issuperset(values)) or [*map(type, values.values())].count(
            bool
        ) != len(values):
            booleans = self.booleans  # the first bad one, named as the Context names it
            for name, value in values.items():
                if name not in booleans or type(value) is not bool:
                    raise ValueError(f"{name}: not a boolean measure's value")
        stored, status, stats = self.values, self.status, self.stats
        switches: list[tuple[str, str, str]] = []
        lock = self.lock
        lock.acquire()
        try:
            now = self.clock.now()
            heap = self.heap
            if heap and heap[0][0] < now:
                self._time_passes(now)
            stats["updates"] += 1
            if values.items() <= stored.items():  # nothing changed (bool values: == is identity)
                stored.update(values)
                self.stamps.update(dict.fromkeys(values, now))
                return switches
            self.version += 1
            if one >= 0:
                touched: Any = (one,)
            else:
                readers = self._readers
                touched = {
                    i: None for n, x in values.items() if stored.get(n) is not x for i in readers.get(n, ())
                }
            stored.update(values)
            stamps = self.stamps
            for n in values:  # (a specialised store per key: cheaper than a dict made to merge)
                stamps[n] = now
            evals = self._eval
            for i in touched:
                evaluate_all, names = evals[i]
                held = evaluate_all(stored)
                clause = len(held) - held[::-1].index(True) if True in held else 0
                old = status[i].clause
                if clause != old:
                    switches.append((self._rule_at[i].name, names[old or 0], names[clause]))
                status[i] = _tnew(RuleStatus, (held, clause, ()))
        finally:
            lock.release()
        return switches

    # ------------------------------------------------------------------ trigger
    def trigger(self, name: str) -> None:
        v, status, ids, stats = self.values, self.status, self.ids, self.stats
        active, by_event = self.active, self.by_event
        made = []
        lock = self.lock
        lock.acquire()
        try:
            now = self.clock.now()
            heap = self.heap
            if heap and heap[0][0] < now:
                self._time_passes(now)
            waiting = by_event.get(name)  # the occurrence meets what is in force
            if waiting:
                for t in waiting.values():
                    t.status, t.outcome_at, t.by = FULFILLED, now, name
                    del active[t.id]
                waiting.clear()
            seq = ids[2]
            ids[2] = seq + 1
            stats["events"] += 1
            for rule, index, condition, reader, value_names, per_clause in self._triggered[name]:
                if not condition(v):
                    continue
                st = status[index]
                clause = st.clause
                assert clause is not None
                obligations, spec, layers = per_clause[clause]
                if obligations is None:
                    obligations = self.issuer.items(spec, rule.name)
                try:
                    read = reader(v)
                except KeyError:  # an unknown value: None, as v.get gives it
                    read = tuple(map(v.get, value_names))
                did = ids[0]
                ids[0] = did + 1
                d = self._at_trigger(
                    id=did, time=now, event=name, rule=rule, clause=clause, fired=True,
                    read=read, status=st.values, semantics=self.semantics,
                    obligations=obligations, missing=(), context_version=self.version, unknown=self.unknown,
                    explanations=None,
                )  # fmt: skip
                self.decisions.append(d)
                stats["decisions"] += 1
                items = []
                for ob in obligations:
                    within = ob.within_s
                    hi = None if within is None else now + within
                    tid = ids[1]
                    ids[1] = tid + 1
                    t = Tracked(
                        id=tid, decision_id=did, clause=clause, rule=rule.name, obligation=ob,
                        start=now, lo=now, hi=hi, seq=seq, instance=did,
                    )  # fmt: skip
                    active[tid] = t
                    ev = ob.event
                    w = by_event.get(ev)
                    if w is None:
                        w = by_event[ev] = {}
                    w[tid] = t
                    if hi is not None:
                        _heappush(heap, (hi, tid))
                    items.append(t)
                made.append((layers, d, items))
        finally:
            lock.release()
        for layers, d, items in made:
            lock.acquire()  # the re-check where the action starts
            try:
                go = True
                for t in items:
                    if t.status != PENDING:
                        go = False
                        break
            finally:
                lock.release()
            if not go:
                continue
            local = self.depth
            depth = getattr(local, "n", 0)
            if depth >= self.max_depth:
                stats["task_failures"] += 1
                continue
            local.n = depth + 1
            runs: list[Ran] = []
            token = _RUNS.set(runs)
            try:
                obs = d.obligations
                if len(obs) == 1:
                    ob = obs[0]
                    ev = ob.event
                    cap = self.capabilities.get(ev)
                    if cap is None:
                        activating(layers, _noop)
                    else:
                        try:
                            activating(layers, cap, ob, d)
                            ok = self._ran_ok.get(ev)
                            if ok is None:
                                ok = self._ran_ok[ev] = Ran("capability", ev)
                            runs.append(ok)
                        except Exception as e:
                            runs.append(Ran("capability", ev, repr(e)))
                else:
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

    def fulfilled(self) -> None:
        self.active.clear()
        self.by_event.clear()
        self.heap.clear()
