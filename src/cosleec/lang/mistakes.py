"""Syntax errors that are a newcomer's natural first guess, told as what the user meant.

A parser that meets ``not RecordVideo for 10 minutes`` reads ``for`` as the name of the next
rule and stops at ``10`` ("expected `when`"), which points away from the mistake. The
mistakes here are recognised from the token the parser stopped at, the few tokens around it
and what the parser expected there; each gets a message about the construct the user wrote
(``for 10 minutes``, ``==``, ``R1:``, a measure as a trigger, braces as parentheses) and a
hint that is the fix, written with the user's own names and numbers.
docs/reference/sleec-language.md §11 item 17 lists them; the other special messages (RTF,
``/``, unclosed ``(``, missing units, the paper notation's forms) stay in parser.py.

May import: the lang modules ast and lexer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from cosleec.lang import ast as A
from cosleec.lang.lexer import BAD_CHAR, Token

_UNITS = frozenset(A.TIME_UNITS)
_NUMBER = frozenset({"INT", "DECIMAL"})
_RESPONSE_END = frozenset({"NAME", "SECONDS", "MINUTES", "HOURS", "DAYS", "EVENTUALLY", "RBRACE"})
"""The tokens a response can end with: what a stray word after a response follows."""


@dataclass(frozen=True, slots=True)
class Mistake:
    """A recognised mistake: a diagnostic's code, message and hint, and where it is."""

    code: str
    message: str
    hint: str
    span: A.Span


def natural_mistake(
    tok: Token, before: Sequence[Token], after: Token | None, expected: set[str], paper: bool
) -> Mistake | None:
    """The mistake the parser met at ``tok``, if it is one of this module's; None otherwise.

    ``before`` holds the tokens just before ``tok`` (nearest last, up to four), ``after`` the
    one after it; ``expected`` what the parser would have taken (as messages show them:
    ``when``, ``a name``...); ``paper``: the file is in the paper notation, where ``R1:`` is
    right and the DSL-only mistakes do not apply.
    """
    prev = before[-1] if before else None
    if (
        _COMPARISONS.get(tok.value)
        and prev is not None
        and prev.type == "NAME"
        and len(before) >= 2
        and before[-2].value.lower() == "when"
    ):  # `when battery < 20 then`: a measure as the trigger
        return _measure_as_trigger(tok, prev, after)
    found = _operator(tok, prev, before, after)
    if paper and found is None and prev is not None and prev.value == "for" and "when" in expected:
        return _after_name(tok, prev, before, after) if tok.type in _NUMBER else None  # `for 10 minutes`
    if found is not None or paper or prev is None:
        return found
    if (
        tok.value == "when"
        and len(before) >= 3
        and before[-3].value == "within"
        and prev.line != before[-2].line
    ):
        limit = f"within {before[-2].value}"  # the next rule's name was read as the unit
        return Mistake(
            "missing-unit",
            f"`{limit}` has no time unit (the next rule's name `{prev.value}` was read as one)",
            f"write the unit: `{limit} seconds` (or minutes, hours, days)",
            _span(before[-3], before[-2]),
        )
    if "when" in expected and prev.type == "NAME":
        return _after_name(tok, prev, before, after)
    if prev.value.lower() == "when" and tok.value in ("{", "("):
        return _condition_as_trigger(tok)
    if prev.value == "{" and expected == {"a name"}:
        return Mistake(
            "braces-group",
            "braces mark one measure (`{m}`); they do not group a condition",
            "group a condition with parentheses: `({m} = low or {m} = medium)`",
            _span(prev),
        )
    if expected == {"="} and len(before) >= 2 and before[-2].value == "constant":
        return Mistake(
            "constant-value",
            f"the constant `{prev.value}` has no value",
            f"give it one: `constant {prev.value} = 5`",
            _span(prev),
        )
    return None


def _operator(tok: Token, prev: Token | None, before: Sequence[Token], after: Token | None) -> Mistake | None:
    """``==``, ``!=``, ``&&`` and ``||``: other languages' operators."""
    adjacent = after is not None and after.start_pos == tok.start_pos + 1
    if tok.value == "=" and prev is not None and prev.value == "=" and prev.start_pos + 1 == tok.start_pos:
        left = _operand(before[:-1])
        right = after.value if after is not None and after.type != "$END" else "..."
        fix = f"`{left} = {right}`"
        if right in ("true", "false") and left.isidentifier():
            fix += f", or `{'not ' if right == 'false' else ''}{left}` for a boolean measure"
        return Mistake("double-equals", "`==` is not SLEEC: `=` compares", f"write {fix}", _span(prev, tok))
    if tok.type != BAD_CHAR or not adjacent or after is None:
        return None
    pair = tok.value + after.value
    if pair == "!=":
        return Mistake(
            "not-equals",
            "`!=` is not SLEEC: `<>` means not equal",
            "write `a <> b` (or `not (a = b)`)",
            _span(tok, after),
        )
    if pair in ("&&", "||"):
        word = "and" if pair == "&&" else "or"
        return Mistake(
            f"operator-{word}",
            f"`{pair}` is not SLEEC: write `{word}`",
            f"write `{word}` for `{pair}`",
            _span(tok, after),
        )
    return None


