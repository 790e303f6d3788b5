"""The implementations of the rules: each rule's handler is a COP layered method.

For every rule this module builds a layered function (``cosleec.cop.layered``) whose base
implements the default response and which has one variant per clause, registered on the
clause's COP layer (``R1.1``, ``R1.2``, ...; the layers belong to the compiled rule).

How a trigger reaches its variant: the Layer Manager (:mod:`cosleec.runtime.layers`) keeps
each rule's COP composition -- the layer of the clause the context selects, none at the
default -- and replaces it whenever the choice changes. The Manager takes the rule's
composition together with the decision, under its lock; :meth:`Implementations.dispatch`
then calls the rule's layered method with that composition's layer activated for the
call (``cosleec.cop.activate``, on top of whatever layers the caller has active), and COP's
own dispatcher runs the variant of the active layer. A context change after the
trigger never swaps the variant of a decision already taken. A ROS task node has no Layer
Manager: it dispatches under the composition of the layer the Manager's decision names.

Implementations come from tasks (the paper's style, one class per rule) or from
capabilities (one handler per response event, composed here). The same class serves the
embedded Manager and remote task nodes.
"""

from __future__ import annotations

import contextvars
import difflib
import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from cosleec.bulk import quick_init
from cosleec.cop import Layer, Snapshot, activating, layered
from cosleec.errors import clip
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import BindingError
from cosleec.runtime.model import CompiledRule, Obligation, ResponseSpec
from cosleec.runtime.ruleset import RuleSet
from cosleec.runtime.tasks import Task

log = logging.getLogger("cosleec.runtime")

Capability = Callable[[Obligation, Decision], Any]
Handler = Callable[[Decision], Any]


@quick_init
@dataclass(frozen=True, slots=True)
class Ran:
    """The outcome of one implementation run for a decision: a capability, a task method, a fallback.

    ``what`` is ``task``, ``capability`` or ``fallback``; ``event`` the event a capability
    performs (None for a task's method); ``error`` is None when it returned normally.
    """

    what: str
    event: str | None
    error: str | None = None

    @property
    def ok(self) -> bool:
        """True when the implementation returned without raising."""
        return self.error is None

    def to_json(self) -> dict[str, Any]:
        """The fields of a ``task-done`` / ``task-failed`` record."""
        return {"what": self.what, "event": self.event, "error": self.error}


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


