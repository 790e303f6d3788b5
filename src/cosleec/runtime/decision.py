"""Decision records: everything a trigger decided, and why, in one immutable value.

Every decision renders as a short explanation a person (or an ``ExplainWhy`` obligation)
can use: ``R1: Refuse and ExplainWhy, because userUndressed was true; userDistressed was
false``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

from cosleec.runtime.model import Obligation
from cosleec.runtime.values import Value


class ConditionValue(NamedTuple):
    clause: int  # 0: the trigger condition; i: clause i
    text: str
    value: bool | None  # None: unknown


@dataclass(frozen=True)
class Decision:
    id: int
    time: float
    event: str
    rule: str
    clause: int | None  # 0 default, i clause i, None undetermined
    layer: str | None
    semantics: str
    values: dict[str, Value | None]
    conditions: tuple[tuple[int, str, bool | None], ...]  # (clause, condition text, value); 0: trigger
    obligations: tuple[Obligation, ...]
    missing: tuple[str, ...] = ()
    reason: str = ""  # set for decisions that are not a rule's clause choice (otherwise follow-ups)
    context_version: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def explanation(self) -> str:
        """Why this decision, in a sentence (computed when first asked for)."""
        cached = self.__dict__.get("_explanation")
        if cached is None:
            cached = self.reason or explain(
                self.rule,
                self.clause,
                tuple(ConditionValue(*c) for c in self.conditions),
                self.obligations,
                self.values,
                self.semantics,
                self.missing,
            )
            object.__setattr__(self, "_explanation", cached)
        return cached

    @property
    def undetermined(self) -> bool:
        return self.clause is None

    def to_json(self) -> dict[str, Any]:
        return {
            "type": "decision",
            "id": self.id,
            "time": self.time,
            "event": self.event,
            "rule": self.rule,
            "clause": self.clause,
            "layer": self.layer,
            "semantics": self.semantics,
            "values": self.values,
            "conditions": [{"clause": c, "condition": t, "value": v} for c, t, v in self.conditions],
            "obligations": [o.to_json() for o in self.obligations],
            "missing": list(self.missing),
            "explanation": self.explanation,
            "context_version": self.context_version,
        }


def _fmt(v: Value | None) -> str:
    if v is None:
        return "unknown"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def explain(
    rule: str,
    clause: int | None,
    conditions: tuple[ConditionValue, ...],
    obligations: tuple[Obligation, ...],
    values: dict[str, Value | None],
    semantics: str,
    missing: tuple[str, ...] = (),
) -> str:
    """Why this clause: the conditions that decided it, with the values they read."""
    hedges = [c for c in conditions if c.clause > 0]

    def reason(c: ConditionValue) -> str:
        t = c.text
        if t in values:  # a boolean measure: "userUndressed was true"
            return f"{t} was {_fmt(c.value)}"
        shown = ", ".join(f"{n} = {_fmt(v)}" for n, v in values.items() if _mentions(t, n))
        return f"{t} was {_fmt(c.value)}" + (f" ({shown})" if shown else "")

    if clause is None:
        return f"{rule}: undetermined, no value for {', '.join(missing)}; nothing was done"
    what = " and ".join(o.describe() for o in obligations) if obligations else "nothing is required"
    if not hedges:
        return f"{rule}: {what}"
    if semantics == "nested":
        decisive = hedges[: clause + 1]
    else:
        decisive = hedges[clause - 1 :] if clause else hedges
    because = "; ".join(reason(c) for c in decisive)
    head = "default" if clause == 0 else f"clause {clause} (unless {hedges[clause - 1].text})"
    return f"{rule}: {what} [{head}], because {because}"


def _mentions(text: str, name: str) -> bool:
    import re

    return re.search(rf"\b{re.escape(name)}\b", text) is not None
