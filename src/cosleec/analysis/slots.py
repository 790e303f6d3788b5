"""The occurrences a trace is encoded with (:mod:`cosleec.analysis.encoding`): slots, the
snapshot an ``otherwise`` reads, the prohibitions a firing can raise, which occurrences come
after a step (:class:`After`, :class:`Step`), and when a declared priority cancels a firing
(:class:`Cut`).

A :class:`Slot` is one possible occurrence: present or not, its time, causal position and
snapshot free. Every question about a response asks which present slots fall in a window
*after* the step that raised it (:class:`After`, :func:`before`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import z3

Z3 = Any  # z3's Python API is untyped


@dataclass(eq=False)
class Slot:
    """One possible occurrence of ``event``: present or not, with its time and snapshot."""

    id: int
    event: str
    depth: int
    t: Z3
    pos: Z3
    present: Z3
    snap: dict[str, Z3]
    why: str = ""  # what it may fulfil, for a witness's timeline


@dataclass(eq=False)
class Fallback:
    """The snapshot an ``otherwise`` that starts at a deadline reads, and when it starts."""

    at: Z3
    started: Z3
    snap: dict[str, Z3]


@dataclass(frozen=True)
class Step:
    """The moment a response (or a prohibition) is raised, as the reference semantics orders
    them: at time ``t``, either at the step of the occurrence at causal position ``pos``, or --
    ``late`` -- after every occurrence at ``t`` (a deadline that closed: its ``otherwise``
    starts once time has passed it). Two moments at one time compare by position, a late one
    after every step; two late ones at one time are the same moment."""

    t: Z3
    pos: Z3
    late: Z3

    @staticmethod
    def at(x: Slot) -> Step:
        """The step of occurrence ``x``."""
        return Step(x.t, x.pos, z3.BoolVal(False, x.present.ctx))

    def follows(self, y: Slot) -> Z3:
        """``y`` comes after this moment."""
        if z3.is_false(self.late):
            return z3.Or(y.t > self.t, z3.And(y.t == self.t, y.pos > self.pos))
        return z3.Or(y.t > self.t, z3.And(y.t == self.t, z3.Not(self.late), y.pos > self.pos))

    def after(self, other: Step) -> Z3:
        """This moment comes strictly after ``other``."""
        same = self.t == other.t
        steps = z3.And(same, z3.Not(self.late), z3.Not(other.late), self.pos > other.pos)
        return z3.Or(self.t > other.t, z3.And(same, self.late, z3.Not(other.late)), steps)

    @staticmethod
    def choose(c: Z3, a: Step, b: Step) -> Step:
        """``a`` when ``c`` holds, else ``b``."""
        late = a.late if a.late.eq(b.late) else z3.If(c, a.late, b.late)
        return Step(z3.If(c, a.t, b.t), z3.If(c, a.pos, b.pos), late)


@dataclass(frozen=True)
class After:
    """Which occurrences come after the step that raised an obligation: after slot ``slot``
    in causal order, or strictly after time ``at`` (an ``otherwise`` started by a deadline)."""

    slot: Slot | None = None
    at: Z3 = None

    def __call__(self, y: Slot) -> Z3:
        """``y`` comes after the raising step."""
        if self.slot is not None:
            x = self.slot
            if y is x:
                return z3.BoolVal(False, y.present.ctx)
            return z3.Or(y.t > x.t, z3.And(y.t == x.t, y.pos > x.pos))
        return y.t > self.at

    @property
    def step(self) -> Step:
        """The raising step, as a :class:`Step`."""
        if self.slot is not None:
            return Step.at(self.slot)
        return Step(self.at, z3.IntVal(0, self.at.ctx), z3.BoolVal(True, self.at.ctx))


@dataclass(frozen=True)
class Cut:
    """When a declared priority cancels one firing (an *instance*) of a lower rule: whether it
    is ``cancelled``, at time ``at`` and -- cancel semantics -- at the step of position ``pos``
    (the firing that cancels it, after everything that step's occurrence settles); under
    conflict-aware semantics (``pos`` None), before anything else happens at ``at``. A
    cancelled instance imposes nothing more (:mod:`cosleec.analysis.priorities`)."""

    cancelled: Z3
    at: Z3
    pos: Z3 | None

    def spares(self, y: Slot) -> Z3:
        """``y`` comes after the cancellation: it no longer breaks the instance's prohibitions."""
        if self.pos is None:
            later = y.t >= self.at
        else:
            later = z3.Or(y.t > self.at, z3.And(y.t == self.at, y.pos > self.pos))
        return z3.And(self.cancelled, later)

    def saves(self, lo: Z3, hi: Z3 | None) -> Z3:
        """An obligation of window ``[lo, hi]`` is not broken: the cancellation comes while its
        window is still open (a window closes once time passes its end; one that closes
        before it opens is broken at once)."""
        if hi is None:
            return self.cancelled
        return z3.And(self.cancelled, lo <= hi, self.at <= hi)

    def by(self, t: Z3, pos: Z3 | None = None) -> Z3:
        """The instance is cancelled at or before time ``t`` (the step of position ``pos``)."""
        if pos is None or self.pos is None:
            return z3.And(self.cancelled, self.at <= t)
        return z3.And(self.cancelled, z3.Or(self.at < t, z3.And(self.at == t, self.pos <= pos)))

    def by_step(self, step: Step) -> Z3:
        """The instance is cancelled at or before moment ``step`` (a late one: anything at its time)."""
        if z3.is_false(step.late):
            return self.by(step.t, step.pos)
        return z3.If(step.late, self.by(step.t), self.by(step.t, step.pos))


@dataclass(frozen=True)
class Ban:
    """A prohibition a rule can raise at ``slot``: in force when ``active``, over ``[lo, hi]``;
    ``rule`` is the rule's name, ``cut`` when a declared priority cancels that firing."""

    slot: Slot
    active: Z3
    lo: Z3
    hi: Z3 | None
    rule: str = ""
    cut: Cut | None = None


@dataclass(frozen=True)
class FallbackBan:
    """A prohibition inside an ``otherwise``, raised when that fallback starts (at ``step``,
    reading ``snap``): in force when ``active`` (its rule fires, its clauses are chosen, the
    fallback started), over ``[lo, hi]``; ``within`` names the refusals of the obligations whose
    fallbacks hold it, innermost last (a refusal of one of them may be what raised it)."""

    step: Step
    snap: dict[str, Z3]
    active: Z3
    lo: Z3
    hi: Z3 | None
    rule: str
    cut: Cut | None
    within: tuple[Any, ...]


@dataclass(eq=False)
class Raised:
    """An obligation or prohibition (``occurrence``) a firing of a rule that a priority orders
    raises, at any depth: its window ``[lo, hi]``, the time its response started, which
    occurrences come after the step that raised it (``after``), and when it is raised
    (``guard``: the rule fires, its clause is chosen, an ``otherwise`` has started); an
    obligation's ``refusal`` (:class:`~cosleec.analysis.refusals.Refusal`), once the encoding
    has asked for it (None: nothing refuses it)."""

    occurrence: Any
    lo: Z3
    hi: Z3 | None
    start: Z3
    after: Any
    guard: Z3
    plain: bool  # no `else`: the reference judges it by its own window alone
    refusal: Any = None


def before(z: Slot, y: Slot) -> Z3:
    """``z`` comes before ``y`` in the trace."""
    return z3.Or(z.t < y.t, z3.And(z.t == y.t, z.pos < y.pos))


__all__ = ["Z3", "After", "Ban", "Cut", "Fallback", "FallbackBan", "Raised", "Slot", "Step", "before"]
