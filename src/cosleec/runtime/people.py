"""Sentences for people: what a decision means to the person the robot talks to.

:attr:`Decision.for_people <cosleec.runtime.decision.Decision.for_people>` is the
author's sentence for the decision's case when the Manager has an explanations file
(:mod:`cosleec.runtime.explanations`), its ``{measure}`` placeholders filled with the values
the decision read; otherwise a sentence in plain words made from the decision itself --
names as words, responses as what the robot will do, deadlines as durations, the values
that decided the clause -- never the rules' notation::

    I will refuse and explain why, because requester is patient is no.
    I will not record video for 10 minutes, because patient consented is no.
    I did not call nurse within 10 minutes, so I will raise alarm.
    I can't decide yet: I don't know battery low. Until I do, I will not move for 1 minute.

Nothing here runs when a decision is made: the sentence is made when first read.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Mapping
from typing import Protocol

from cosleec.lang import HedgeSemantics, Unknowns, decisive
from cosleec.runtime.explanations import PLACEHOLDER, Explanations
from cosleec.runtime.model import Obligation
from cosleec.runtime.plain import listed, mentioned, spoken, value_words, words
from cosleec.runtime.values import Value

__all__ = ["Decided", "action", "case", "fill", "generated", "sentence", "why_forbidden"]


class Decided(Protocol):
    """What a sentence is made of: the parts of a :class:`~cosleec.runtime.decision.Decision`
    read here (a protocol: the decision module uses this one, not the other way round)."""

    @property
    def rule(self) -> str:
        """The rule that decided."""

    @property
    def clause(self) -> int | None:
        """The clause chosen (0: the default; None: undetermined)."""

    @property
    def values(self) -> dict[str, Value | None]:
        """The measures' values it read."""

    @property
    def conditions(self) -> tuple[tuple[int, str, bool | None], ...]:
        """Each condition: (clause, its text, its value)."""

    @property
    def obligations(self) -> tuple[Obligation, ...]:
        """What it requires."""

    @property
    def missing(self) -> tuple[str, ...]:
        """The measures it had no value for."""

    @property
    def semantics(self) -> HedgeSemantics:
        """How the clauses combine."""

    @property
    def unknown(self) -> Unknowns:
        """How unknown condition values were read."""

    @property
    def missed(self) -> Obligation | None:
        """A fallback's missed obligation."""

    @property
    def explanations(self) -> Explanations | None:
        """The author's sentences, if any."""

    @property
    def fallback(self) -> bool:
        """Is it an ``otherwise`` decision?"""


def sentence(d: Decided) -> str:
    """The sentence for people of ``d``: the author's for its case, filled, else :func:`generated`."""
    given = authored(d)
    return generated(d) if given is None else given


def authored(d: Decided) -> str | None:
    """The author's sentence for ``d``'s case (its explanations file's), filled; None when
    the file has none for it, or there is no file (the sentence is then :func:`generated`)."""
    given = d.explanations.sentence(d.rule, case(d)) if d.explanations is not None else None
    return None if given is None else fill(given, d.values)


def why_forbidden(d: Decided) -> tuple[str, bool]:
    """What a refusal tells a person of ``d``, the decision whose prohibition forbids: the
    author's sentence for its case, filled (and True); else the values that decided its
    clause, in words, to follow "because" (and False; empty when nothing decided it).

    Not the generated sentence of ``d`` itself: "I will not record video for 10 minutes"
    after "I can't record video for another 9 minutes" reads as a contradiction.
    """
    given = d.explanations.sentence(d.rule, case(d)) if d.explanations is not None else None
    if given is not None:
        return fill(given, d.values), True
    return _because(d), False


def case(d: Decided) -> str:
    """The case of ``d`` as an explanations file names it: ``default``, a clause number,
    ``otherwise``; ``undetermined`` (no file names it: only a rule's sentence for every case)."""
    if d.fallback:
        return "otherwise"
    if d.clause is None:
        return "undetermined"
    return "default" if d.clause == 0 else str(d.clause)


def fill(text: str, values: Mapping[str, Value | None]) -> str:
    """``text`` with each ``{name}`` replaced by the value of measure ``name`` in words
    (``unknown`` when it has none); other braces are left as written."""
    return PLACEHOLDER.sub(lambda m: value_words(values.get(m[1])), text)


Fact = tuple[str | None, str]
"""One fact a sentence gives after "because": a measure's name (its value is said as the
decision read it), or None and the fact in words (a condition that reads no measure)."""

#: the shape of each sentence made -- its words, and which measures' values it says -- by
#: everything but the values: decisions recur (the same rule, clause and conditions), and an
#: audit log, an observer or a ROS topic asks each one for its sentence
_SHAPES: dict[tuple[object, ...], tuple[str, tuple[Fact, ...]]] = {}
_SHAPES_MAX = 4096


