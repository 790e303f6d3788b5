"""Generated SLEEC for the tests: Hypothesis strategies for ASTs (round-trip, cross-check),
and random text -- token soup, mutations of real files, the paper notation -- for the
robustness fuzz test and the parser cross-check."""

from __future__ import annotations

import random
import re

from hypothesis import strategies as st

from cosleec.lang import ast as A
from cosleec.lang.parser import CONTEXTUAL_KEYWORDS, KEYWORDS

# `when` is a keyword and `until` a relation keyword: the printer must escape them (`^when`)
EVENTS = ["Start", "Stop", "Alarm", "Help", "when", "until"]
BOOLS = ["flag", "busy"]
NUMS = ["temp"]
SCALE = ("level", ("lo", "mid", "hi"))
CONSTS = ["LIMIT", "ALIAS"]

DEFINITIONS: tuple[A.Definition, ...] = (
    *(A.EventDecl(e) for e in EVENTS),
    *(A.MeasureDecl(b, A.BooleanType()) for b in BOOLS),
    *(A.MeasureDecl(n, A.NumericType()) for n in NUMS),
    A.MeasureDecl(SCALE[0], A.ScaleType(SCALE[1])),
    A.ConstantDecl("LIMIT", 30),
    A.ConstantDecl("ALIAS", "LIMIT"),
)

num_leaf = st.one_of(
    st.integers(-50, 500).map(A.IntLit),
    st.sampled_from(NUMS + CONSTS).map(A.Name),
)
num_expr = st.recursive(
    num_leaf,
    lambda inner: st.builds(A.BinOp, st.sampled_from(["+", "-", "*"]), inner, inner),
    max_leaves=4,
)
rel = st.sampled_from(["<", "<=", ">", ">=", "=", "<>"])
bool_leaf = st.one_of(
    st.sampled_from(BOOLS).map(A.Name),
    st.booleans().map(A.BoolLit),
    st.builds(A.Compare, rel, num_expr, num_expr),
    st.builds(lambda op, lit: A.Compare(op, A.Name(SCALE[0]), A.Name(lit)), rel, st.sampled_from(SCALE[1])),
)
condition = st.recursive(
    bool_leaf,
    lambda inner: st.one_of(
        st.builds(A.Not, inner),
        st.builds(A.BinOp, st.sampled_from(["and", "or"]), inner, inner),
    ),
    max_leaves=6,
)
duration = st.builds(A.Duration, num_expr, st.sampled_from(list(A.TIME_UNITS)))
time_limit = st.one_of(st.builds(A.TimeLimit, duration), st.builds(A.TimeLimit, duration, duration))
occurrence = st.builds(
    A.Occurrence, st.sampled_from(EVENTS), st.booleans(), st.none() | time_limit, st.booleans()
)


def _response(inner: st.SearchStrategy[A.Response]) -> st.SearchStrategy[A.Response]:
    item = st.builds(A.ResponseItem, occurrence, st.none() | inner, st.none() | inner)
    defeater = st.builds(A.Defeater, condition, st.none() | inner)
    return st.builds(
        A.Response,
        st.lists(item, min_size=1, max_size=2).map(tuple),
        st.lists(defeater, max_size=3).map(tuple),
    )


simple_response = st.builds(
    A.Response, st.lists(st.builds(A.ResponseItem, occurrence), min_size=1, max_size=2).map(tuple)
)
response = st.recursive(simple_response, _response, max_leaves=5)
trigger = st.builds(A.Trigger, st.sampled_from(EVENTS), st.none() | condition)

relation = st.one_of(
    st.builds(
        A.EventRelation,
        st.sampled_from(["witness", "equal", "mutualExclusive", "happenBefore"]),
        st.sampled_from(EVENTS),
        st.sampled_from(EVENTS),
    ),
    st.builds(
        A.MeasureRelation,
        st.sampled_from(["imply", "iff", "opposite", "mutualExclusive"]),
        condition,
        condition,
    ),
    st.builds(A.MeasureRelation, st.just("invariant"), condition),
    st.builds(
        A.EventMeasureRelation,
        st.sampled_from(["causation", "includes", "forbid"]),
        st.sampled_from(EVENTS),
        condition,
    ),
    st.builds(A.UntilRelation, trigger, condition, st.sampled_from(EVENTS), st.none() | condition),
    st.builds(A.ForRelation, trigger, condition, duration),
)
situation = st.builds(
    A.Situation,
    st.just(""),
    st.sampled_from(["when", "exists"]),
    trigger,
    st.lists(response, max_size=2).map(tuple),
)


@st.composite
def specifications(draw: st.DrawFn) -> A.Specification:
    rules = draw(st.lists(st.builds(A.Rule, st.just(""), trigger, response), min_size=1, max_size=3))
    rules = [A.Rule(f"R{i}", r.trigger, r.response) for i, r in enumerate(rules)]
    concerns = [
        A.Situation(f"c{i}", s.kind, s.trigger, s.responses)
        for i, s in enumerate(draw(st.lists(situation, max_size=2)))
    ]
    purposes = [
        A.Situation(f"p{i}", s.kind, s.trigger, s.responses)
        for i, s in enumerate(draw(st.lists(situation, max_size=2)))
    ]
    # priorities among the drawn rules: repeats, self-pairs and cycles too (the checker's
    # business, not the printer's or the parser's)
    names = st.sampled_from([r.name for r in rules])
    priorities = draw(st.lists(st.builds(A.Priority, names, names), max_size=4))
    return A.Specification(
        DEFINITIONS,
        tuple(rules),
        tuple(concerns),
        tuple(purposes),
        tuple(draw(st.lists(relation, max_size=3))),
        tuple(priorities),
    )


