"""Walks over the AST, for passes that need one kind of node at a time (declaration inference,
the analysis's witnesses and coverage checks)."""

from __future__ import annotations

from collections.abc import Iterator

from cosleec.lang import ast as A


def responses(resp: A.Response) -> Iterator[A.Response]:
    """The response and every response nested in it (otherwise, else, hedge clauses)."""
    yield resp
    for item in resp.items:
        if item.otherwise is not None:
            yield from responses(item.otherwise)
        if item.alternative is not None:
            yield from responses(item.alternative)
    for d in resp.defeaters:
        if d.response is not None:
            yield from responses(d.response)


def occurrences(resp: A.Response) -> Iterator[A.Occurrence]:
    """Every occurrence in the response and the responses nested in it."""
    for r in responses(resp):
        for item in r.items:
            yield item.occurrence


def durations(resp: A.Response) -> Iterator[A.Duration]:
    """Every deadline in the response and the responses nested in it (interval starts first)."""
    for occ in occurrences(resp):
        if occ.limit is not None:
            if occ.limit.lo is not None:
                yield occ.limit.lo
            yield occ.limit.hi


def response_conditions(resp: A.Response) -> Iterator[A.Expr]:
    """The condition of every hedge clause in the response and the responses nested in it."""
    for r in responses(resp):
        for d in r.defeaters:
            yield d.condition


def situations(spec: A.Specification) -> Iterator[A.Situation]:
    """Every concern and purpose, each followed by its ``meanwhile`` chain."""
    for s in (*spec.concerns, *spec.purposes):
        cur: A.Situation | None = s
        while cur is not None:
            yield cur
            cur = cur.meanwhile


def triggers(spec: A.Specification) -> Iterator[A.Trigger]:
    """Every trigger: of the rules, of the situations, of ``until``/``for`` relations."""
    for r in spec.rules:
        yield r.trigger
    for s in situations(spec):
        yield s.trigger
    for rel in spec.relations:
        if isinstance(rel, A.UntilRelation | A.ForRelation):
            yield rel.trigger


def all_responses(spec: A.Specification) -> Iterator[A.Response]:
    """Every top-level response: of the rules, then of the situations."""
    for r in spec.rules:
        yield r.response
    for s in situations(spec):
        yield from s.responses


def conditions(spec: A.Specification) -> Iterator[A.Expr]:
    """Every boolean condition: triggers, hedge clauses, situations and relations."""
    for t in triggers(spec):
        if t.condition is not None:
            yield t.condition
    for resp in all_responses(spec):
        yield from response_conditions(resp)
    for rel in spec.relations:
        if isinstance(rel, A.MeasureRelation):
            yield rel.first
            if rel.second is not None:
                yield rel.second
        elif isinstance(rel, A.EventMeasureRelation):
            yield rel.condition
        elif isinstance(rel, A.UntilRelation):
            yield rel.condition
            if rel.until_condition is not None:
                yield rel.until_condition
        elif isinstance(rel, A.ForRelation):
            yield rel.condition


def all_durations(spec: A.Specification) -> Iterator[A.Duration]:
    """Every deadline of the responses, then of ``for`` relations."""
    for resp in all_responses(spec):
        yield from durations(resp)
    for rel in spec.relations:
        if isinstance(rel, A.ForRelation):
            yield rel.duration


def event_references(spec: A.Specification) -> Iterator[tuple[str, A.Span]]:
    """Every place an event is named, with its span."""
    for t in triggers(spec):
        yield t.event, t.span
    for resp in all_responses(spec):
        for occ in occurrences(resp):
            yield occ.event, occ.span
    for rel in spec.relations:
        if isinstance(rel, A.EventRelation):
            yield rel.first, rel.span
            yield rel.second, rel.span
        elif isinstance(rel, A.EventMeasureRelation):
            yield rel.event, rel.span
        elif isinstance(rel, A.UntilRelation):
            yield rel.until_event, rel.span


def names(e: A.Expr | None) -> Iterator[A.Name]:
    """Every name an expression mentions (measures, constants, scale literals), in order.

    Without recursion: a generated ``a and b and ...`` of 50,000 terms is as deep, and
    nested generators would take time quadratic in it (issue 28)."""
    todo = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, A.Name):
            yield x
        elif isinstance(x, A.Not):
            todo.append(x.operand)
        elif isinstance(x, A.BinOp | A.Compare):
            todo += (x.right, x.left)  # the left first


def terms(e: A.BinOp) -> Iterator[A.Expr]:
    """The terms of the chain of ``e.op`` that ``e`` heads, left to right, without recursion:
    ``a and b and c``, ``(a and b) and c`` and ``a and (b and c)`` alike give a, b, c. For
    reading a chain of ``and`` or ``or`` as one n-ary operator however long it is."""
    todo: list[A.Expr] = [e]
    while todo:
        x = todo.pop()
        if isinstance(x, A.BinOp) and x.op == e.op:
            todo += (x.right, x.left)
        else:
            yield x


def rule_expressions(rule: A.Rule) -> Iterator[A.Expr]:
    """What a rule reads: its trigger condition, its clauses' conditions, its deadlines."""
    if rule.trigger.condition is not None:
        yield rule.trigger.condition
    yield from response_conditions(rule.response)
    for d in durations(rule.response):
        yield d.value
