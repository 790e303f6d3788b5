"""Permission: may an event happen now, and if not, why not -- in a sentence a person can read.

:meth:`Manager.request <cosleec.runtime.Manager.request>` (a real attempt: a refusal is
counted and recorded) and :meth:`Manager.permission <cosleec.runtime.Manager.permission>`
(a question: nothing is recorded) answer with a :class:`Permission`; :class:`Answers`
words it from the prohibitions that forbid the event now (what the tracker says), once per
rule, however many of its activations forbid it.
"""

from __future__ import annotations

import bisect
import difflib
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from cosleec.errors import clip, show
from cosleec.records import Kind
from cosleec.runtime import people
from cosleec.runtime.core import Core
from cosleec.runtime.decision import Decision
from cosleec.runtime.errors import ContextError
from cosleec.runtime.obligations import Tracked
from cosleec.runtime.plain import duration, listed, spoken, words
from cosleec.runtime.steps import Step


@dataclass(frozen=True)
class Permission:
    """The answer of :meth:`Manager.request` and :meth:`Manager.permission`: may ``event``
    happen now, and if not, why not.

    ``rules`` names the rules whose prohibitions forbid it now (empty when it is permitted,
    and when it is refused for another reason: an undeclared event, a Manager that has
    stopped); ``reason`` says it in one sentence a person can read (an operator's screen,
    an ``ExplainWhy``). True as a condition exactly when permitted, so that
    ``if manager.request(e):`` means what it says. ``reason`` is for developers and
    operators (rules, the prohibition, how long it still holds: ``for another 9 min 20 s``);
    ``for_people`` says it to the person the robot talks to: ``I can't record video for
    another 9 minutes: ...`` and the sentence for people of the decision that forbade it
    (:attr:`Decision.for_people <cosleec.runtime.decision.Decision.for_people>`).
    """

    event: str
    permitted: bool
    rules: tuple[str, ...]
    reason: str
    for_people: str = ""

    def __post_init__(self) -> None:
        if not self.for_people:  # an answer made without one: the plain sentence
            what = words(self.event) if isinstance(self.event, str) else "do that"
            said = f"I can {what} now." if self.permitted else f"I can't {what} now."
            object.__setattr__(self, "for_people", said)

    def __bool__(self) -> bool:
        return self.permitted