class Implementations:
    """Tasks and capabilities bound to a rule set, and each rule's layered handler."""

    def __init__(self, ruleset: RuleSet) -> None:
        self.ruleset = ruleset
        self.tasks: dict[str, Task] = {}
        self.capabilities: dict[str, Capability] = {}
        self._handlers: dict[str, Handler] = {}
        self.failures = 0

    # ------------------------------------------------------------------ binding
    def bind(self, task: Task) -> None:
        """Bind a task to the rule it names; BindingError if the rule or a clause does not exist."""
        if not task.rule:
            raise BindingError([f"task {type(task).__name__} names no rule (set `rule = ...`)"])
        rule = self.ruleset.by_name.get(task.rule)
        if rule is None:
            names = sorted(self.ruleset.by_name)
            near = difflib.get_close_matches(str(task.rule), names, n=1)
            listed = ", ".join(names[:10]) + (f" and {len(names) - 10} more" if len(names) > 10 else "")
            raise BindingError(
                [f"task {type(task).__name__}: no rule named {task.rule!r}"],
                hint=(f"did you mean {near[0]!r}? " if near else "") + f"the rules are {listed}",
            )
        extra = [i for i in task.clauses() if not 1 <= i <= len(rule.clauses)]
        if extra:
            n = len(rule.clauses)
            has = f"clauses 1 to {n}" if n > 1 else "one unless clause, 1" if n else "no unless clause"
            raise BindingError(
                [f"task {type(task).__name__}: rule {rule.name} has no clause {i}" for i in extra],
                hint=f"rule {rule.name} has {has}: number each @hedge(i) as its unless clauses, from 1",
            )
        self.tasks[task.rule] = task
        self._handlers.pop(task.rule, None)

    def capability(self, event: str) -> Callable[[Capability], Capability]:
        """Decorator: ``fn(obligation, decision)`` performs ``event`` whenever a rule obliges it.

        BindingError at once, with the closest names, when no response of the rules names
        ``event``: a misspelt capability would otherwise never run, silently.
        """
        if event not in self.ruleset.responds:
            close = difflib.get_close_matches(event, sorted(self.ruleset.responds), n=3)
            what = f"{event[:80]!r}" + ("..." if len(event) > 80 else "")
            raise BindingError(
                [
                    f"capability {what}: no rule's response names this event"
                    + (f" (did you mean {', '.join(close)}?)" if close else "")
                ]
            )

        def register(fn: Capability) -> Capability:
            self.capabilities[event] = fn
            return fn

        return register

    def missing(self, rules: Iterable[CompiledRule] | None = None) -> list[str]:
        """What the completeness check reports: clauses and events without an implementation."""
        out: list[str] = []
        for r in rules if rules is not None else self.ruleset.rules:
            task = self.tasks.get(r.name)
            out += self._missing_task(r, task) if task is not None else self._missing_capabilities(r)
        return out

    def _missing_task(self, r: CompiledRule, task: Task) -> list[str]:
        out = []
        impls = task.clauses()
        name = type(task).__name__
        if r.default.items and not task.has_default():
            out.append(f"{r.name}: task {name} does not implement the default response")
        for c in r.clauses:
            if c.response is not None and c.index not in impls:
                out.append(
                    f"{c.layer}: task {name} has no @hedge({c.index}) implementation (unless {c.text})"
                )
        fallbacks: set[str] = set()
        for spec in (r.default, *(c.response for c in r.clauses)):
            if spec is not None:
                for it in spec.items:
                    _events(it.otherwise, fallbacks)
        if not hasattr(task, "fallback"):
            for ev in sorted(fallbacks - set(self.capabilities)):
                out.append(f"{r.name}: no capability or {name}.fallback for `otherwise` event {ev}")
        return out

    def _missing_capabilities(self, r: CompiledRule) -> list[str]:
        needed: set[str] = set()
        _events(r.default, needed)
        for c in r.clauses:
            _events(c.response, needed)
        return [
            f"{r.name}: no task and no capability for response event {ev}"
            for ev in sorted(needed - set(self.capabilities))
        ]

    def check(self, rules: Iterable[CompiledRule] | None = None) -> None:
        """Raise BindingError listing everything :meth:`missing` finds."""
        missing = self.missing(rules)
        if missing:
            raise BindingError(missing)

    # ------------------------------------------------------------------ dispatch
    def handler(self, rule: CompiledRule) -> Handler:
        """The rule's layered method (built on first use, rebuilt after a new bind)."""
        h = self._handlers.get(rule.name)
        if h is None:
            h = self._build(rule)
            self._handlers[rule.name] = h
        return h

    def _build(self, rule: CompiledRule) -> Handler:
        task = self.tasks.get(rule.name)
        compose = self.compose
        default_impl: Handler = task.default if task is not None else compose

        @layered(method=False)  # type: ignore[untyped-decorator]
        def handle(decision: Decision) -> Any:
            return default_impl(decision)

        impls = task.clauses() if task is not None else {}
        for c, layer in zip(rule.clauses, rule.layers):
            impl = impls.get(c.index, compose)

            def variant(decision: Decision, *, proceed: Any, impl: Handler = impl) -> Any:
                return impl(decision)  # a clause replaces the default: proceed is not called

            handle.variant(layer)(variant)
        handle.__qualname__ = handle.__name__ = f"rule_{rule.name}"
        return handle  # type: ignore[no-any-return]

    def prepare(self, rules: Iterable[CompiledRule] | None = None) -> None:
        """Build the layered handler of every rule bound to a task now (call after binding,
        before triggers); a rule without a task needs none (:meth:`dispatch`)."""
        for rule in rules if rules is not None else self.ruleset.rules:
            if rule.name in self.tasks:
                self.handler(rule)

    def compose(self, decision: Decision) -> None:
        """Capability style: run the handler of every event the decision obliges.

        Every capability runs even when an earlier one raised (``A and B``: B still runs);
        each outcome is collected by the dispatch that called it, and the first failure is
        raised again once all have run.
        """
        errors = [ran for ran in self._capabilities(decision, set()) if not ran.ok]
        if errors:
            raise _Failed(errors)

    def _capabilities(self, decision: Decision, handled: set[str]) -> list[Ran]:
        out: list[Ran] = []
        for ob in decision.obligations:
            if ob.negated:
                continue
            cap = self.capabilities.get(ob.event)
            if cap is None:
                continue
            handled.add(ob.event)
            self._call(cap, ob, decision, out)
        runs = _RUNS.get()
        if runs is not None:
            runs.extend(out)
        return out

    def dispatch(
        self, rule: CompiledRule, decision: Decision, composition: Snapshot | None = None
    ) -> list[Ran]:
        """Run the rule's layered method for ``decision`` under ``composition``; a failing task
        never stops the caller.

        ``composition`` is the rule's COP composition as the Layer Manager had it when the
        decision was made (the embedded Manager passes it). Without one -- a task node,
        which has no Layer Manager of its own -- it is the composition of the layer the
        decision names, as the Manager chose it. Returns what ran, each with its outcome
        (empty for a decision without a clause, which runs nothing); a failure is also
        counted in :attr:`failures`.
        """
        if decision.clause is None:
            return []
        if composition is None:
            if (
                not 0 <= decision.clause <= len(rule.clauses)
                or rule.layer_of(decision.clause) != decision.layer
            ):
                self.failures += 1  # a decision from elsewhere that contradicts itself: run nothing
                log.error(
                    "decision %s of %s: clause %s and layer %s disagree",
                    decision.id,
                    rule.name,
                    decision.clause,
                    decision.layer,
                )
                return [Ran("task", None, f"clause {decision.clause} and layer {decision.layer} disagree")]
            composition = rule.compositions[decision.clause]
        # the decision's layers active (added to whatever the caller has active, never replacing
        # it) around the rule's layered method; without a task, every variant of that method is
        # the capabilities of the decision's events (compose), so they are called directly
        layers = composition.layers
        if rule.name in self.tasks:
            return self._guarded("task", rule, decision, activating, layers, self.handler(rule), decision)
        return self.capabilities_under(layers, rule, decision)

    def capabilities_under(
        self, layers: tuple[Layer, ...], rule: CompiledRule, decision: Decision
    ) -> list[Ran]:
        """(A rule bound to no task.) Run the capability of each event ``decision`` requires,
        with ``layers`` active: what :meth:`dispatch` runs for such a rule, for the hot path
        that found the composition's layers itself (:mod:`cosleec.runtime.plans`)."""
        return self._guarded("task", rule, decision, activating, layers, self._capabilities, decision, set())

    def capability_under(
        self, layers: tuple[Layer, ...], rule: CompiledRule, decision: Decision, ob: Obligation
    ) -> list[Ran]:
        """(A rule bound to no task.) What :meth:`capabilities_under` does for a decision that
        requires one event, ``ob``'s: its capability run with ``layers`` active (none
        registered: the layers entered and left, a task outcome), a failure logged and
        counted, never raised."""
        runs: list[Ran] = []
        token = _RUNS.set(runs)
        try:
            cap = self.capabilities.get(ob.event)
            if cap is None:
                activating(layers, _nothing)
                runs.append(_TASK_DONE)
            else:
                activating(layers, self._call, cap, ob, decision, runs)
        except Exception as e:  # (the layers' activation failed: a task failure, as _guarded says)
            self.failures += 1
            log.exception("task for %s failed on decision %s", rule.name, decision.id)
            runs.append(Ran("task", None, _describe(e)))
        finally:
            _RUNS.reset(token)
        return runs

    def _call(self, cap: Capability, ob: Obligation, decision: Decision, runs: list[Ran]) -> None:
        """Run one capability, its outcome collected in ``runs`` (what :meth:`_capabilities`
        does for each event)."""
        try:
            cap(ob, decision)
            ran = _DONE.get(ob.event)
            if ran is None:  # (an outcome is an immutable value: one per event serves every run)
                ran = _DONE[ob.event] = Ran("capability", ob.event)
            runs.append(ran)
        except Exception as e:
            self.failures += 1
            log.exception("capability %s failed on decision %s of %s", ob.event, decision.id, decision.rule)
            runs.append(Ran("capability", ob.event, _describe(e)))

    def dispatch_fallback(self, rule: CompiledRule, decision: Decision) -> list[Ran]:
        """Run an ``otherwise`` decision: capabilities for its events, else the task's ``fallback``.

        Returns what ran, each with its outcome (every capability runs, whatever the others do).
        """
        fallback = getattr(self.tasks.get(rule.name), "fallback", None)
        handled: set[str] = set()
        out = self._capabilities(decision, handled)
        if fallback is not None and any(
            not o.negated and o.event not in handled for o in decision.obligations
        ):
            out += self._guarded("fallback", rule, decision, fallback, decision)
        return out

    def _guarded(
        self, what: str, rule: CompiledRule, decision: Decision, run: Callable[..., object], *args: object
    ) -> list[Ran]:
        """Run a task's code; a failure is logged and counted, never raised into the caller.

        Capabilities composed inside it report their own outcomes; a task method's outcome
        is one more (``event`` None).
        """
        runs: list[Ran] = []
        token = _RUNS.set(runs)
        try:
            run(*args)
            if what == "task" and not runs:
                runs.append(Ran("task", None))
        except _Failed:
            pass  # composed capabilities failed: their outcomes are already in `runs`
        except Exception as e:
            self.failures += 1
            log.exception("%s for %s failed on decision %s", what, rule.name, decision.id)
            runs.append(Ran(what, None, _describe(e)))
        finally:
            _RUNS.reset(token)
        return runs


class _Failed(Exception):
    """Raised by :meth:`Implementations.compose` after every capability ran, when some failed."""

    def __init__(self, errors: list[Ran]) -> None:
        super().__init__("; ".join(f"{r.event}: {r.error}" for r in errors))
        self.errors = errors


# a capability's successful outcome per event (immutable: shared by every run); bounded by
# the events declared in the rule sets a process loads
_DONE: dict[str, Ran] = {}

_TASK_DONE = Ran("task", None)


def _nothing() -> None:
    """What runs under a decision's layers when no capability is registered for its event."""


# the outcomes of the capabilities composed inside one guarded run (a task may call compose)
_RUNS: contextvars.ContextVar[list[Ran] | None] = contextvars.ContextVar("cosleec_runs", default=None)


def _describe(e: BaseException) -> str:
    """An exception in one bounded line: ``ValueError: no gripper`` (at most 300 characters)."""
    try:
        text = f"{type(e).__name__}: {e}"
    except Exception:  # an exception whose str() fails must not stop the next capability
        text = f"{type(e).__name__}: <cannot be shown>"
    return clip(text, 300)
