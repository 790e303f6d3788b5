"""Decision records: everything a trigger decided, and why, in one immutable value.

Every decision renders as a short explanation for developers (:attr:`Decision.explanation`:
``R1: Refuse and ExplainWhy [clause 1 (unless userUndressed)], because userUndressed was
true; userDistressed >= high was false``) and as a sentence for the person the robot talks
to (:attr:`Decision.for_people`: the author's sentence from an explanations file, else
plain words, :mod:`cosleec.runtime.people`). Which condition values are named is decided
by :func:`cosleec.lang.hedges.decisive`, so both follow the same clause semantics as the
choice itself. Both are made when first read, not when the decision is made.

:meth:`Decision.to_json` and :meth:`Decision.from_json` are the one wire format: the audit
log, the ROS topics and the task nodes all use them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any, cast

from cosleec.lang import HedgeSemantics, Unknowns, decisive
from cosleec.runtime import people
from cosleec.runtime.explanations import Explanations
from cosleec.runtime.model import CompiledRule, Obligation
from cosleec.runtime.plain import mentioned
from cosleec.runtime.values import Value

#: the ``event`` of a fallback decision (no event triggered it: an obligation was missed)
OTHERWISE = "otherwise"


# the memos a decision made on the hot path gets when first used (Decision.__getattr__)
_MEMOS = frozenset({"_explanation", "_for_people", "_recorded"})


class DecisionOrigin(StrEnum):
    """What made a decision: a trigger (its rule's event), or a missed obligation (an ``otherwise``)."""

    TRIGGER = "trigger"
    OTHERWISE = "otherwise"


@dataclass(frozen=True, kw_only=True)
class Decision:
    """What one trigger decided for one rule (or what an ``otherwise`` started).

    ``origin`` says what made it: :attr:`DecisionOrigin.TRIGGER`, or
    :attr:`DecisionOrigin.OTHERWISE` for an ``otherwise`` (a *fallback*, :attr:`fallback`).
    ``clause`` is 0 for the default response, i for clause i (layer ``R.i``), None when
    undetermined (a measure it needed had no value: nothing is done); a fallback's is the
    clause whose obligation was missed, and its ``layer`` None. ``conditions`` holds
    ``(clause, condition text, value)`` with clause 0 for the trigger condition. A fallback
    has ``violated``, the id of the obligation whose miss started it, ``missed``, that
    obligation, and its explanation in ``reason``; its ``event`` is :data:`OTHERWISE` (no
    event triggered it), as its records say. ``explanations`` are the sentences for people
    of its rules (:attr:`for_people`), when the Manager was given some.
    """

    id: int
    time: float
    event: str
    rule: str
    clause: int | None
    layer: str | None
    semantics: HedgeSemantics
    values: dict[str, Value | None]
    conditions: tuple[tuple[int, str, bool | None], ...]
    obligations: tuple[Obligation, ...]
    missing: tuple[str, ...] = ()
    reason: str = ""
    context_version: int = 0
    violated: int | None = None
    unknown: Unknowns = Unknowns.UNDETERMINED  # how unknown condition values were read
    origin: DecisionOrigin = DecisionOrigin.TRIGGER
    missed: Obligation | None = None  # a fallback's missed obligation
    explanations: Explanations | None = field(default=None, compare=False, repr=False)
    _explanation: list[str] = field(default_factory=list, init=False, compare=False, repr=False)
    _for_people: list[str] = field(default_factory=list, init=False, compare=False, repr=False)
    _recorded: list[str] = field(default_factory=list, init=False, compare=False, repr=False)

    @classmethod
    def made(
        cls,
        *,
        id: int,
        time: float,
        event: str,
        rule: str,
        clause: int | None,
        layer: str | None,
        semantics: HedgeSemantics,
        values: dict[str, Value | None],
        conditions: tuple[tuple[int, str, bool | None], ...],
        obligations: tuple[Obligation, ...],
        missing: tuple[str, ...] = (),
        reason: str = "",
        context_version: int = 0,
        violated: int | None = None,
        unknown: Unknowns = Unknowns.UNDETERMINED,
        origin: DecisionOrigin = DecisionOrigin.TRIGGER,
        missed: Obligation | None = None,
        explanations: Explanations | None = None,
    ) -> Decision:
        """The same as the constructor, for the Manager's hot path: a frozen dataclass sets
        each of its fields through ``object.__setattr__`` (about 5 us a decision here);
        this fills the instance's dict in one call, from a literal (a quarter cheaper than
        from keywords). The parameters are the fields, with the same defaults (a test keeps
        them so)."""
        d = object.__new__(cls)
        d.__dict__.update(
            {
                "id": id,
                "time": time,
                "event": event,
                "rule": rule,
                "clause": clause,
                "layer": layer,
                "semantics": semantics,
                "values": values,
                "conditions": conditions,
                "obligations": obligations,
                "missing": missing,
                "reason": reason,
                "context_version": context_version,
                "violated": violated,
                "unknown": unknown,
                "origin": origin,
                "missed": missed,
                "explanations": explanations,
                "_explanation": [],
                "_for_people": [],
                "_recorded": [],
            }
        )
        return d

    @classmethod
    def at_trigger(
        cls,
        *,
        id: int,
        time: float,
        event: str,
        rule: CompiledRule,
        clause: int | None,
        fired: bool | None,
        read: tuple[Any, ...],
        status: tuple[bool | None, ...],
        semantics: HedgeSemantics,
        obligations: tuple[Obligation, ...],
        missing: tuple[str, ...],
        context_version: int,
        unknown: Unknowns,
        explanations: Explanations | None,
    ) -> Decision:
        """A trigger's decision, for the hot path: its ``values`` and ``conditions`` are made
        when first read, from what it keeps of the moment it was made -- ``read``, the stored
        values of ``rule.value_names`` (the context changes; this tuple does not), ``fired``,
        the trigger condition's value, and ``status``, the clause conditions' values (the
        Layer Manager's, never changed once made). Most decisions are never read: a
        decision of 20 clauses no longer builds 21 tuples and a dict each time. Equal, field
        for field, to the one :meth:`made` makes from the same parts (a test holds it so)."""
        fields = cls.trigger_fields(
            rule, clause, semantics=semantics, unknown=unknown, explanations=explanations
        )
        return cls.from_trigger_fields(
            fields, id, time, event, obligations, missing, context_version, (rule, read, fired, status)
        )

    @staticmethod
    def trigger_fields(
        rule: CompiledRule,
        clause: int | None,
        *,
        semantics: HedgeSemantics,
        unknown: Unknowns,
        explanations: Explanations | None,
    ) -> dict[str, Any]:
        """The fields that every decision :meth:`at_trigger` makes for ``rule`` at ``clause``
        has in common (read as they are now): made once, kept by the decider, and copied and
        completed by :meth:`from_trigger_fields` for each decision."""
        return {
            "id": 0,
            "time": 0.0,
            "event": "",
            "rule": rule.name,
            "clause": clause,
            "layer": rule.layer_names[clause] if clause else None,
            "semantics": semantics,
            "obligations": (),
            "missing": (),
            "reason": "",
            "context_version": 0,
            "violated": None,
            "unknown": unknown,
            "origin": DecisionOrigin.TRIGGER,
            "missed": None,
            "explanations": explanations,
        }

    @classmethod
    def from_trigger_fields(
        cls,
        fields: dict[str, Any],
        id: int,
        time: float,
        event: str,
        obligations: tuple[Obligation, ...],
        missing: tuple[str, ...],
        context_version: int,
        parts: tuple[CompiledRule, tuple[Any, ...], bool | None, tuple[bool | None, ...]],
        /,
    ) -> Decision:
        """The decision :meth:`at_trigger` makes, from its rule and clause's
        :meth:`trigger_fields` and what is its own (positional: the hot path's call);
        ``parts`` is ``(rule, read, fired, status)``."""
        dd = fields.copy()
        dd["id"] = id
        dd["time"] = time
        dd["event"] = event
        dd["obligations"] = obligations
        dd["missing"] = missing
        dd["context_version"] = context_version
        dd["_parts"] = parts  # (its memos of sentences are made when first used: __getattr__)
        d = object.__new__(cls)
        object.__setattr__(d, "__dict__", dd)  # (frozen: its fields are set once, here)
        return d

    def __getstate__(self) -> dict[str, Any]:
        """Pickled (and copied) whole: ``values`` and ``conditions`` made, and what they were
        made from left behind (it holds the compiled rule, which does not pickle)."""
        if "_parts" not in self.__dict__:
            return dict(self.__dict__)
        self.__dict__["values"] = self.values  # made now if not yet
        return {k: v for k, v in self.__dict__.items() if k != "_parts"}

    if not TYPE_CHECKING:  # (to mypy every attribute is a field: a misspelt one stays an error)

        def __getattr__(self, name: str) -> Any:
            """``values`` and ``conditions`` of a decision :meth:`at_trigger` made, made when first
            read (and kept: later reads are plain attribute reads); so are its memos of sentences
            (most decisions are never explained: no list is made for them)."""
            if name in _MEMOS:
                memo: list[str] = self.__dict__.setdefault(name, [])  # (atomic: one list, whoever races)
                return memo
            if name == "values" or name == "conditions":
                parts = self.__dict__.get("_parts")
                if parts is not None:
                    rule, read, fired, status = parts
                    values = dict(zip(rule.value_names, read))
                    for n, lits in rule.scale_values:  # scale positions back to their literals
                        x = values[n]
                        if x is not None:
                            values[n] = lits[x]
                    conditions = (
                        (0, rule.trigger_text, fired),
                        *zip(rule.clause_ids, rule.clause_texts, status),
                    )
                    self.__dict__.update(values=values, conditions=conditions)
                    return self.__dict__[name]
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def explanation(self) -> str:
        """Why this decision, in a sentence (computed when first asked for)."""
        if not self._explanation:
            self._explanation.append(self.reason or _because(self))
        return self._explanation[0]

    @property
    def for_people(self) -> str:
        """What the robot says to the person in front of it: the sentence of the Manager's
        explanations file for this case of the rule, its ``{measure}`` placeholders filled,
        else one in plain words (``I will refuse and explain why, because requester is
        patient is no.``); made when first asked for."""
        if not self._for_people:
            self._for_people.append(people.sentence(self))
        return self._for_people[0]

    def explain(self, width: int | None = None) -> str:
        """:attr:`explanation`, or with ``width`` a version for a screen: each condition
        longer than ``width`` characters is cut at a word boundary and ends with `…` and the
        number of terms left out, and at most :data:`SHOWN_VALUES` values are named. The
        wire and audit forms keep the complete :attr:`explanation`."""
        if width is None:
            return self.explanation
        return self.reason or _because(self, width)

    @property
    def fallback(self) -> bool:
        """True for an ``otherwise`` decision (``origin``): started by a missed obligation
        (``violated``), not by a trigger."""
        return self.origin is DecisionOrigin.OTHERWISE

    @property
    def undetermined(self) -> bool:
        """True when no clause could be chosen (a measure had no value)."""
        return self.clause is None

    def to_json(self) -> dict[str, Any]:
        """The wire and audit form; :meth:`from_json` reads it back.

        ``for_people`` is in it only when it is the author's (an explanations file's
        sentence, or one a record kept): a sentence in plain words is made from the rest of
        the record when someone reads it (:meth:`from_json`), not on every decision."""
        out = self._json()
        said = self._recorded[0] if self._recorded else people.authored(self)
        if said is not None:
            out["for_people"] = said
        return out

    def _json(self) -> dict[str, Any]:
        return {
            "type": "decision",
            "id": self.id,
            "time": self.time,
            "event": self.event,
            "rule": self.rule,
            "clause": self.clause,
            "layer": self.layer,
            "semantics": str(self.semantics),
            "values": self.values,
            "conditions": [{"clause": c, "condition": t, "value": v} for c, t, v in self.conditions],
            "obligations": [o.to_json() for o in self.obligations],
            "missing": list(self.missing),
            "reason": self.reason,
            "explanation": self.explanation,
            "context_version": self.context_version,
            "violated": self.violated,
            "unknowns": str(self.unknown),
            "origin": str(self.origin),
            "missed": None if self.missed is None else self.missed.to_json(),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Decision:
        """A decision read back from :meth:`to_json`; raises KeyError/ValueError/TypeError when
        malformed. A record of an older Manager, without ``origin``, is a fallback when it has
        ``violated``; one without ``for_people`` gets the sentence in plain words."""
        clause = d.get("clause")
        violated = d.get("violated")
        missed = d.get("missed")
        if isinstance(clause, bool) or not (clause is None or isinstance(clause, int)):
            raise ValueError(f"decision clause must be a whole number or null, not {clause!r}")
        origin = d.get("origin", DecisionOrigin.TRIGGER if violated is None else DecisionOrigin.OTHERWISE)
        decision = cls(
            id=int(d["id"]),
            time=float(d.get("time", 0.0)),
            event=str(d.get("event", "")),
            rule=str(d["rule"]),
            clause=None if clause is None else int(clause),
            layer=d.get("layer"),
            semantics=HedgeSemantics(d.get("semantics", HedgeSemantics.LAST_WINS)),
            values=dict(d.get("values", {})),
            conditions=tuple(
                (int(c["clause"]), str(c["condition"]), c["value"]) for c in d.get("conditions", [])
            ),
            obligations=tuple(Obligation.from_json(o) for o in d.get("obligations", [])),
            missing=tuple(d.get("missing", ())),
            reason=str(d.get("reason", "")),
            context_version=int(d.get("context_version", 0)),
            violated=None if violated is None else int(violated),
            unknown=Unknowns(d.get("unknowns", Unknowns.UNDETERMINED)),
            origin=DecisionOrigin(origin),
            missed=None if missed is None else Obligation.from_json(missed),
        )
        said = d.get("for_people")
        if isinstance(said, str):  # what was said then, whatever the explanations are now
            decision._for_people.append(said)
            decision._recorded.append(said)
        return decision


def _fmt(v: Value | None) -> str:
    if v is None:
        return "unknown"
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


SHOWN_VALUES = 8
"""How many measure values a shortened explanation (:meth:`Decision.explain`) names per condition."""

_TERM = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|[0-9]+(?:\.[0-9]+)?")
_CONNECTIVES = frozenset({"and", "or", "not"})


def shorten(text: str, width: int) -> str:
    """``text`` if it has at most ``width`` characters, else its start up to a word boundary
    followed by `… (N more terms)`: N counts the names and numbers left out."""
    if len(text) <= width:
        return text
    cut = text.rfind(" ", 0, width + 1)
    if cut <= 0:
        cut = width
    left = sum(1 for t in _TERM.findall(text, cut) if t not in _CONNECTIVES)
    return f"{text[:cut].rstrip()} … ({left:,} more term{'s' if left != 1 else ''})"


def _because(d: Decision, width: int | None = None) -> str:
    """Why this clause: the conditions that decided it, with the values they read (shortened
    to ``width`` as :meth:`Decision.explain` says)."""
    rule, clause = d.rule, d.clause
    if clause is None:
        held = " and ".join(o.describe() for o in d.obligations)
        return f"{rule}: undetermined, no value for {', '.join(d.missing)}; nothing was done" + (
            f"; meanwhile {held}, as some reading of the rule requires" if held else ""
        )
    what = " and ".join(o.describe() for o in d.obligations) if d.obligations else "nothing is required"
    if width is None and (made := _made_once(d)) is not None:
        return f"{rule}: {what} {made}"
    hedges = [(c, t, v) for c, t, v in d.conditions if c > 0]
    if not hedges:
        return f"{rule}: {what}"
    chosen = set(decisive([v for _, _, v in hedges], clause, d.semantics, d.unknown))

    def cond(t: str) -> str:
        return t if width is None else shorten(t, width)

    def reason(t: str, v: bool | None) -> str:
        if t in d.values:  # a boolean measure: "userUndressed was true"
            return f"{t} was {_fmt(v)}"
        named = mentioned(t, d.values)
        more = ""
        if width is not None and len(named) > SHOWN_VALUES:
            more = f", … ({len(named) - SHOWN_VALUES:,} more)"
            named = named[:SHOWN_VALUES]
        shown = ", ".join(f"{n} = {_fmt(x)}" for n, x in named) + more
        return f"{cond(t)} was {_fmt(v)}" + (f" ({shown})" if shown else "")

    because = "; ".join(reason(t, v) for c, t, v in hedges if c in chosen)
    head = (
        "default"
        if clause == 0
        else f"clause {clause}"
        + (f" (unless {cond(hedges[clause - 1][1])})" if clause <= len(hedges) else "")
    )
    return f"{rule}: {what} [{head}], because {because}"


#: how many ends of explanations a rule keeps (``CompiledRule.reasons``): under last-wins a
#: clause chosen on known values has one, so a rule keeps one per clause at most, and this
#: only bounds what unknown values could add
_REASONS_KEPT = 256


def _made_once(d: Decision) -> str | None:
    """The end of :func:`_because`'s sentence, ``[head], because ...``, for a trigger's decision
    under last-wins whose deciding conditions are all measures (``userUndressed was true``):
    a function of the clause and those conditions' values alone, so made once per rule and
    clause (and values) and kept in the compiled rule; None for any other decision, which
    :func:`_because` explains in full. The same text as the general path (a test holds it)."""
    parts = cast(
        "tuple[CompiledRule, tuple[Any, ...], bool | None, tuple[bool | None, ...]] | None",
        d.__dict__.get("_parts"),
    )
    clause = d.clause
    if parts is None or clause is None or d.semantics != HedgeSemantics.LAST_WINS:
        return None
    rule, _read, _fired, status = parts
    if not status or clause > len(status):
        return None
    key = (clause, status[(clause or 1) - 1 :])  # the deciding ones: this clause and every later one
    made = rule.reasons.get(key)
    if made is None:
        texts = rule.clause_texts[(clause or 1) - 1 :]
        if not set(texts) <= set(rule.value_names) or len(rule.reasons) >= _REASONS_KEPT:
            return None
        because = "; ".join(f"{t} was {_fmt(v)}" for t, v in zip(texts, key[1], strict=True))
        head = "default" if clause == 0 else f"clause {clause} (unless {rule.clause_texts[clause - 1]})"
        made = rule.reasons.setdefault(key, f"[{head}], because {because}")
    return made


def said_in(record: Mapping[str, Any]) -> str:
    """What a decision record says to people: the sentence it kept (an author's), else the
    one in plain words made from the record now (records keep only the author's: see
    :meth:`Decision.to_json`); "" for a record too malformed to read back. For readers of
    records (the live page, the timeline), which must not fail on an odd line."""
    kept = record.get("for_people")
    if isinstance(kept, str):
        return kept
    try:
        return Decision.from_json(record).for_people
    except (KeyError, ValueError, TypeError, AttributeError):
        return ""
