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
the ``RuleStatus``); a trigger is a closure over what it reads, a decision is its clause's
template of ``Decision.at_trigger``'s fields copied and completed, and an obligation's
``Tracked`` is set by a positional ``__init__`` made from the dataclass's own fields. Two
adversarial reviews (issue 32) wrote it, each asked to make the floor faster without
dropping a record or a duty and checked record for record against the one before on
random sequences: 0.63x the cost of the straightforward floor at 60 x 20, then 0.67x of
that one on ``dispatch_path``'s trigger. ``tests/unit/test_bench_floor.py`` holds it to
the Manager's own decisions, obligations, layer switches, capability calls and counts.
What this costs is what keeping these records costs at best in CPython, as far as anyone
has found: the figure the runtime's parts are measured against (``dispatch_path``,
``scalability_grid``).
"""

from __future__ import annotations

import heapq
import threading
from collections import deque
from typing import Any

from cosleec.bulk import positional_init
from cosleec.cop import activating
from cosleec.runtime import Manager
from cosleec.runtime.decision import Decision, DecisionOrigin
from cosleec.runtime.implementations import _RUNS, Ran
from cosleec.runtime.layers import RuleStatus
from cosleec.runtime.obligations import FULFILLED, PENDING, VIOLATED, Tracked
from cosleec.runtime.plans import reader as value_reader

_tnew = tuple.__new__  # what RuleStatus.__new__ does, without its Python frame
_heappush = heapq.heappush


def _noop(*_: Any) -> None:
    return None


_GIVEN = (
    "id",
    "decision_id",
    "clause",
    "rule",
    "obligation",
    "start",
    "lo",
    "hi",
    "seq",
    "instance",
    "own_hi",
)


_init_tracked = positional_init(Tracked, _GIVEN)  # (what the tracker's start_plain sets, positional)


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
                        value_reader(rule.value_names),
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
        self.trigger = self._make_trigger()

    def take_context(self, m: Manager) -> None:
        """(With ``own_context``.) The Manager's values and rule statuses now, copied into the
        floor's own, in place (its trigger holds them): a floor built before a benchmark's
        warm-up starts its timed pass from the context the runtime's started from."""
        self.values.clear()
        self.values.update(m.core.context.values)
        self.status[:] = m.core.layers.status

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
    def _make_trigger(self):  # type: ignore[no-untyped-def]
        """``trigger``, as a closure over what it reads: every object it uses one cell load away.

        Per event, per rule it triggers: whether its condition is the constant true (then not
        called), and per clause a template of the decision's fixed fields (those
        ``Decision.at_trigger`` writes from the rule and clause: name, clause, layer,
        semantics, obligations when fixed, ...; in its key order), the obligations with their
        deadlines' offsets, the layers and the capability's event.
        """
        from cosleec.runtime.compile import always  # the condition of a rule without one

        v, status, ids, stats = self.values, self.status, self.ids, self.stats
        active, by_event, heap = self.active, self.by_event, self.heap
        lock = self.lock
        acquire, release = lock.acquire, lock.release
        now_of = self.clock.now
        time_passes = self._time_passes
        issuer_items = self.issuer.items
        history = self.decisions.append
        local = self.depth
        capabilities = self.capabilities
        ran_ok = self._ran_ok
        run_all = self._run
        runs_set, runs_reset = _RUNS.set, _RUNS.reset
        semantics, unknown = self.semantics, self.unknown
        _new = object.__new__
        _setattr = object.__setattr__
        _init = _init_tracked
        origin = DecisionOrigin.TRIGGER
        me = self

        def template(rule: Any, clause: int, obligations: Any) -> dict[str, Any]:
            return {  # Decision.at_trigger's dict, in its order; None where a trigger writes its own
                "id": None, "time": None, "event": None, "rule": rule.name, "clause": clause,
                "layer": rule.layer_names[clause] if clause else None, "semantics": semantics,
                "obligations": obligations, "missing": (), "reason": "", "context_version": None,
                "violated": None, "unknown": unknown, "origin": origin, "missed": None,
                "explanations": None,
            }  # fmt: skip

        table: dict[str, tuple[Any, ...]] = {}
        for name, entries in self._triggered.items():
            out = []
            for rule, index, condition, reader, value_names, per_clause in entries:
                clauses = []
                for k, (fixed, spec, layers) in enumerate(per_clause):
                    timed = None if fixed is None else tuple((ob, ob.within_s, ob.event) for ob in fixed)
                    clauses.append(
                        (
                            fixed,
                            spec,
                            layers,
                            template(rule, k, fixed),
                            timed,
                            timed[0] if timed is not None and len(timed) == 1 else None,
                        )
                    )
                out.append(
                    (rule, rule.name, index, None if condition is always else condition, reader, value_names,
                     tuple(clauses))
                )  # fmt: skip
            table[name] = tuple(out)

        def decide(entry: tuple[Any, ...], name: str, now: float, seq: int) -> Any:
            """The decision of one rule the occurrence triggers, its obligations in force (under the
            lock): (layers, decision, its Tracked items, the one obligation or None), or None."""
            rule, rname, index, condition, reader, value_names, per_clause = entry
            if condition is not None and not condition(v):
                return None
            st = status[index]
            values, clause = st[0], st[1]  # RuleStatus(values, clause, ...)
            assert clause is not None
            fixed, spec, layers, fields, timed, one = per_clause[clause]
            try:
                read = reader(v)
            except KeyError:  # an unknown value: None, as v.get gives it
                read = tuple(map(v.get, value_names))
            did = ids[0]
            ids[0] = did + 1
            dd = fields.copy()  # what Decision.at_trigger makes: its fixed fields copied, the rest set
            dd["id"] = did
            dd["time"] = now
            dd["event"] = name
            dd["context_version"] = me.version
            if fixed is None:
                dd["obligations"] = obligations = issuer_items(spec, rname)
                timed = tuple((ob, ob.within_s, ob.event) for ob in obligations)
                one = timed[0] if len(timed) == 1 else None
            dd["_parts"] = (rule, read, True, values)
            d = _new(Decision)
            _setattr(d, "__dict__", dd)
            history(d)
            stats["decisions"] += 1
            items = []
            for ob, within, ev in timed:
                tid = ids[1]
                ids[1] = tid + 1
                t = _new(Tracked)
                if within is None:
                    _init(t, tid, did, clause, rname, ob, now, now, None, seq, did, None)
                else:
                    hi = now + within
                    _init(t, tid, did, clause, rname, ob, now, now, hi, seq, did, hi)
                    _heappush(heap, (hi, tid))
                active[tid] = t
                w = by_event.get(ev)
                if w is None:
                    w = by_event[ev] = {}
                w[tid] = t
                items.append(t)
            return layers, d, items, one

        def run(layers: Any, d: Decision, items: list[Tracked], one: Any) -> None:
            """The re-check where the action starts, the depth guard, the run with the rule's layers
            active and its outcome collected, a failure counted."""
            acquire()  # the re-check where the action starts
            try:
                for t in items:
                    if t.status != PENDING:
                        return
            finally:
                release()
            depth = getattr(local, "n", 0)
            if depth >= me.max_depth:
                stats["task_failures"] += 1
                return
            local.n = depth + 1
            runs: list[Ran] = []
            token = runs_set(runs)
            try:
                if one is not None:
                    ob, _, ev = one
                    cap = capabilities.get(ev)
                    if cap is None:
                        activating(layers, _noop)
                    else:
                        try:
                            activating(layers, cap, ob, d)
                            ok = ran_ok.get(ev)
                            if ok is None:
                                ok = ran_ok[ev] = Ran("capability", ev)
                            runs.append(ok)
                        except Exception as e:
                            runs.append(Ran("capability", ev, repr(e)))
                else:
                    activating(layers, run_all, d, runs)
            finally:
                runs_reset(token)
                local.n = depth
            for r in runs:
                if not r.ok:
                    stats["task_failures"] += 1

        def trigger(name: str) -> None:
            entries = table[name]
            acquire()
            try:
                now = now_of()
                if heap and heap[0][0] < now:
                    time_passes(now)
                waiting = by_event.get(name)  # the occurrence meets what is in force
                if waiting:
                    for t in waiting.values():
                        t.status, t.outcome_at, t.by = FULFILLED, now, name
                        del active[t.id]
                    waiting.clear()
                seq = ids[2]
                ids[2] = seq + 1
                stats["events"] += 1
                if len(entries) != 1:
                    made = [x for x in [decide(e, name, now, seq) for e in entries] if x is not None]
                else:  # the usual case: one rule, one clause's one obligation, inline
                    made = None
                    rule, rname, index, condition, reader, value_names, per_clause = entries[0]
                    if condition is not None and not condition(v):
                        return
                    st = status[index]
                    values, clause = st[0], st[1]  # RuleStatus(values, clause, ...)
                    assert clause is not None
                    _, _, layers, fields, _, one = per_clause[clause]
                    if one is None:
                        made = [decide(entries[0], name, now, seq)]
                    else:
                        try:
                            read = reader(v)
                        except KeyError:  # an unknown value: None, as v.get gives it
                            read = tuple(map(v.get, value_names))
                        did = ids[0]
                        ids[0] = did + 1
                        dd = fields.copy()  # Decision.at_trigger's dict: its fixed fields copied
                        dd["id"] = did
                        dd["time"] = now
                        dd["event"] = name
                        dd["context_version"] = me.version
                        dd["_parts"] = (rule, read, True, values)
                        d = _new(Decision)
                        _setattr(d, "__dict__", dd)
                        history(d)
                        stats["decisions"] += 1
                        ob, within, ev = one
                        tid = ids[1]
                        ids[1] = tid + 1
                        t = _new(Tracked)
                        if within is None:
                            _init(t, tid, did, clause, rname, ob, now, now, None, seq, did, None)
                        else:
                            hi = now + within
                            _init(t, tid, did, clause, rname, ob, now, now, hi, seq, did, hi)
                            _heappush(heap, (hi, tid))
                        active[tid] = t
                        w = by_event.get(ev)
                        if w is None:
                            w = by_event[ev] = {}
                        w[tid] = t
            finally:
                release()
            if made is not None:
                for x in made:
                    run(*x)
                return
            acquire()  # the re-check where the action starts
            try:
                go = t.status == PENDING
            finally:
                release()
            if not go:
                return
            depth = getattr(local, "n", 0)
            if depth >= me.max_depth:
                stats["task_failures"] += 1
                return
            local.n = depth + 1
            runs: list[Ran] = []
            token = runs_set(runs)
            try:
                cap = capabilities.get(ev)
                if cap is None:
                    activating(layers, _noop)
                else:
                    try:
                        activating(layers, cap, ob, d)
                        ok = ran_ok.get(ev)
                        if ok is None:
                            ok = ran_ok[ev] = Ran("capability", ev)
                        runs.append(ok)
                    except Exception as e:
                        runs.append(Ran("capability", ev, repr(e)))
            finally:
                runs_reset(token)
                local.n = depth
            for r in runs:
                if not r.ok:
                    stats["task_failures"] += 1

        return trigger

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
