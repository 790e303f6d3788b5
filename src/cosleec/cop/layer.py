"""Layers and groups of layers.

A :class:`Layer` is a named, first-class object with no behaviour of its own: partials
registered on layered functions give it behaviour. A layer with a ``when`` predicate is a
*predicate layer*: a hedge group selects it at dispatch time from the context snapshot.

A :class:`LayerGroup` makes its members mutually exclusive. With a selection policy it is
a *hedge group* (SLEEC: all ``unless`` clauses of one rule): at each dispatch the policy
picks at most one member from the predicates' values -- ``last`` (SLEEC: the last clause
whose condition holds) or ``nested`` (the CO-SLEEC paper's formula), or any callable.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any, Literal

from cosleec.cop.errors import DefinitionError

Predicate = Callable[[Any], object]
Policy = Callable[[Sequence[bool]], "int | None"]

_ids = itertools.count()


class Layer:
    """A named layer. Identity matters, not the name: two layers may share a name."""

    __slots__ = ("__weakref__", "_enter", "_exit", "group", "id", "name", "predicate", "priority")

    def __init__(self, name: str, *, when: Predicate | None = None, priority: int = 0) -> None:
        self.name = name
        self.predicate = when
        self.priority = priority
        self.group: LayerGroup | None = None
        self.id = next(_ids)
        self._enter: list[Callable[[Layer], None]] = []
        self._exit: list[Callable[[Layer], None]] = []

    def on_enter(self, hook: Callable[[Layer], None]) -> Callable[[Layer], None]:
        """Call ``hook(layer)`` on every effective activation (SD/E38)."""
        from cosleec.cop import state

        self._enter.append(hook)
        state.HOOKED.count += 1
        state.hooks_changed()
        return hook

    def on_exit(self, hook: Callable[[Layer], None]) -> Callable[[Layer], None]:
        from cosleec.cop import state

        self._exit.append(hook)
        state.HOOKED.count += 1
        state.hooks_changed()
        return hook

    def __repr__(self) -> str:
        return f"Layer({self.name!r})"


# ---------------------------------------------------------------- selection policies


def policy_last(values: Sequence[bool]) -> int | None:
    """SLEEC: the last member, in declared order, whose predicate holds."""
    for i in range(len(values) - 1, -1, -1):
        if values[i]:
            return i
    return None


def policy_nested(values: Sequence[bool]) -> int | None:
    """The CO-SLEEC paper's formula: member i iff predicates 1..i hold and i+1 does not."""
    k = 0
    for v in values:
        if not v:
            break
        k += 1
    return k - 1 if k else None


def policy_first(values: Sequence[bool]) -> int | None:
    """The first member whose predicate holds (generic COP; never used for SLEEC)."""
    for i, v in enumerate(values):
        if v:
            return i
    return None


POLICIES: dict[str, Policy] = {"last": policy_last, "nested": policy_nested, "first": policy_first}

OnError = Literal["raise", "default"] | str


class LayerGroup:
    """Mutually exclusive layers; with a ``policy``, a hedge group selecting by predicate.

    ``exclusion="strict"`` (default): explicitly activating a second member while one is
    active raises :class:`ExclusionError` and changes nothing. ``"weak"``: the new member
    replaces the old one.

    ``selector`` (optional) maps the context snapshot directly to a member index, instead of
    evaluating predicates under a policy.

    ``on_error`` says what a dispatch does when a member's predicate raises: ``"raise"``
    (default: abort with :class:`HedgeEvaluationError`), ``"default"`` (select no member),
    or the name of a member to select (a conservative choice).
    """

    def __init__(
        self,
        name: str,
        layers: Sequence[Layer],
        *,
        policy: str | Policy | None = None,
        exclusion: Literal["strict", "weak"] = "strict",
        on_error: OnError = "raise",
        selector: Callable[[Any], int | None] | None = None,
    ) -> None:
        if exclusion not in ("strict", "weak"):
            raise DefinitionError(f"exclusion must be 'strict' or 'weak', not {exclusion!r}")
        self.name = name
        self.members: tuple[Layer, ...] = tuple(layers)
        # A selector maps the context straight to a member index (None: no member): for
        # groups whose choice is already known, e.g. decided by a layer manager upstream.
        self.selector = selector
        if selector is not None and policy is None:
            policy = "last"
        self.exclusion = exclusion
        self._policy: Policy | None = None
        self.policy_name = ""
        self.set_policy(policy)
        names = {m.name for m in self.members}
        if on_error not in ("raise", "default") and on_error not in names:
            raise DefinitionError(f"on_error={on_error!r} names no member of group {name!r}")
        self.on_error = on_error
        for m in self.members:
            if m.group is not None and m.group is not self:
                raise DefinitionError(f"{m!r} already belongs to group {m.group.name!r}")
            m.group = self
        if self._policy is not None and selector is None:
            missing = [m.name for m in self.members if m.predicate is None]
            if missing:
                raise DefinitionError(f"hedge group {name!r}: members without a predicate: {missing}")

    @property
    def policy(self) -> Policy | None:
        return self._policy

    def set_policy(self, policy: str | Policy | None) -> None:
        """Switch the selection policy; no re-registration needed (H47)."""
        if isinstance(policy, str):
            if policy not in POLICIES:
                raise DefinitionError(f"unknown policy {policy!r}; expected one of {sorted(POLICIES)}")
            self._policy, self.policy_name = POLICIES[policy], policy
        elif policy is None:
            self._policy, self.policy_name = None, ""
        else:
            self._policy, self.policy_name = policy, getattr(policy, "__name__", "custom")

    def __repr__(self) -> str:
        return f"LayerGroup({self.name!r}, {[m.name for m in self.members]})"


def HedgeGroup(name: str, layers: Sequence[Layer], *, policy: str | Policy = "last", **kw: Any) -> LayerGroup:
    """A :class:`LayerGroup` of predicate layers with a selection policy (default ``last``)."""
    return LayerGroup(name, layers, policy=policy, **kw)
