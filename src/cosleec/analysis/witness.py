"""Witness traces: a solver's model as a trace, checked by the reference semantics.

Every trace the analysis shows is first judged by :func:`cosleec.semantics.judge` -- the
independent oracle ``cosleec conforms`` uses -- and its verdicts become the timeline a
person reads. A witness the oracle does not confirm is flagged (it would be a bug in the
encoding), never silently shown.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import z3

from cosleec.analysis.encoding import Encoding, as_float
from cosleec.analysis.findings import Witness
from cosleec.lang import Reading, Specification, visit
from cosleec.lang import ast as A
from cosleec.semantics import Judgement, Step, Value, judge


def smallest(enc: Encoding, assumptions: list[Any]) -> Any:
    """A model with as few occurrences as one pass can leave out, and without an ``otherwise``
    when one exists: each occurrence the last model used (but the probes), latest first, is
    left out if the question stays satisfiable. The solver must just have answered sat under
    ``assumptions``."""
    model = enc.solver.model()
    out = list(assumptions)
    if enc.fallbacks:  # a trace that needs no `otherwise`, if there is one: `conforms` then passes it too
        trial = [*out, *(z3.Not(fb.started) for fb in enc.fallbacks)]
        if enc.check(trial) == z3.sat:
            out, model = trial, enc.solver.model()
        else:
            enc.check(out)  # back to the model asked for
            model = enc.solver.model()
    probes = [s for s in enc.slots if s.depth == 0]
    for s in reversed(enc.slots):
        if s in probes or not z3.is_true(model.eval(s.present, model_completion=True)):
            continue
        trial = [*out, z3.Not(s.present)]
        if enc.check(trial) == z3.sat:
            out, model = trial, enc.solver.model()
    return model


def steps(enc: Encoding, model: Any, also: Any = None) -> list[Step]:
    """The trace a model describes: each present occurrence, preceded by the values it
    reads; each started ``otherwise`` snapshot after every occurrence at its instant; then
    one last step far enough on that every deadline of the trace has passed. ``also`` is a slot
    to include as if present (at the time and values the model gives it)."""
    present = [s for s in enc.slots if s is also or z3.is_true(model.eval(s.present, model_completion=True))]
    at: dict[int, float] = {s.id: _number(model.eval(s.t, model_completion=True)) for s in present}
    order = sorted(present, key=lambda s: (at[s.id], model.eval(s.pos, model_completion=True).as_long()))
    fallbacks = []
    for fb in enc.fallbacks:
        if z3.is_true(model.eval(fb.started, model_completion=True)):
            fallbacks.append((_number(model.eval(fb.at, model_completion=True)), fb.snap))
    fallbacks.sort(key=lambda x: x[0])
    out: list[Step] = []
    fi = 0
    for s in order:
        t = at[s.id]
        while fi < len(fallbacks) and fallbacks[fi][0] < t:
            out.append(Step(fallbacks[fi][0], None, _values(enc, model, fallbacks[fi][1])))
            fi += 1
        out.append(Step(t, s.event, _values(enc, model, s.snap)))
    for when, snap in fallbacks[fi:]:
        out.append(Step(when, None, _values(enc, model, snap)))
    last = max((s.t for s in out), default=0.0)
    out.append(Step(last + _horizon(enc.spec)))
    return out


def then(enc: Encoding, history: Any, last: Any, reading: Reading) -> Witness:
    """A history the rules allow (a model without the ``last`` slot, whose time, order and
    values it pins), then the ``last`` trigger: the reference semantics must find a breach."""
    trace = steps(enc, history, also=last)
    j = judge(enc.spec, trace, reading)
    return Witness(tuple(trace), tuple(timeline(enc.spec, trace, j)), bool(final_breaches(enc.spec, j)))


def _values(enc: Encoding, model: Any, snap: dict[str, Any]) -> dict[str, Value | None]:
    out: dict[str, Value | None] = {}
    for m, var in snap.items():
        v = model.eval(var, model_completion=True)
        t = enc.measures[m]
        if isinstance(t, A.BooleanType):
            out[m] = z3.is_true(v)
        elif isinstance(t, A.ScaleType):
            out[m] = t.literals[v.as_long()]
        else:
            out[m] = _number(v)
    return out


def _number(v: Any) -> float:
    """A model's number for a trace: a whole one written without its ``.0``."""
    f = as_float(v)
    return int(f) if z3.is_rational_value(v) and f == int(f) else f  # type: ignore[return-value]


def _horizon(spec: Specification) -> float:
    """Longer than any chain of written deadlines: the sum of every literal duration, plus one."""
    total = 1.0

    def walk(resp: A.Response | None) -> None:
        nonlocal total
        if resp is None:
            return
        for it in resp.items:
            lim = it.occurrence.limit
            if lim is not None:
                for d in (lim.lo, lim.hi):
                    if d is not None and isinstance(d.value, A.IntLit):
                        total += abs(d.value.value) * A.TIME_UNITS.get(d.unit.lower(), 1)
            walk(it.otherwise)
            walk(it.alternative)
        for clause in resp.defeaters:
            walk(clause.response)

    for r in spec.rules:
        walk(r.response)
    return min(total, 1e9)