def generated(d: Decided) -> str:
    """A sentence in plain words for ``d``, when its author gave none (shaped once per case)."""
    key = (
        d.rule, d.clause, d.fallback, d.obligations, d.conditions, d.missing,
        d.semantics, d.unknown, d.missed, tuple(d.values),
    )  # fmt: skip
    shape = _SHAPES.get(key)
    if shape is None:
        if len(_SHAPES) >= _SHAPES_MAX:
            _SHAPES.clear()
        shape = _SHAPES[key] = _shape(d)
    return _said(shape, d.values)


def _said(shape: tuple[str, tuple[Fact, ...]], values: Mapping[str, Value | None]) -> str:
    head, facts = shape
    return f"{head}, because {_told(facts, values)}." if facts else head


def _told(facts: tuple[Fact, ...], values: Mapping[str, Value | None]) -> str:
    """``facts`` in words, each once, in order: ``a is yes and b is no``."""
    said = dict.fromkeys(
        text if n is None else f"{words(n)} is {value_words(values[n])}" for n, text in facts
    )
    return listed(list(said))


def _shape(d: Decided) -> tuple[str, tuple[Fact, ...]]:
    """The words of ``d``'s sentence and the facts that follow "because" (none: the whole sentence)."""
    doing = listed([action(o) for o in d.obligations])
    if d.fallback:
        missed = _missed(d.missed)
        if d.clause is None:
            return f"{missed}, and I can't decide what to do next: I don't know {_unknown(d)}.", ()
        return f"{missed}, so " + (f"I will {doing}." if doing else "nothing more is required of me."), ()
    if d.clause is None:
        until = f" Until I do, I will {doing}." if doing else ""
        return f"I can't decide yet: I don't know {_unknown(d)}.{until}", ()
    head = f"I will {doing}" if doing else "Nothing is required of me"
    facts = _facts(d)
    return (head, facts) if facts else (f"{head}.", ())


@functools.lru_cache(maxsize=4096)  # a rule's obligations recur: one sentence part each
def action(o: Obligation) -> str:
    """What obligation ``o`` makes the robot do, as words after "I will": ``call nurse within
    10 minutes``, ``not record video for 10 minutes``."""
    verb = words(o.event)
    hi, lo = o.within_s, o.from_s
    if o.negated:
        if hi is None:
            return f"never {verb}" if o.eventually else f"not {verb}"
        return (
            f"not {verb} for {spoken(hi)}"
            if not lo
            else f"not {verb} from {spoken(lo)} to {spoken(hi)} from now"
        )
    if hi is None:
        return f"{verb} at some point" if o.eventually else verb
    return (
        f"{verb} within {spoken(hi)}" if not lo else f"{verb} between {spoken(lo)} and {spoken(hi)} from now"
    )


def _missed(o: Obligation | None) -> str:
    """What went wrong, for a fallback's sentence: ``I did not call nurse in time``."""
    if o is None:
        return "Something I had to do was not done in time"
    if o.negated:
        return f"I was not to {words(o.event)}, and it happened"
    return f"I did not {words(o.event)} in time"


def _unknown(d: Decided) -> str:
    return listed([words(n) for n in d.missing]) or "enough"


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@functools.lru_cache(maxsize=1024)  # a rule's conditions and the measures it reads recur
def _reads(texts: tuple[str, ...], names: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    """For each condition of ``texts``, the measures of ``names`` it reads, in their order."""
    blank = dict.fromkeys(names)
    return tuple(tuple(n for n, _ in mentioned(t, blank)) for t in texts)


def _facts(d: Decided) -> tuple[Fact, ...]:
    """The facts that decided ``d``'s clause (``requester is patient is no``), each a
    measure to say with its value, or a condition that reads none in words; none when the
    rule has no ``unless``."""
    hedges = [(c, t, v) for c, t, v in d.conditions if c > 0]
    if not hedges or d.clause is None:
        return ()
    chosen = set(decisive([v for _, _, v in hedges], d.clause, d.semantics, d.unknown))
    reads = _reads(tuple(t for _, t, _ in hedges), tuple(d.values))
    facts: list[Fact] = []
    for (c, t, v), named in zip(hedges, reads, strict=True):
        if c not in chosen:
            continue
        if named:
            facts += [(n, "") for n in named]
        else:  # a condition that reads no measure: said as written, names as words
            said = _NAME.sub(lambda m: words(m[0]), t)
            facts.append((None, f"{said} is {value_words(v)}"))
    return tuple(facts)


def _because(d: Decided) -> str:
    """The values that decided ``d``'s clause, in words, to follow "because" (empty: none)."""
    return _told(_facts(d), d.values)