# ---------------------------------------------------------------------------- random text

# every keyword the grammar has, plus names, numbers, punctuation and junk
TOKENS = [
    *sorted(KEYWORDS | CONTEXTUAL_KEYWORDS),
    "R1",
    "E",
    "F",
    "a",
    "b",
    "x",
    "low",
    "high",
    "0",
    "5",
    "-3",
    "2.5",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "=",
    "->",
    "<",
    ">",
    "<=",
    ">=",
    "<>",
    "+",
    "-",
    "*",
    "/",
    "//",
    "/*",
    "*/",
    "^",
    "^when",
    "^E",
    "é",
    "\\rtf",
    "\ufeff",
    "WHEN",
    "THEN",
    "UNLESS",
    "IN",
    "WHICH",
    "CASE",
]


def token_soup(rng: random.Random, size: int = 40) -> str:
    """Up to ``size`` random tokens separated by spaces or newlines."""
    return "".join(rng.choice(TOKENS) + rng.choice(" \n") for _ in range(rng.randint(0, size)))


def mutate(rng: random.Random, text: str) -> str:
    """One to four random edits of ``text``: deletions, duplications, insertions, cuts."""
    for _ in range(rng.randint(1, 4)):
        if not text:
            break
        i, j = sorted(rng.randrange(len(text) + 1) for _ in range(2))
        op = rng.randrange(5)
        if op == 0:
            text = text[:i] + text[j:]  # delete a span
        elif op == 1:
            text = text[:i] + text[i:j] + text[i:]  # duplicate a span
        elif op == 2:
            text = text[:i] + " " + rng.choice(TOKENS) + " " + text[i:]  # insert a token
        elif op == 3:
            text = text[:i]  # truncate
        else:
            text = text[:i] + chr(rng.randrange(1, 0x250)) + text[i:]  # a stray character
    return text


def mutate_words(rng: random.Random, text: str) -> str:
    """One small edit of one word of ``text`` (replace it by a token, drop it, swap it with
    the next), so that most results are still almost valid: keywords end up as names, names
    as keywords, and marks go missing."""
    words = re.split(r"(\s+)", text)
    spots = [i for i, w in enumerate(words) if w and not w.isspace()]
    if not spots:
        return text
    i = rng.choice(spots)
    op = rng.randrange(4)
    if op <= 1:
        words[i] = rng.choice(TOKENS)
    elif op == 2:
        words[i] = ""
    elif i + 2 < len(words):
        words[i], words[i + 2] = words[i + 2], words[i]
    return "".join(words)


PAPER_EVENTS = ["Start", "Stop", "Alarm", "Help", "^when", "until"]


def _case(rng: random.Random, word: str) -> str:
    return rng.choice((word, word.upper(), word.capitalize()))


def _paper_condition(rng: random.Random, depth: int = 0) -> str:
    k = rng.randrange(6 if depth < 2 else 3)
    if k == 0:
        return rng.choice([*BOOLS, "userDistressed", "true", "FALSE"])
    if k == 1:
        return f"{rng.choice(NUMS)} {rng.choice(['<', '<=', '>', '>=', '=', '<>'])} {rng.randint(-5, 90)}"
    if k == 2:
        return f"{{{rng.choice(BOOLS)}}}"
    if k == 3:
        return f"{_case(rng, 'not')} {_paper_condition(rng, depth + 1)}"
    if k == 4:
        op = _case(rng, rng.choice(["and", "or"]))
        return f"{_paper_condition(rng, depth + 1)} {op} {_paper_condition(rng, depth + 1)}"
    return f"({_paper_condition(rng, depth + 1)})"


def _paper_response(rng: random.Random) -> str:
    items = []
    for _ in range(rng.randint(1, 3)):
        item = ("NOT " if rng.random() < 0.2 else "") + rng.choice(PAPER_EVENTS)
        if rng.random() < 0.4:
            item += f" {_case(rng, 'within')} {rng.randint(0, 60)} {rng.choice([*A.TIME_UNITS, 'minute'])}"
        items.append(item)
    text = f" {_case(rng, 'and')} ".join(items)
    return f"({text})" if len(items) > 1 or rng.random() < 0.2 else text


def paper_text(rng: random.Random) -> str:
    """A few rules in the CO-SLEEC paper's notation (grammar/paper.lark), keywords in any case."""
    rules = []
    for i in range(rng.randint(1, 3)):
        name = rng.choice(["", f"R{i}: ", f"Rule{i} "])
        rule = f"{name}{_case(rng, 'when')} {rng.choice(PAPER_EVENTS)}"
        if rng.random() < 0.3:
            rule += f" {_case(rng, 'and')} {_paper_condition(rng)}"
        rule += f" {_case(rng, 'then')} {_paper_response(rng)}"
        for _ in range(rng.randint(0, 3)):
            rule += f"\n  {_case(rng, 'unless')} {_paper_condition(rng)}"
            if rng.random() < 0.7:
                rule += f" {_case(rng, 'in which case')} {_paper_response(rng)}"
        rules.append(rule)
    return "\n".join(rules) + rng.choice(["", "\n", " // the end\n", "\n/* done */"])
