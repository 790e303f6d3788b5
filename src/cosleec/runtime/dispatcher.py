"""Task-side dispatch: each rule's handler is a COP layered method (Table 1 of the paper).

For every rule the dispatcher builds a layered function whose base is the implementation
of the default obligation and which has one variant per hedge clause, each bound to the
clause's layer (``R1.1``, ``R1.2``, ...). The layers of one rule form an exclusive hedge
group; a decision activates exactly the layer of its clause, so the COP runtime runs that
clause's implementation -- or the base when the default applies.

Implementations come from tasks (the paper's style, one class per rule) or from
capabilities (one handler per response event, composed by the runtime). The same class
serves the embedded Manager and remote task nodes (ROS).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from cosleec.cop import HedgeGroup, Layer, layered, using_context
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError
from cosleec.runtime.model import CompiledRule, Obligation, ResponseSpec, RuleSet
from cosleec.runtime.tasks import Task

log = logging.getLogger("cosleec.runtime")

Capability = Callable[[Obligation, Decision], Any]


def _events(spec: ResponseSpec | None, out: set[str]) -> None:
    if spec is None:
        return
    for it in spec.items:
        if not it.negated:
            out.add(it.event)
        _events(it.otherwise, out)
        _events(it.alternative, out)
    for c in spec.clauses:
        _events(c.response, out)


def _is_clause(i: int) -> Callable[[Decision], bool]:
    """The predicate of layer R.i: the decision chose clause i (the Layer Manager's verdict)."""

    def holds(decision: Decision) -> bool:
        return decision.clause == i

    return holds


def _clause_index(decision: Decision) -> int | None:
    """The group member of the decision's clause: the Layer Manager has already chosen it."""
    c = decision.clause
    return c - 1 if c else None


class _Probe:
    """Stands in for a decision of a given clause while chains are warmed."""

    def __init__(self, clause: int) -> None:
        self.clause = clause


class TaskDispatcher:
    def __init__(self, ruleset: RuleSet) -> None:
        self.ruleset = ruleset
        self.tasks: dict[str, Task] = {}
        self.capabilities: dict[str, Capability] = {}
        self.handlers: dict[str, Callable[[Decision], Any]] = {}
        self.layers: dict[str, Layer] = {}
        self.failures = 0

    # ------------------------------------------------------------------ binding
    def bind(self, task: Task) -> None:
        if not task.rule:
            raise BindingError([f"task {type(task).__name__} names no rule (set `rule = ...`)"])
        try:
            rule = self.ruleset.rule(task.rule)
        except KeyError:
            raise BindingError([f"task {type(task).__name__}: no rule named {task.rule!r}"]) from None
        extra = [i for i in task.clauses() if not 1 <= i <= len(rule.clauses)]
        if extra:
            raise BindingError(
                [f"task {type(task).__name__}: rule {rule.name} has no clause {i}" for i in extra]
            )
        self.tasks[task.rule] = task
        self.handlers.pop(task.rule, None)

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        def register(fn: Capability) -> Capability:
            self.capabilities[event] = fn
            return fn

        return register

    def missing(self, rules: list[CompiledRule] | None = None) -> list[str]:
        """What the completeness check reports: clauses and events without an implementation."""
        out = []
        for r in rules if rules is not None else self.ruleset.rules:
            task = self.tasks.get(r.name)
            if task is not None:
                impls = task.clauses()
                if r.default.items and not task.has_default():
                    out.append(
                        f"{r.name}: task {type(task).__name__} does not implement the default response"
                    )
                for c in r.clauses:
                    if c.response is not None and c.index not in impls:
                        out.append(
                            f"{c.layer}: task {type(task).__name__} has no @hedge({c.index}) "
                            f"implementation (unless {c.text})"
                        )
                fallbacks: set[str] = set()
                for spec in (r.default, *(c.response for c in r.clauses)):
                    if spec is not None:
                        for it in spec.items:
                            _events(it.otherwise, fallbacks)
                for ev in sorted(fallbacks - set(self.capabilities)):
                    if not hasattr(task, "fallback"):
                        out.append(
                            f"{r.name}: no capability or {type(task).__name__}.fallback for `otherwise` event {ev}"
                        )
            else:
                needed: set[str] = set()
                _events(r.default, needed)
                for c in r.clauses:
                    _events(c.response, needed)
                for ev in sorted(needed - set(self.capabilities)):
                    out.append(f"{r.name}: no task and no capability for response event {ev}")
        return out

    def check(self, rules: list[CompiledRule] | None = None) -> None:
        missing = self.missing(rules)
        if missing:
            raise BindingError(missing)

    # ------------------------------------------------------------------ dispatch
    def handler(self, rule: CompiledRule) -> Callable[[Decision], Any]:
        h = self.handlers.get(rule.name)
        if h is None:
            h = self._build(rule)
            self.handlers[rule.name] = h
        return h

    def _build(self, rule: CompiledRule) -> Callable[[Decision], Any]:
        task = self.tasks.get(rule.name)
        layers = []
        for c in rule.clauses:
            la = self.layers.get(c.layer)
            if la is None:
                la = Layer(c.layer, when=_is_clause(c.index))
                self.layers[c.layer] = la
            layers.append(la)
        compose = self.compose
        default_impl: Callable[[Decision], Any] = task.default if task is not None else compose

        group = HedgeGroup(rule.name, layers, selector=_clause_index)

        @layered(hedges=group, method=False, compile_prologue=False)  # type: ignore[untyped-decorator]
        def handle(decision: Decision) -> Any:
            return default_impl(decision)

        impls = task.clauses() if task is not None else {}
        for c, la in zip(rule.clauses, layers):
            impl = impls.get(c.index, compose)

            def variant(decision: Decision, *, proceed: Any, impl: Callable[[Decision], Any] = impl) -> Any:
                return impl(decision)

            handle.variant(la)(variant)
        handle.__qualname__ = handle.__name__ = f"rule_{rule.name}"
        return handle  # type: ignore[no-any-return]

    def warm(self) -> None:
        """Build every rule's handler and the COP chain of every clause now, so that the first
        trigger of a clause pays no construction cost (start-up work, not trigger latency)."""
        from cosleec.cop.state import RT, dyn_get

        for rule in self.ruleset.rules:
            lf = self.handler(rule).layered  # type: ignore[attr-defined]
            for clause in range(len(rule.clauses) + 1):
                with using_context(_Probe(clause)):
                    lf.chain_for(RT.state, dyn_get())

    def compose(self, decision: Decision) -> None:
        """Capability style: run the handler of every event the decision obliges."""
        for ob in decision.obligations:
            if ob.negated:
                continue
            cap = self.capabilities.get(ob.event)
            if cap is not None:
                cap(ob, decision)

    def dispatch(self, rule: CompiledRule, decision: Decision) -> bool:
        """Run the implementation of the decision's clause; a failing task never stops the caller."""
        try:
            with using_context(decision):
                self.handler(rule)(decision)
            return True
        except Exception:
            self.failures += 1
            log.exception("task for %s failed on decision %s", rule.name, decision.id)
            return False

    def dispatch_fallback(self, rule: CompiledRule, decision: Decision) -> bool:
        task = self.tasks.get(rule.name)
        try:
            handled = set()
            for ob in decision.obligations:
                cap = self.capabilities.get(ob.event)
                if cap is not None and not ob.negated:
                    cap(ob, decision)
                    handled.add(ob.event)
            fb = getattr(task, "fallback", None)
            if fb is not None and any(not o.negated and o.event not in handled for o in decision.obligations):
                fb(decision)
            return True
        except Exception:
            self.failures += 1
            log.exception("fallback for %s failed on decision %s", rule.name, decision.id)
            return False
