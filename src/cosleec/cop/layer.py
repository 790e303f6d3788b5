"""Layers, groups of layers and the selection policies of hedge groups.

A :class:`Layer` is a named, first-class object with no behaviour of its own: partials
registered on layered functions give it behaviour. A layer with a ``when`` predicate is a
*predicate layer*: a hedge group selects it at dispatch time from the context snapshot.

A :class:`LayerGroup` makes its members mutually exclusive. With a selection policy it is
a *hedge group*: at each dispatch the policy picks at most one member from the values of
the members' predicates -- ``last`` (the last one that holds), ``first``, or any callable
``Sequence[bool] -> int | None``.

This module is the bottom of ``cosleec.cop``: it imports only :mod:`cosleec.cop.errors`.
Enter/exit hooks are kept here, on the layer they observe, and so is the exclusion check:
``state.py`` and ``extent.py`` call :func:`displaced` and :func:`fire_hooks`.

Codes such as SD7 (semantic decisions) and A8, E38, H48 (checklist items) refer to docs/reference/cop-runtime.md.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Sequence
from typing import Any, ClassVar, Literal

from cosleec.cop.errors import DefinitionError, ExclusionError

Predicate = Callable[[Any], object]
Policy = Callable[[Sequence[bool]], "int | None"]
LayerHook = Callable[["Layer"], None]

_ids = itertools.count()


class Layer:
    """A named layer: use one per behaviour variation you want to switch on and off.

    Identity matters, not the name: two layers may share a name. ``when`` makes it a
    predicate layer (a hedge group member); ``priority`` moves it outward in every chain
    (docs/reference/cop-runtime.md SD7).
    """

    __slots__ = ("__weakref__", "enter_hooks", "exit_hooks", "group", "id", "name", "predicate", "priority")

    hooked: ClassVar[int] = 0
    """How many enter/exit hooks exist on any layer (zero: scopes skip working out what changed)."""

    def __init__(self, name: str, *, when: Predicate | None = None, priority: int = 0) -> None:
        self.name = name
        self.predicate = when
        self.priority = priority
        self.group: LayerGroup | None = None
        self.id = next(_ids)
        self.enter_hooks: list[LayerHook] = []
        self.exit_hooks: list[LayerHook] = []

    def on_enter(self, hook: LayerHook) -> LayerHook:
        """Call ``hook(layer)`` on every effective activation, global or scoped (checklist E38).

        Use it to acquire what the layer's behaviour needs; usable as a decorator.
        """
        self.enter_hooks.append(hook)
        Layer.hooked += 1
        return hook

    def on_exit(self, hook: LayerHook) -> LayerHook:
        """Call ``hook(layer)`` on every effective deactivation; the counterpart of :meth:`on_enter`."""
        self.exit_hooks.append(hook)
        Layer.hooked += 1
        return hook

    def __repr__(self) -> str:
        return f"Layer({self.name!r})"


# ---------------------------------------------------------------- selection policies


def policy_last(values: Sequence[bool]) -> int | None:
    """The last member, in declared order, whose predicate holds: later members refine earlier ones.

    The default policy of :func:`HedgeGroup`.
    """
    for i in range(len(values) - 1, -1, -1):
        if values[i]:
            return i
    return None


def policy_first(values: Sequence[bool]) -> int | None:
    """The first member whose predicate holds: for generic groups where earlier members win."""
    for i, v in enumerate(values):
        if v:
            return i
    return None


POLICIES: dict[str, Policy] = {"last": policy_last, "first": policy_first}
"""The policies a group accepts by name; any other callable policy is passed as itself."""

OnError = Literal["raise", "default"] | str


class LayerGroup:
    """Mutually exclusive layers; with a ``policy``, a hedge group selecting by predicate.

    Use a plain group for modes that must not combine (at most one member active), and a
    hedge group (:func:`HedgeGroup`) for predicate layers of which a dispatch selects at
    most one.

    ``exclusion="strict"`` (default): explicitly activating a second member while one is
    active raises :class:`ExclusionError` and changes nothing. ``"weak"``: the new member
    replaces the old one.

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
    ) -> None:
        if exclusion not in ("strict", "weak"):
            raise DefinitionError(f"exclusion must be 'strict' or 'weak', not {exclusion!r}")
        self.name = name
        self.members: tuple[Layer, ...] = tuple(layers)
        self.exclusion = exclusion
        self.policy: Policy | None = None
        self.set_policy(policy)
        names = {m.name for m in self.members}
        if on_error not in ("raise", "default") and on_error not in names:
            raise DefinitionError(f"on_error={on_error!r} names no member of group {name!r}")
        self.on_error = on_error
        # the layered function this hedge group is attached to (a weak reference, set by
        # @layered): one group serves one function (SD12)
        self.owner: Callable[[], object] | None = None
        for m in self.members:
            if m.group is not None and m.group is not self:
                raise DefinitionError(f"{m!r} already belongs to group {m.group.name!r}")
            m.group = self
        if self.policy is not None:
            missing = [m.name for m in self.members if m.predicate is None]
            if missing:
                raise DefinitionError(f"hedge group {name!r}: members without a predicate: {missing}")

    def set_policy(self, policy: str | Policy | None) -> None:
        """Switch the selection policy; the next dispatch uses it, no re-registration (H47)."""
        if isinstance(policy, str):
            if policy not in POLICIES:
                raise DefinitionError(f"unknown policy {policy!r}; expected one of {sorted(POLICIES)}")
            policy = POLICIES[policy]
        self.policy = policy

    def __repr__(self) -> str:
        return f"LayerGroup({self.name!r}, {[m.name for m in self.members]})"


def HedgeGroup(name: str, layers: Sequence[Layer], *, policy: str | Policy = "last", **kw: Any) -> LayerGroup:
    """A :class:`LayerGroup` of predicate layers with a selection policy (default ``last``).

    Use one per function whose variants are chosen by conditions on the context, the
    members in the order the policy reads them.
    """
    return LayerGroup(name, layers, policy=policy, **kw)


def displaced(layer: Layer, current: Iterable[Layer], how: str = "") -> list[Layer]:
    """The members of ``layer``'s group in ``current`` that activating ``layer`` displaces.

    A strict group refuses instead: :class:`ExclusionError`, nothing changed (SD6, SD11).
    """
    group = layer.group
    if group is None:
        return []
    rivals = [la for la in current if la is not layer and la.group is group]
    if rivals and group.exclusion == "strict":
        raise ExclusionError(
            f"cannot activate {layer.name!r}{how}: {rivals[0].name!r} of exclusive group {group.name!r} is active"
        )
    return rivals


def fire_hooks(*, exited: Iterable[Layer], entered: Iterable[Layer]) -> None:
    """Run the exit hooks of ``exited``, then the enter hooks of ``entered`` (checklist E38)."""
    for la in exited:
        for hook in la.exit_hooks:
            hook(la)
    for la in entered:
        for hook in la.enter_hooks:
            hook(la)