def _after_name(tok: Token, prev: Token, before: Sequence[Token], after: Token | None) -> Mistake | None:
    """The parser expected ``when`` after ``prev``, a name: it read ``prev`` as a rule's name."""
    if tok.value == ":":
        return Mistake(
            "rule-colon",
            "a rule's name is followed by `when`, not `:`",
            f"write `{prev.value} when ...` (no colon)",
            _span(tok),
        )
    if len(before) < 2 or before[-2].line != prev.line or before[-2].type not in _RESPONSE_END:
        return None  # a real rule name at the start of its line: the generic message says it
    if tok.type == BAD_CHAR:
        return None  # the character is the mistake (parser.py names it)
    if prev.value == "for" and tok.type in _NUMBER and after is not None and after.value in _UNITS:
        written = f"{tok.value} {after.value}"
        response = _operand(before[:-1])
        negated = len(before) >= 3 and before[-3].value == "not"
        if negated:
            response = f"not {response}"
        return Mistake(
            "for-duration",
            f"SLEEC has no `for {written}`: durations are written `within {written}`",
            f"write `{response} within {written}`"
            + (" (it must not happen within that time of the trigger)" if negated else ""),
            _span(prev, after),
        )
    shown = "end of file" if tok.type == "$END" else f"`{tok.value}`"
    return Mistake(
        "stray-word",
        f"`{prev.value}` after a response is read as the name of a new rule, which must be "
        f"followed by `when` (found {shown})",
        f"a response is `E`, `E within 5 minutes` or `E eventually`: remove `{prev.value}`, or "
        "start the next rule on a line of its own",
        _span(prev),
    )


_COMPARISONS = dict.fromkeys(("<", "<=", ">", ">=", "=", "<>", "==", "!="), True)


def _measure_as_trigger(tok: Token, prev: Token, after: Token | None) -> Mistake:
    """``when battery < 20 then``: a comparison where the trigger event goes."""
    written, value = tok.value, after.value if after is not None else "..."
    if after is not None and after.value == "=" and tok.value in ("=", "!"):  # `==`, `!=`: two tokens
        written, value = tok.value + "=", "..."
    op = {"=": "=", "==": "=", "!=": "<>"}.get(written, written)
    return Mistake(
        "trigger-condition",
        f"a rule is triggered by an event, named right after `when`; `{prev.value} {written} "
        f"{value}` is a condition, which comes after the event",
        f"write `when SomeEvent and {prev.value} {op} {value} then ...`, with the event that is "
        f"perceived (a reading of `{prev.value}`, say)",
        _span(prev, tok),
    )


def _condition_as_trigger(tok: Token) -> Mistake:
    """``when {m} then``, ``when (E1 or E2) then``: a condition where the event goes."""
    return Mistake(
        "trigger-condition",
        "a rule is triggered by one event, named right after `when`; a condition comes after it",
        "write `when Event and {m} then ...` (one rule per trigger event)",
        _span(tok),
    )


def untimed_otherwise(item: A.ResponseItem) -> tuple[str, str]:
    """What to say of ``item``, an ``otherwise`` after a response without ``within``: the
    message (it names the ``otherwise``) and the fix, with the item's own events."""
    occ = item.occurrence
    fallback = item.otherwise.items[0].occurrence.event if item.otherwise and item.otherwise.items else "C"
    response = f"{'not ' if occ.negated else ''}{occ.event}"
    return (
        f"`otherwise` needs a deadline: `{response}` has none",
        f"write `then {response} within 5 minutes otherwise {fallback}`",
    )


def _operand(tokens: Sequence[Token]) -> str:
    """The operand that ends ``tokens``, as written: a name, a number or ``{m}``."""
    if len(tokens) >= 3 and tokens[-1].value == "}" and tokens[-3].value == "{":
        return "{" + tokens[-2].value + "}"
    return tokens[-1].value if tokens else "..."


def _span(first: Token, last: Token | None = None) -> A.Span:
    """From the start of ``first`` to the end of ``last`` (``first`` itself by default)."""
    end = last or first
    if end.line != first.line:
        end = first
    return A.Span(first.line, first.column, first.line, end.column + max(len(end.value), 1))


__all__ = ["Mistake", "natural_mistake", "untimed_otherwise"]
