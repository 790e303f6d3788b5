"""Reload: new rules in force while the runtime runs, as *check → plan → apply*, in one step.

:func:`check` refuses (ReloadError, nothing changed) rules the runtime could not enforce
faithfully: priorities naming rules the new rules lack, a bound task or capability that
does not fit them, a rule left without an implementation when the bindings were checked,
a measure that holds a value and changes its type. :class:`Plan` says what the swap will
do -- which obligations are kept (their item found again by key, or as the one item of
their rule with their event and sense), withdrawn or dropped, which decisions are
withheld, which values are carried -- and :func:`apply` does it, each change with its
record (``reloaded``, ``obligation`` withdrawn, ``dropped``, ``withheld``, ``layers``).
The Manager runs all three under one lock, between two decisions, never within one
(:meth:`Manager.reload <cosleec.runtime.Manager.reload>` says what users see).

What users see (:meth:`Manager.reload`):

- *Obligations and prohibitions* in force (held decisions and pending ``otherwise``
  chains included) are kept when their rule still exists: a rule of the same name
  whose response still has the item they came from (the same item key with the same
  event and sense, or else the one item of the rule with that event and sense) --
  exactly what a restart on the journal with the new rules keeps, so a crash right
  after a reload changes nothing. A kept one keeps its window (it was decided under
  the old text) and takes the new item's ``otherwise``. The others are *withdrawn*
  (an ``obligation`` record with status ``withdrawn`` each): they can no longer be
  violated and their ``otherwise`` never runs; a decision of a removed rule not yet
  run (held, or an ``otherwise`` due at the reload) is ``withheld``; a miss waiting
  for its late event is ``dropped``. A decision already handed to its implementation
  runs as it was decided.
- *Context*: the values of measures still declared are kept (a scale value by its
  literal); those of measures no longer declared are ``dropped`` (recorded); new
  measures start unknown. ``max_age`` applies to the measures declared now (kept for
  the others: a later reload that declares them again ages them again).
- *Layers* are recomputed for the new rules under the current context (a ``layers``
  record: a rule added switches from the base, one removed to it).
- *Priorities*: the new rules' own and the caller's (``priorities``; None keeps those
  given to the Manager); activations in force that a new priority orders meet now
  (cancellation), as after a restore.
- *Implementations*: tasks bound to rules still there stay bound (``tasks`` binds more
  or replaces them, ``capabilities`` adds handlers for new response events); a task of
  a removed rule is unbound. A decision runs with the implementations bound when it
  was made.

One ``reloaded`` record says what changed: ``previous_hash`` and ``current_hash``
(``Manager.rules_hash``), rule names ``added``, ``removed`` and ``changed`` (in both, with
another canonical text), the obligation ids ``withdrawn`` and ``relinked`` (kept, with
a new item key), the decisions ``withheld``, measures added and removed, the
priorities. With a journal it is one commit: a restart with the new rules restores
what was kept and nothing withdrawn; a restart with the old rules is a restart with
changed rules (``restored`` says ``rules_changed``; what they lack is ``dropped``).

Refused with :class:`ReloadError` -- nothing changes, nothing is recorded, the old rules
stay in force -- when the Manager could not enforce ``rules`` faithfully: a measure
that holds a value and changes its type (boolean, numeric, scale), or a scale that
loses the literal its value is; a priority naming a rule the new rules lack (or a
cycle); a bound task naming a clause its rule no longer has, or a task or capability
for a rule or event the new rules lack; and, when ``Manager.start`` checked the bindings,
a rule, clause or ``otherwise`` left without an implementation. A Manager that is
closed or whose journal failed raises as for any step.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from cosleec.errors import show
from cosleec.lang import CANCEL, HedgeSemantics, Printer, clause_semantics_for
from cosleec.lang import ast as A
from cosleec.lang import pairs as priority_pairs
from cosleec.records import Kind
from cosleec.runtime.context import Context
from cosleec.runtime.core import Core
from cosleec.runtime.enforcer import Enforcer
from cosleec.runtime.errors import BindingError, ConfigurationError, ReloadError
from cosleec.runtime.gate import Gate
from cosleec.runtime.implementations import Capability, Implementations
from cosleec.runtime.jobs import Job
from cosleec.runtime.layers import LayerManager, LayerSwitch
from cosleec.runtime.model import CompiledRule, ItemSpec
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.options import given_priorities
from cosleec.runtime.priorities import Priorities
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.steps import Step
from cosleec.runtime.tasks import Task

_REFUSED = "reload refused, the rules in force stay"


@dataclass(frozen=True)
class Reloaded:
    """What :meth:`Manager.reload` changed (its ``reloaded`` record says the same).

    The hashes are :attr:`RuleSet.digest` (sha256 of the canonical text) before and after;
    ``added``/``removed``/``changed`` are rule names (changed: in both, with a different
    canonical text); ``withdrawn`` the ids of the obligations and prohibitions that ended
    because what they came from is gone.
    """

    previous_hash: str
    current_hash: str
    added: tuple[str, ...]
    removed: tuple[str, ...]
    changed: tuple[str, ...]
    withdrawn: tuple[int, ...]


def arguments(
    rules: object, priorities: Iterable[str | tuple[str, str]] | None, kept: list[str | tuple[str, str]]
) -> list[str | tuple[str, str]]:
    """The caller's priorities for a reload to ``rules`` (None: ``kept``), or TypeError /
    ReloadError for arguments that are not what ``reload`` takes."""
    if not isinstance(rules, RuleSet):
        raise TypeError(
            f"reload needs a RuleSet, not {type(rules).__name__}: "
            "use RuleSet.from_file(path), RuleSet.from_text(text) or RuleSet.from_spec(spec)"
        )
    try:
        return kept if priorities is None else given_priorities(priorities)
    except ConfigurationError as e:
        raise ReloadError(f"{_REFUSED}: {e}") from None


def swap(
    core: Core,
    enforcer: Enforcer,
    gate: Gate,
    new: tuple[RuleSet, Priorities, Implementations],
    due: list[Job],
    step: Step,
) -> tuple[Reloaded, list[Job]]:
    """(In ``step``, after :func:`check`.) Put the ``new`` rules in force; ``due`` are the
    decisions due now (those of a removed rule are withheld). Returns what changed, and
    the parts that may run now."""
    rules, prio, impl = new
    plan = Plan.make(core, [*gate.held.values(), *due], rules, prio, impl)
    apply(plan, core, enforcer, gate, step.now, step)
    return plan.result, gate.ready([job for job in due if job.rule.name in rules.by_name], step.now, step)


def check(
    core: Core,
    rules: RuleSet,
    given: list[str | tuple[str, str]],
    tasks: list[Task],
    capabilities: dict[str, Capability],
    *,
    checked: bool,
) -> tuple[Priorities, Implementations]:
    """The priorities and implementations ``rules`` would run with, or ReloadError; also
    refuses values the new rules cannot read (:func:`carried`). Changes nothing."""
    try:
        prio = Priorities.build(
            (r.name for r in rules.rules),
            [*priority_pairs(rules.spec), *given],
            core.priorities.semantics,
            core.priorities.lead,
        )
    except ConfigurationError as e:
        raise ReloadError(
            f"{_REFUSED}: {e}", hint="give the priorities for the new rules: reload(rules, priorities=[...])"
        ) from None
    impl = _bound(core.implementations, rules, tasks, capabilities, checked=checked)
    carried(core.context, rules)
    return prio, impl


def same_semantics(core: Core, rules: RuleSet, given: HedgeSemantics | None) -> None:
    """ReloadError when ``rules`` would be read with other clause semantics than the rules in
    force (their file declares another, or contradicts ``given``, the caller's option): the
    layers of a running Manager keep one semantics, so that change needs a restart."""
    try:
        wanted = clause_semantics_for(rules.spec, given)
    except ConfigurationError as e:
        raise ReloadError(f"{_REFUSED}: {e.message}", hint=e.hint, where=e.where) from None
    if wanted != core.layers.semantics:
        raise ReloadError(
            f"{_REFUSED}: the new rules are read with clause semantics {wanted}, the rules in force "
            f"with {core.layers.semantics}",
            hint="a running Manager keeps one clause semantics: restart it to change the semantics "
            "block, or keep the block as it was",
        )


def _bound(
    old: Implementations,
    rules: RuleSet,
    tasks: list[Task],
    capabilities: dict[str, Capability],
    *,
    checked: bool,
) -> Implementations:
    """The implementations ``rules`` would run with: the tasks bound still fitting, and the new ones."""
    impl = Implementations(rules)
    # every capability is kept, even for an event no rule obliges now: a later reload may again
    impl.capabilities.update(old.capabilities)
    replaced = {t.rule for t in tasks}
    try:
        for t in old.tasks.values():
            if t.rule in rules.by_name and t.rule not in replaced:
                impl.bind(t)
        for t in tasks:
            impl.bind(t)
        for event, fn in capabilities.items():
            impl.capability(event)(fn)
        if checked:  # start() checked the rules it began with: the new ones are held to it too
            impl.check()
    except BindingError as e:
        raise ReloadError(
            f"{_REFUSED}: {e}",
            hint="bind the new rules' implementations in the reload: reload(rules, tasks=[...], "
            "capabilities={event: handler})",
        ) from None
    return impl


def carried(context: Context, rules: RuleSet) -> dict[str, Any]:
    """The values (stored form) ``context`` keeps under ``rules``, or ReloadError when a value
    held cannot be read as the new measure's type (changes nothing)."""
    out: dict[str, Any] = {}
    problems: list[str] = []
    for name, v in context.values.items():
        new = rules.measures.get(name)
        if new is None:
            continue  # no longer declared: dropped
        old = context.measures[name]
        shown = show(old.external(v), 40)
        if new.kind != old.kind:
            problems.append(
                f"measure {name} holds {shown} as a {old.kind}, and the new rules make it {new.kind}"
            )
        elif new.kind == "scale":
            literal = old.literals[int(v)]
            if literal in new.literals:
                out[name] = new.literals.index(literal)
            else:
                problems.append(
                    f"measure {name} holds {shown}, a literal its new scale "
                    f"({', '.join(new.literals)}) does not have"
                )
        else:
            out[name] = v
    if problems:
        raise ReloadError(
            f"{_REFUSED}: {'; '.join(problems)}",
            hint="keep the measure's type (and the literal its value is), or give the measure "
            "a new name: its value then starts unknown",
        )
    return out


def item_of(t: Tracked, rules: RuleSet) -> ItemSpec | None:
    """The response item of ``rules`` an obligation came from, when it was made under other
    rules (a journal's, rules before a reload): by its key, or -- when the rule was edited
    around it -- the one item of its rule with the same event and sense. None when there is
    none: the rules no longer have it."""
    item = rules.items.get(t.obligation.item)
    if item is not None and item.event == t.event and item.negated == t.prohibition:
        return item
    rule = rules.by_name.get(t.rule)
    if rule is None:
        return None
    same = [
        it
        for resp in rule.responses()
        for it in resp.walk()
        if it.event == t.event and it.negated == t.prohibition
    ]
    return same[0] if len(same) == 1 else None


@dataclass
class Plan:
    """What a reload to ``rules`` will do (made under the lock, after :func:`check`)."""

    rules: RuleSet
    priorities: Priorities
    implementations: Implementations
    values: dict[str, Any]
    kept: list[tuple[Tracked, ItemSpec]]
    withdrawn: list[Tracked]
    forgotten: list[Tracked]
    gone: list[Job]
    result: Reloaded

    @classmethod
    def make(
        cls, core: Core, held: list[Job], rules: RuleSet, prio: Priorities, impl: Implementations
    ) -> Plan:
        """The plan for ``rules`` given what is in force and ``held`` (held decisions and those due now)."""
        withdrawn: list[Tracked] = []
        kept: list[tuple[Tracked, ItemSpec]] = []
        for t in sorted(core.tracker.active, key=lambda t: t.id):
            item = item_of(t, rules)
            if item is None:
                withdrawn.append(t)
            else:
                kept.append((t, item))
        before, after = _texts(core.ruleset), _texts(rules)
        result = Reloaded(
            previous_hash=core.ruleset.digest,
            current_hash=rules.digest,
            added=tuple(n for n in after if n not in before),
            removed=tuple(n for n in before if n not in after),
            changed=tuple(n for n in after if n in before and before[n] != after[n]),
            withdrawn=tuple(t.id for t in withdrawn),
        )
        return cls(
            rules=rules,
            priorities=prio,
            implementations=impl,
            values=carried(core.context, rules),
            kept=kept,
            withdrawn=withdrawn,
            forgotten=[t for t in core.tracker.misses() if item_of(t, rules) is None],
            gone=[job for job in held if job.rule.name not in rules.by_name],
            result=result,
        )

    def record(self, core: Core) -> dict[str, Any]:
        """The ``reloaded`` record's data."""
        r, old, new = self.result, core.ruleset, self.rules
        return {
            "previous_hash": r.previous_hash,
            "current_hash": r.current_hash,
            "added": list(r.added),
            "removed": list(r.removed),
            "changed": list(r.changed),
            "withdrawn": list(r.withdrawn),
            "relinked": [t.id for t, item in self.kept if t.obligation.item != item.key],
            "withheld": [job.decision.id for job in self.gone],
            "measures_added": sorted(new.measures.keys() - old.measures.keys()),
            "measures_removed": sorted(old.measures.keys() - new.measures.keys()),
            "priorities": sorted([h, lo] for h, lo in self.priorities.declared),
        }


def apply(plan: Plan, core: Core, enforcer: Enforcer, gate: Gate, now: float, step: Step) -> None:
    """Put ``plan.rules`` in force at ``now`` (under the lock, as part of ``step``)."""
    step.emit(Kind.RELOADED, plan.record(core), now)
    dropped = sorted(n for n in core.context.values if n not in plan.values)
    switches, newly = _swap(plan, core)
    enforcer.reset()  # what conflict-aware priorities force: found again, for the new priorities
    gate.look_again()  # every held decision is examined again
    _withdraw(plan, core, now, step)
    for job in plan.gone:
        was_held = gate.held.pop(job.decision.id, None) is not None
        if job.record is not None and not was_held:
            job.record["dispatch"] = "withheld"
        step.emit(
            Kind.WITHHELD,
            {
                "decision": job.decision.id,
                "rule": job.decision.rule,
                "reason": f"its rule {job.decision.rule} was removed by a reload",
            },
        )
        if core.journal:
            step.change.outbox[job.decision.id] = None
    for name in dropped:
        step.emit(Kind.DROPPED, {"what": f"measure {name}: the rules no longer declare it"})
        if core.journal:
            step.change.context[name] = None
    core.switched(switches, step)
    if newly and plan.priorities.semantics == CANCEL:
        enforcer.meet(core.tracker.active, now, step)


def _swap(plan: Plan, core: Core) -> tuple[list[LayerSwitch], bool]:
    """The rules, and what is computed from them, in force; the layer switches, and whether
    priorities were added."""
    rules = plan.rules
    context = Context(rules.measures, {n: a for n, a in core.max_age.items() if n in rules.measures})
    context.values.update(plan.values)
    context.stamps.update((n, core.context.stamps[n]) for n in plan.values)
    context.version = core.context.version
    layers = LayerManager(rules, core.layers.semantics, core.layers.unknown)
    layers.recompute_all(context.values)
    layers.version = core.layers.version
    switches = _switches(core.ruleset, core.layers, rules, layers)
    newly = bool(plan.priorities.above - core.priorities.above)
    core.install(rules, context, layers, plan.priorities, plan.implementations)
    core.index()
    return switches, newly


def _withdraw(plan: Plan, core: Core, now: float, step: Step) -> None:
    """What the new rules lack ends, each with its record; what they keep takes its new item."""
    for t in plan.withdrawn:
        core.tracker.withdraw(t, now)
        core.track(t, step)
    for t, item in plan.kept:
        moved = t.obligation.item != item.key
        t.obligation = dataclasses.replace(t.obligation, otherwise=item.otherwise, item=item.key)
        if moved and core.journal:
            step.change.obligations[t.id] = t.to_json()
    for t in plan.forgotten:
        core.tracker.forget(t)
        step.emit(
            Kind.DROPPED,
            {"what": f"obligation {t.id} ({t.rule}: {t.obligation.describe()}): the rules no longer have it"},
        )
        if core.journal:
            step.change.obligations[t.id] = None


def _texts(rules: RuleSet) -> dict[str, str]:
    """Each rule's canonical text, by name, in rule order: what a reload compares to tell a changed rule."""
    dialect = rules.spec.dialect if rules.spec.dialect is not A.Dialect.PAPER else A.Dialect.TK
    printer = Printer(rules.spec, dialect)
    return {r.name: printer.rule(r.ast) for r in rules.rules}


def _switches(old: RuleSet, was: LayerManager, new: RuleSet, now: LayerManager) -> list[LayerSwitch]:
    """The layer switches of a reload, by rule name: a rule added switches from the base (None),
    one removed to it; rules in the new order, then the removed ones."""
    before = {r.name: _layer(r, st.clause) for r, st in zip(old.rules, was.status)}
    after = {r.name: _layer(r, st.clause) for r, st in zip(new.rules, now.status)}
    names = [*after, *(n for n in before if n not in after)]
    return [LayerSwitch(n, before.get(n), after.get(n)) for n in names if before.get(n) != after.get(n)]


def _layer(rule: CompiledRule, clause: int | None) -> str | None:
    """A rule's active layer as a ``layers`` record names it: None the base, ``"?"`` undetermined."""
    return "?" if clause is None else rule.layer_of(clause)