class Answers:
    """Words the answers: permitted (made once per event, the common case), forbidden (by
    which rules, until when, and the explanation of the decision that forbade it, while the
    core still keeps that decision), or stopped (the Manager takes no more steps)."""

    def __init__(self, core: Core) -> None:
        self.core = core
        self.allowed: dict[str, Permission] = {}

    def ask(self, name: str, source: str, step: Step) -> Permission:
        """(In ``step``.) The answer for declared event ``name`` now; a refusal is counted (on
        each forbidding prohibition too, kept in the journal) and recorded (``refused``)."""
        core = self.core
        forbidding = core.tracker.forbidding(name, step.now)
        answer = self.allowed.get(name) if not forbidding else None
        if answer is None:
            answer = self.given(name, forbidding, step.now)
        if not forbidding:
            return answer
        for t in forbidding:
            t.refused += 1
            if core.journal:  # the count is the prohibition's state: it is kept
                step.change.obligations[t.id] = t.to_json()
        core.stats.refused += 1
        data: dict[str, Any] = {
            "event": name,
            "by": [t.rule for t in forbidding],
            "obligations": [t.id for t in forbidding],
            "reason": answer.reason,
        }
        if source:
            data["source"] = clip(source, 200)
        step.emit(Kind.REFUSED, data)
        return answer

    def peek(self, name: str, now: float, policy: StrEnum) -> Permission:
        """(Under the lock.) The answer for ``name`` at ``now``, recording and counting
        nothing: what :meth:`Manager.permission` says. An undeclared event raises ContextError
        (policy ``raise``) or is not permitted, with the closest declared names."""
        if isinstance(name, str) and name in self.core.ruleset.events:
            return self.given(name, self.core.tracker.forbidding(name, now), now)
        reason, hint = _unknown(self.core, name)
        if policy == "raise":
            raise ContextError(reason, hint=hint)
        return Permission(name, False, (), f"{clip(name, 80)} is not an event the rules declare ({hint})")

    def given(self, name: str, forbidding: list[Tracked], now: float | None = None) -> Permission:
        """The answer for ``name`` given the prohibitions that forbid it ``now`` (none:
        permitted; ``now`` None: the clock's time). How long each still holds is a duration
        from ``now``, never a reading of the clock."""
        if not forbidding:  # the same answer every time: made once per event (declared events only)
            allowed = self.allowed.get(name)
            if allowed is None:
                allowed = Permission(
                    name, True, (), f"{name} is permitted: no prohibition in force forbids it now"
                )
                self.allowed[name] = allowed
            return allowed
        what = clip(name, 80)
        # one phrase per rule, however many of its activations forbid it: the one that ends
        # last says until when (a reason that grew with every trigger would fill the audit log)
        last: dict[str, Tracked] = {}
        for t in forbidding:
            held = last.get(t.rule)
            if held is None or (held.hi is not None and (t.hi is None or t.hi > held.hi)):
                last[t.rule] = t
        at = self.core.steps.clock.now() if now is None else now
        parts: list[str] = []
        said: dict[str, None] = {}  # the authors' sentences, each once, in order
        because: dict[str, None] = {}  # else what decided each forbidding clause, in words
        for t in last.values():
            until = "with no end" if t.hi is None else f"for another {duration(t.hi - at)}"
            d = self.decision(t)
            why = (
                d.explanation
                if d
                else f"{t.rule}: {t.obligation.describe()}, in force for {duration(at - t.start)}"
            )
            parts.append(f"by {t.rule} {until} ({clip(why, 300)})")
            if d is not None:
                text, authored = people.why_forbidden(d)
                if text:
                    (said if authored else because)[text] = None
        ends = [t.hi for t in last.values()]
        longest = None if None in ends else max(h for h in ends if h is not None)
        head = f"I can't {words(name)} " + (
            "now" if longest is None else f"for another {spoken(longest - at)}"
        )
        if because:
            head = f"{head}, because {listed(list(because))}"
        told = f"{head}: {' '.join(said)}" if said else f"{head}."
        return Permission(name, False, tuple(last), f"{what} is forbidden {' and '.join(parts)}", told)

    def why(self, t: Tracked) -> str | None:
        """The explanation of the decision that put ``t`` in force, while :attr:`decisions` keeps it."""
        d = self.decision(t)
        return None if d is None else d.explanation

    def decision(self, t: Tracked) -> Decision | None:
        """The decision that put ``t`` in force, while :attr:`decisions` keeps it."""
        ds = self.core.decisions  # in the order of their ids: found by bisection
        i = bisect.bisect_left(ds, t.decision_id, key=lambda d: d.id)
        return ds[i] if i < len(ds) and ds[i].id == t.decision_id else None

    @staticmethod
    def stopped(name: str, broken: Exception | None) -> Permission:
        """The answer of a Manager that takes no more steps: nothing is permitted."""
        what = clip(name, 80) if isinstance(name, str) else show(name)
        if broken is not None:
            why = f"the Manager can no longer keep its state ({broken}), so it permits nothing"
        else:
            why = "the Manager is closed"
        return Permission(name, False, (), f"{what} is not permitted: {why}")


def undeclared(core: Core, name: str, what: str, step: Step, policy: StrEnum) -> str | None:
    """None when ``name`` is a declared event; else apply the ``unknown_events`` ``policy``:
    record it (``rejected``), then raise ContextError (``raise``) or return why it is refused."""
    if isinstance(name, str) and name in core.ruleset.events:
        return None
    core.stats.rejected += 1
    if not isinstance(name, str):
        step.emit(Kind.REJECTED, {"reason": f"an event is named by a string, not {type(name).__name__}"})
    reason, hint = _unknown(core, name)
    step.emit(Kind.REJECTED, {"reason": reason, "what": what, "hint": hint})
    if policy == "raise":
        raise ContextError(reason, hint=hint)
    return f"{clip(name, 80)} is not an event the rules declare ({hint})"


def _unknown(core: Core, name: object) -> tuple[str, str]:
    """Why ``name`` is no event of the rules, and the hint (the closest declared names);
    ContextError when it is no string at all."""
    if not isinstance(name, str):
        raise ContextError(
            f"an event is named by a string, not {type(name).__name__} {show(name)}",
            hint='give the event\'s name as a string, as the rules declare it ("CallSupport")',
        )
    close = difflib.get_close_matches(name, sorted(core.ruleset.events), n=3) if len(name) < 200 else []
    hint = f"did you mean {', '.join(close)}?" if close else "declare it in the rules' def block"
    return f"unknown event {show(name)}", hint