def final_breaches(spec: Specification, j: Judgement) -> list[Any]:
    """The breaches nothing makes up for: a missed item that has an ``otherwise`` is judged
    by that ``otherwise`` (which may impose nothing, or its own verdicts)."""
    return [v for v in j.verdicts if v.breach and not _has_fallback(spec, v.key)]


_KEY = re.compile(r"^(?P<rule>.+?)(?:\.(?P<clause>\d+))?(?P<path>(?:~\d+)*:\d+(?:/o(?:~\d+)*:\d+)*)$")


def _has_fallback(spec: Specification, key: str) -> bool:
    """Whether the item a verdict key names (``R1.2:0/o~1:0``, the reference's naming) has an
    ``otherwise``; an ``else`` branch (``/e``) or an unknown key counts as having none."""
    m = _KEY.match(key)
    rules = {r.name: r for r in spec.rules}
    if m is None or m["rule"] not in rules:
        return False
    resp: A.Response | None = rules[m["rule"]].response
    if m["clause"] is not None:
        assert resp is not None
        resp = resp.defeaters[int(m["clause"]) - 1].response
    else:
        resp = A.Response(resp.items) if resp is not None else None
    item: A.ResponseItem | None = None
    for part in re.findall(r"/o|~\d+|:\d+", m["path"]):
        if resp is None and part != "/o":
            return False
        if part == "/o":
            resp = item.otherwise if item is not None else None
        elif part.startswith("~"):
            assert resp is not None
            resp = resp.defeaters[int(part[1:]) - 1].response
        else:
            assert resp is not None
            item = resp.items[int(part[1:])]
    return item is not None and item.otherwise is not None


def timeline(spec: Specification, trace: Sequence[Step], j: Judgement, *, limit: int = 40) -> list[str]:
    """The trace as lines a person reads: the values the rules that fired read (each when it
    changes), what occurred, and what the reference semantics made of each obligation."""
    fired = {f.rule for f in j.firings if f.fired}
    shown = set().union(*(reads(r) for r in spec.rules if r.name in fired)) if fired else set()
    out: list[str] = []
    last: dict[str, object] = {}
    for s in trace:
        parts = []
        changed = {k: v for k, v in s.values.items() if k in shown and last.get(k, ...) != v}
        last.update(s.values)
        if changed:
            parts.append("set " + ", ".join(f"{k}={_show(v)}" for k, v in sorted(changed.items())))
        if s.event is not None:
            parts.append(s.event)
        out.append(f"t={_show(s.t)}: " + ("; ".join(parts) if parts else "(time passes)"))
    for f in j.firings:
        if f.fired:
            clause = "default response" if not f.clause else f"clause {f.clause}"
            out.append(f"  {f.rule} fires at t={_show(f.time)} ({clause})")
    open_ = j.pending
    for v in j.verdicts:
        when = "" if v.at is None else f" at t={_show(v.at)}"
        status = "pending (no deadline)" if v in open_ else v.status
        out.append(f"  {v.rule}: {v.describe()} {status}{when}")
    if len(out) > limit:
        out = [*out[: limit - 1], f"  ... ({len(out) - limit + 1} more lines)"]
    return out


def reads(rule: A.Rule) -> set[str]:
    """The names a rule's conditions and deadlines mention (measures among them)."""
    return {n.name for e in visit.rule_expressions(rule) for n in visit.names(e)}


def snapshot(enc: Encoding, model: Any, snap: dict[str, Any], names: set[str]) -> str:
    """``m=value, ...`` for the measures of ``names`` in a snapshot (scale values by literal)."""
    shown = _values(enc, model, {m: v for m, v in snap.items() if m in names})
    return ", ".join(f"{m}={_show(v)}" for m, v in sorted(shown.items()))


def show(model: Any, var: Any) -> str:
    """A model's value of ``var`` as a person reads it (``0.25``, ``true``), not as z3 prints it."""
    v = model.eval(var, model_completion=True)
    if z3.is_bool(v):
        return "true" if z3.is_true(v) else "false"
    return _show(_number(v))


def _show(v: object) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def witness(
    enc: Encoding,
    model: Any,
    reading: Reading,
    *,
    confirm: Callable[[Judgement], bool] | None = None,
    shows: Iterable[A.Rule] = (),
) -> Witness:
    """The model as a witness, judged by the reference semantics: ``confirm`` says whether
    the judgement shows what the witness should (default: the rules hold on it); each rule of
    ``shows`` (a concern or purpose read as a rule) must fire and be met at least once."""
    trace = steps(enc, model)
    j = judge(enc.spec, trace, reading)
    ok = confirm(j) if confirm is not None else not final_breaches(enc.spec, j)
    for rule in shows:
        probe = Specification(enc.spec.definitions, (rule,), path=enc.spec.path)
        pj = judge(probe, trace, Reading(semantics=reading.semantics, untimed=0.0))
        fired = {f.instance for f in pj.firings if f.fired and f.instance is not None}
        waiting = {v.id for v in pj.pending}
        good = [
            i
            for i in fired
            if all(
                not v.breach and (v.negated or v.id not in waiting) for v in pj.verdicts if v.instance == i
            )
        ]
        ok = ok and bool(good)
    return Witness(tuple(trace), tuple(timeline(enc.spec, trace, j)), ok)
